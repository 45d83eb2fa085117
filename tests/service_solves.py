"""Picklable fake solve functions for the service tests. They run in spawned worker
processes, which import this module: keep it light (numpy and the domain types)."""

from __future__ import annotations

import os
import time

import numpy as np

from solver.curve import Curve
from solver.errors import InputError


def make_curve(n: int = 5, status: str = "complete", reason: str = "") -> Curve:
    """A synthetic curve of n points (0..n-1 kPa, 10 degrees per kPa)."""
    p = np.linspace(0.0, 1000.0 * (n - 1), n)
    return Curve(pressure_pa=p, volume_ul=p / 1000, time_s=p / 2500, angle_deg=p / 100,
                 tip_displacement_mm=np.zeros((n, 2)), max_membrane_stretch=1 + p / 1e4,
                 force_mn=np.full(n, np.nan), newton_iterations=np.full(n, 3, dtype=np.int64),
                 residual_norm=np.full(n, 1e-10), negative_eigenvalues=np.full(n, -1),
                 status=status, reason=reason, n_dofs=10, wall_time_s=0.1)


def fast_solve(design, settings, on_step=None):
    """Three steps, instantly."""
    for step in range(1, 4):
        if on_step:
            on_step({"step": step, "pressure_pa": np.float64(100.0 * step),
                     "volume_ul": 0.25 * step, "angle_deg": 1.0 * step,
                     "newton_iterations": 4})
    return make_curve(4)


def landing_solve(design, settings, on_step=None):
    """A solve whose last converged step overshoots the 90-deg stop (92 deg at 2920 Pa)
    and is replaced by its landing, as the real solver's is (solver/landing.py): the
    stored curve ends at 90 deg, 2900 Pa."""
    for step, (p, a) in enumerate(((1000.0, 10.0), (2000.0, 40.0), (2920.0, 92.0)), 1):
        if on_step:
            on_step({"step": step, "pressure_pa": p, "volume_ul": p / 1000, "angle_deg": a,
                     "newton_iterations": 4})
    curve = make_curve(4)
    curve.pressure_pa[-1], curve.angle_deg[-1] = 2900.0, 90.0
    curve.angle_deg[1:3] = (10.0, 40.0)
    return curve


def slow_solve(design, settings, on_step=None):
    """One step, then sleeps 60 s (to be cancelled or timed out)."""
    if on_step:
        on_step({"step": 1, "pressure_pa": 50.0, "volume_ul": 0.05, "angle_deg": 0.5,
                 "newton_iterations": 3})
    time.sleep(60)
    return make_curve(2)


def failing_solve(design, settings, on_step=None):
    raise InputError("t_mm", "refused by the fake solver", "anything else")


def crashing_solve(design, settings, on_step=None):
    os._exit(3)
