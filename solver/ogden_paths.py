"""The incompressible Ogden material along the homogeneous test paths, and its stability.

A path is parametrised by the stretch l along axis 1 with principal stretches
(l, l^k, l^-(1+k)) (volume kept): uniaxial k = -1/2, planar (pure shear) k = 0,
equibiaxial k = 1. Along it solver.materials' W_iso = sum_p mu_p / alpha_p
(l1^a + l2^a + l3^a - 3) has

    dW/dl   = sum_p mu_p (l^(a-1) + k l^(ka-1) - (1+k) l^(-(1+k)a-1))       (stress)
    d2W/dl2 = sum_p mu_p ((a-1) l^(a-2) + k (ka-1) l^(ka-2)
                          + (1+k) ((1+k)a+1) l^(-(1+k)a-2))                   (stiffness)

(kPa with mu in kPa). dW/dl on the uniaxial path is the nominal uniaxial stress
sum_p mu_p (l^(a-1) - l^(-a/2-1)); at l = 1 the uniaxial stiffness is 3 mu0.

A material is stable (Drucker's condition on these paths, as finite-element codes check a
fitted Ogden material) where the stiffness is positive: the stress rises with stretch.
A term is stable on its own, at every stretch of every path, when mu_p alpha_p > 0 and
alpha_p >= 1 or alpha_p <= -2 (``terms_each_stable``; checked on these paths for alpha
in 1..60 and -60..-2, 3000 values each); a sum of such terms is then stable too, and
is not checked stretch by stretch (the presets, Ogden's 1972 rubber). A term with
0 < alpha < 1 (its equibiaxial stress peaks near a stretch of 2.5) or -2 < alpha < 0 is
not, and terms of opposite signs that nearly cancel (mu [10, -5], alpha [2, 3.99]: mu0
0.025 kPa, but the stress falls from a stretch of 1.1) are not: the FE then fails at
rest after a long solve.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

PATHS = {"uniaxial": -0.5, "planar": 0.0, "equibiaxial": 1.0}   # k of each path
# The largest principal stretch checked: a membrane ballooned to 90 deg of bending
# (solver.design_space.RECOGNITION_STRETCHES reads the same range).
STABLE_STRETCH_MAX = 4.0
# l from 1/16 to 4, each path's in tension and compression while no stretch passes the
# largest (uniaxial compression to 1/16: lateral stretches of 4)
_STRETCHES = np.geomspace(STABLE_STRETCH_MAX ** -2, STABLE_STRETCH_MAX, 801)


def path_stress_kpa(mu_kpa: Sequence[float], alpha: Sequence[float], stretch: object,
                    k: float) -> np.ndarray:
    """dW/dl (kPa) along the path ``k`` at each ``stretch`` l (module docstring)."""
    lam = np.asarray(stretch, float)
    return sum((m * (lam ** (a - 1.0) + k * lam ** (k * a - 1.0)
                     - (1.0 + k) * lam ** (-(1.0 + k) * a - 1.0))
                for m, a in zip(mu_kpa, alpha)), np.zeros_like(lam))


def path_stiffness_kpa(mu_kpa: Sequence[float], alpha: Sequence[float], stretch: object,
                       k: float) -> np.ndarray:
    """d2W/dl2 (kPa) along the path ``k`` at each ``stretch`` l (module docstring)."""
    lam = np.asarray(stretch, float)
    return sum((m * ((a - 1.0) * lam ** (a - 2.0) + k * (k * a - 1.0) * lam ** (k * a - 2.0)
                     + (1.0 + k) * ((1.0 + k) * a + 1.0) * lam ** (-(1.0 + k) * a - 2.0))
                for m, a in zip(mu_kpa, alpha)), np.zeros_like(lam))


def terms_each_stable(mu_kpa: Sequence[float], alpha: Sequence[float]) -> bool:
    """Whether every term is stable on its own (mu alpha > 0, alpha >= 1 or <= -2): then
    the material is, and ``unstable_at`` need not walk the paths (0.2 ms a material,
    which a scaled material paid on every request and every candidate of a search)."""
    return all(m * a > 0 and (a >= 1.0 or a <= -2.0) for m, a in zip(mu_kpa, alpha))


def unstable_at(mu_kpa: Sequence[float], alpha: Sequence[float]) -> tuple[str, float] | None:
    """(path, stretch) of the first stretch, nearest 1, where the material's stress falls
    with stretch along a path while no principal stretch passes STABLE_STRETCH_MAX; None
    for a stable material (``terms_each_stable`` first, then ``unstable_on_paths``)."""
    return None if terms_each_stable(mu_kpa, alpha) else unstable_on_paths(mu_kpa, alpha)


def unstable_on_paths(mu_kpa: Sequence[float], alpha: Sequence[float]
                      ) -> tuple[str, float] | None:
    """``unstable_at`` found by walking the three paths' stretches, whatever the terms."""
    found: tuple[str, float] | None = None
    for name, k in PATHS.items():
        lam = _STRETCHES
        largest = np.maximum.reduce([lam, lam ** k, lam ** (-(1.0 + k))])
        lam = lam[largest <= STABLE_STRETCH_MAX * (1 + 1e-12)]
        with np.errstate(over="ignore", invalid="ignore"):
            bad = lam[~(path_stiffness_kpa(mu_kpa, alpha, lam, k) > 0.0)]
        if bad.size:
            at = float(bad[np.argmin(np.abs(np.log(bad)))])
            if found is None or abs(np.log(at)) < abs(np.log(found[1])):
                found = (name, at)
    return found
