"""The two exact invariances the emulator relies on, checked against the FE itself.

1. Scaling every length by k leaves angle(p) unchanged (no length scale in the
   quasi-static hyperelastic problem; the mesh scales with W, solver/mesh.py).
2. Scaling both layers' Ogden mu by s scales the pressure axis by s.

Small solves (hex1, to 40 degrees), compared at the FE's own points; each check also
shows that a change which is NOT an invariance moves the curve, so the tolerance is not
a free pass.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import PchipInterpolator

from solver import Design, SolverSettings, solve
from solver.design_space import locate, scaled_material

SETTINGS = SolverSettings(element="hex1", max_angle_deg=30.0)
BASE = dict(L_mm=5.0, t_mm=0.6, T_mm=1.0, b_mm=1.6, h_mm=0.2)


@pytest.fixture(scope="module")
def base_curve():
    return solve(Design(**BASE), SETTINGS)


def _angle_at(curve, pressure_pa):
    return PchipInterpolator(curve.pressure_pa, curve.angle_deg)(pressure_pa)


def test_scaling_every_length_leaves_the_curve_unchanged(base_curve):
    k = 2.0
    # the default body length and chamber position scale with W: no need to set them
    scaled = Design(**{n: k * v for n, v in BASE.items()}, W_mm=3.0 * k).validated()
    base = Design(**BASE).validated()
    assert scaled.body_length_mm == pytest.approx(k * base.body_length_mm) == 12.0 * k
    assert scaled.chamber_offset_mm == pytest.approx(k * base.chamber_offset_mm)
    curve = solve(scaled, SETTINGS)
    assert curve.status == base_curve.status == "complete"
    # the same mesh scaled by k: the same curve, read at the scaled solve's own points
    # (Newton's absolute force floor lets the step sequences differ slightly)
    p = curve.pressure_pa
    inside = (p > 0) & (p <= base_curve.pressure_pa[-1])
    gap = np.abs(_angle_at(base_curve, p[inside]) - curve.angle_deg[inside])
    assert gap.max() < 0.02, gap
    v = PchipInterpolator(base_curve.pressure_pa, base_curve.volume_ul)(p[inside])
    np.testing.assert_allclose(curve.volume_ul[inside], k**3 * v, rtol=2e-3)
    # and the box sees the scaled design as the base one
    assert locate(scaled).geometry_mm == pytest.approx(locate(Design(**BASE)).geometry_mm)


def test_scaling_both_moduli_scales_the_pressure_axis(base_curve):
    s = 1.7
    stiffer = Design(**BASE, body_material=scaled_material("pdms_1_10", s),
                     membrane_material=scaled_material("ecoflex_00_30", s))
    curve = solve(stiffer, SETTINGS)
    p = curve.pressure_pa / s
    inside = (p > 0) & (p <= base_curve.pressure_pa[-1])
    gap = np.abs(_angle_at(base_curve, p[inside]) - curve.angle_deg[inside])
    assert gap.max() < 0.1, gap
    # scaling the membrane alone is not an invariance: it must move the curve
    membrane_only = solve(Design(**BASE, membrane_material=scaled_material("ecoflex_00_30", s)),
                          SETTINGS)
    q = membrane_only.pressure_pa / s
    inside = (q > 0) & (q <= base_curve.pressure_pa[-1])
    moved = np.abs(_angle_at(base_curve, q[inside]) - membrane_only.angle_deg[inside])
    assert moved.max() > 1.0
