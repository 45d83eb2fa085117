"""Where a design's FE curve may end in a Newton failure: the membrane's stretch.

The default FE fails (Newton diverging after every cut-back) on a share of the box's
designs before 90 deg, most of them PDMS-bodied, at membrane stretches of 7.3-10 (the
largest principal stretch at any membrane quadrature point, ``Curve.max_membrane_stretch``:
a corner value at the membrane's bonded edge on the default mesh, not a rupture stretch,
docs/physics.md). The range model (``PairEmulator.range_model``) foresees such an end only
where database curves nearby ended early; on random designs away from them, 20 of the 104
early-ended FE curves of ten random-design sets were answered past their FE end (15 of
them PDMS-bodied). Among every default-FE free-tip curve of the PDMS-bodied group (shipped
database and those sets), 96 % of the Newton-failed ones had passed a stretch of 7 before
they failed (median 15 deg before), against 30 % of the complete ones (benchmarks/RESULTS.md,
fortieth session).

``StretchHazard`` emulates the stretch along a design's curve: a GP over the box of
log(stretch - 1) at STRETCH_NODES_DEG, fitted on the group's complete curves (left out
by design groups of five folds, its relative error 1-2.5 % on the PDMS-bodied group). Where
a design's emulated stretch passes HAZARD_STRETCH, an answer at a larger angle carries the
flag ``high_membrane_stretch``, with the share of the group's database curves that
reached that stretch and then ended in a Newton failure before 90 deg. It is a flag, not a
cut: most curves that pass that stretch run on to 90 deg.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from surrogate.emulator.vector_gp import (
    MEANS_ONLY,
    VectorGP,
    fit_output_gps,
    vector_gp_from_dict,
)

STRETCH_NODES_DEG = np.array([5.0, 15.0, 30.0, 45.0, 60.0, 75.0, 90.0])
# The stretch from which answers are flagged. On the PDMS-bodied group (shipped database
# and ten random-design sets): 96 % of the Newton-failed curves passed it before failing,
# 30 % of the complete ones pass it (7.7 % of their angle range); at 7.5: 89 % and 21 %;
# at 6.5: 99 % and 37 %.
HAZARD_STRETCH = 7.0
FLAG = "high_membrane_stretch"


def stretch_nodes(angle_deg: np.ndarray, stretch: np.ndarray) -> np.ndarray:
    """log(stretch - 1) of one FE curve at STRETCH_NODES_DEG (|angle| on its rising part;
    NaN past its last angle)."""
    a = np.abs(np.asarray(angle_deg, float))
    s = np.asarray(stretch, float)
    rising = np.concatenate(([True], np.diff(a) > 0))
    a, s = a[rising], s[rising]
    out = np.log(np.maximum(np.interp(STRETCH_NODES_DEG, a, s), 1.0 + 1e-6) - 1.0)
    out[STRETCH_NODES_DEG > a[-1] + 1e-9] = np.nan
    return out


def reached_hazard(stretch: np.ndarray) -> bool:
    """Whether an FE curve's membrane stretch reached HAZARD_STRETCH."""
    s = np.asarray(stretch, float)
    return bool(s.size and np.nanmax(s) >= HAZARD_STRETCH)


@dataclass(frozen=True)
class StretchHazard:
    """The emulated membrane stretch of a group's designs, and how often its FE curves
    failed past HAZARD_STRETCH.

    model     GP of log(stretch - 1) at STRETCH_NODES_DEG over the unit box
    reached   database curves of the group whose FE stretch reached HAZARD_STRETCH
    failed    of those, the ones that ended in a Newton failure before 90 deg
    """

    model: VectorGP
    reached: int
    failed: int

    def onset_deg(self, u: np.ndarray) -> float:
        """The angle (deg, unsigned) at which the emulated stretch (mean) of the design at
        unit coordinates ``u`` reaches HAZARD_STRETCH; inf where it stays below to 90 deg."""
        mean, _ = self.model.predict(np.asarray(u, float), MEANS_ONLY)
        stretch = 1.0 + np.exp(mean)
        above = np.flatnonzero(stretch >= HAZARD_STRETCH)
        if not above.size:
            return float("inf")
        k = int(above[0])
        if k == 0:
            return float(STRETCH_NODES_DEG[0])
        s0, s1 = stretch[k - 1], stretch[k]
        a0, a1 = STRETCH_NODES_DEG[k - 1], STRETCH_NODES_DEG[k]
        return float(a0 + (a1 - a0) * (HAZARD_STRETCH - s0) / (s1 - s0))

    def message(self, onset_deg: float, onset_pa: float, answered: int, group: str) -> str:
        """The flag's sentence for ``answered`` points at or above ``onset_deg``
        (unsigned; chamber pressure ``onset_pa`` there) of a design of ``group``
        (body/membrane, as ``solver.design_space.GROUPS`` names it)."""
        share = (f"{self.failed} of the {self.reached} FE curves of the database's "
                 f"{group} designs that reached it ended in a Newton failure before 90 deg"
                 if self.reached else f"no FE curve of the database's {group} designs "
                 "reached it")
        return (f"{answered} answered point(s) lie at or above {onset_deg:.0f} deg "
                f"({onset_pa:.0f} Pa), where this design's emulated membrane stretch passes "
                f"{HAZARD_STRETCH:g} (the largest stretch at the membrane's bonded edge on "
                f"the FE's mesh); {share}: this design's FE curve may end before these "
                "points; an FE solve (POST /v1/solve) tells where it ends")

    def as_dict(self) -> dict:
        return {"model": self.model.as_dict(), "reached": self.reached,
                "failed": self.failed, "nodes_deg": STRETCH_NODES_DEG.tolist(),
                "hazard_stretch": HAZARD_STRETCH}


def fit_stretch_hazard(u: np.ndarray, nodes: np.ndarray, reached: int, failed: int,
                       min_designs: int, seed: int = 0) -> StretchHazard | None:
    """The hazard model of a group from its complete curves' unit coordinates ``u`` (n, 6)
    and ``stretch_nodes`` (n, len(STRETCH_NODES_DEG)); None with fewer than
    ``min_designs`` curves that reach every node."""
    u, nodes = np.asarray(u, float), np.asarray(nodes, float)
    ok = np.isfinite(nodes).all(axis=1)
    if ok.sum() < min_designs:
        return None
    gp = fit_output_gps(u[ok], nodes[ok], seed=seed, shared=slice(None))
    return StretchHazard(gp, int(reached), int(failed))


def stretch_hazard_from_dict(d: dict | None) -> StretchHazard | None:
    """``StretchHazard.as_dict`` read back; None for a file without it (format <= 15)."""
    if d is None:
        return None
    if list(d["nodes_deg"]) != STRETCH_NODES_DEG.tolist() or \
            float(d["hazard_stretch"]) != HAZARD_STRETCH:
        raise ValueError("stretch hazard nodes or threshold differ from this code's")
    reached, failed = d["reached"], d["failed"]
    if not (isinstance(reached, int) and isinstance(failed, int) and 0 <= failed <= reached):
        raise ValueError("stretch hazard counts must be integers, 0 <= failed <= reached")
    model = vector_gp_from_dict(d["model"])
    if model.gps[0].x.shape[1] != 6 or len(model.center) != len(STRETCH_NODES_DEG):
        raise ValueError("stretch hazard model of the wrong shape")
    return StretchHazard(model, reached, failed)
