"""Richardson extrapolation of a mesh sequence: observed order and the limit.

For values f_i on meshes of element size h_i (a nested or consistently graded
family), f_i = f* + C h_i^q + higher order. Three levels give the observed order q
(``observed_order``), two the limit f* for a given q (``richardson``). Used by the
mesh-convergence study (benchmarks/mesh_convergence.py) and the slow convergence test.
"""

from __future__ import annotations

import numpy as np


def observed_order(h: np.ndarray, f: np.ndarray) -> float | None:
    """q with f_i = f* + C h_i^q through three (h, f) pairs; None when the three are
    not monotone (outside the asymptotic range)."""
    from scipy.optimize import brentq

    d12, d23 = f[0] - f[1], f[1] - f[2]
    if d12 == 0 or d23 == 0 or np.sign(d12) != np.sign(d23):
        return None
    ratio = d12 / d23

    def g(q: float) -> float:
        return (h[0]**q - h[1]**q) / (h[1]**q - h[2]**q) - ratio

    try:
        return float(brentq(g, 0.05, 12.0))
    except ValueError:
        return None


def richardson(h: np.ndarray, f: np.ndarray, q: float) -> float:
    """f* from the two finest levels for order q."""
    return float(f[-1] - (f[-2] - f[-1]) * h[-1]**q / (h[-2]**q - h[-1]**q))
