"""What a mould's tolerance does to a listed design's answer: the change of its value when
one length is made ``TOLERANCE_MM`` larger, the others kept.

A candidate at 45.0 deg read 46.4 with its t rounded to 0.01 mm, 5x its band (an audit of
the thirty-fifth session): each listed design carries this sensitivity
(``DesignCandidate.change_per_0_01_mm``: deg, or mN for a force target, per 0.01 mm).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from solver.design import Design
from solver.errors import InputError
from surrogate.search.design_target import DesignTarget
from surrogate.search.pump_targets import ask

#: the length step of the sensitivity, mm (a mould's usual tolerance)
TOLERANCE_MM = 0.01
#: the lengths a mould sets, mm
MOULD_LENGTHS = ("L_mm", "t_mm", "T_mm", "b_mm", "h_mm")


def change_per_tolerance(model: object, design: Design, target: DesignTarget, at: float,
                         level: float) -> dict[str, float] | None:
    """The value at ``at`` (the pressure, Pa, or for a pump's target the injected
    volume, ul; signed angle, deg, or force, mN) changed by making
    each length TOLERANCE_MM larger, the others kept (central differences; one-sided at
    the box's faces). None where the model has no number there."""
    def value(d: Design) -> float:
        try:
            p = ask(model, d, target, [at], level)
        except InputError:
            return float("nan")
        if target.kind == "force_at_pressure":
            return float(p.force_mn[0]) if p.force_mn is not None else float("nan")
        return float(p.angle_deg[0])

    here = value(design)            # asked once: only a one-sided difference needs it
    out = {}
    for name in MOULD_LENGTHS:
        x = getattr(design, name)
        # the body length and chamber position by the solver's rule, as the search's own
        up, down = (value(replace(design, body_length_mm=None, chamber_offset_mm=None,
                                  **{name: x + s * TOLERANCE_MM}).validated())
                    for s in (1, -1))
        slope = ((up - down) / 2 if np.isfinite(up) and np.isfinite(down) else
                 up - here if np.isfinite(up) else here - down)
        if not np.isfinite(slope):
            return None
        out[name] = float(slope)
    return out
