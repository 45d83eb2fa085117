"""Fast deterministic stand-ins for ``solver.solve``, importable by worker processes
(the process pool and Dask workers import this module by name; tests/ is on sys.path).

fake_solve: a 6-point curve whose numbers follow from the design alone
    (angle_deg = 0.1 L (exp(p / 500) - 1) with p = 0 .. 400 t Pa), status "complete";
    T_mm = 2 returns a "failed" curve, T_mm = 3 raises RuntimeError.
slow_fake_solve: the same after FAKE_SLEEP_S seconds (interrupt and kill tests).
blocking_fake_solve: fake_solve, except that L_mm = 6.1 touches the file named by
    BALLOON_FAKE_MARKER and then never returns (a deterministic Ctrl-C test).
pid_sleeping_solve: writes the worker's pid to a file in the directory BALLOON_FAKE_PIDS,
    then sleeps 120 s (a kill -9 of the job while its workers solve).
"""

from __future__ import annotations

import os
import time

import numpy as np

from solver.curve import Curve

FAKE_SLEEP_S = float(os.environ.get("BALLOON_FAKE_SLEEP_S", "0.6"))


def fake_curve(design, status: str = "complete", reason: str = "fake: max angle") -> Curve:
    p = np.linspace(0.0, 400.0 * design.t_mm, 6)
    angle = 0.1 * design.L_mm * (np.exp(p / 500.0) - 1.0)
    n = len(p)
    return Curve(pressure_pa=p, volume_ul=p / 100.0, time_s=p / 250.0, angle_deg=angle,
                 tip_displacement_mm=np.c_[-angle / 100.0, angle / 10.0],
                 max_membrane_stretch=1.0 + p / 1e4, force_mn=np.full(n, np.nan),
                 newton_iterations=np.arange(n), residual_norm=np.full(n, 1e-10),
                 negative_eigenvalues=np.full(n, -1), status=status, reason=reason,
                 n_dofs=123, wall_time_s=0.01, timings_s={"assembly": 0.005})


def fake_solve(design, settings) -> Curve:
    if design.T_mm == 2.0:
        return fake_curve(design, "failed", "fake: Newton did not converge")
    if design.T_mm == 3.0:
        raise RuntimeError("fake: the solver blew up")
    return fake_curve(design)


def slow_fake_solve(design, settings) -> Curve:
    time.sleep(FAKE_SLEEP_S)
    return fake_solve(design, settings)


def always_ok_solve(design, settings) -> Curve:
    return fake_curve(design)


def blocking_fake_solve(design, settings) -> Curve:
    if design.L_mm == 6.1:
        from pathlib import Path

        Path(os.environ["BALLOON_FAKE_MARKER"]).touch()
        while True:  # until the job stops this worker
            time.sleep(1.0)
    return fake_solve(design, settings)


def pid_sleeping_solve(design, settings) -> Curve:
    from pathlib import Path

    (Path(os.environ["BALLOON_FAKE_PIDS"]) / str(os.getpid())).touch()
    time.sleep(120.0)
    return fake_curve(design)
