"""Fakes for the service tests: picklable solve functions (they run in worker
processes) and a tiny in-memory surrogate.

The fake surrogate evaluates the paper's exponential model (Eq. 5-6 with the
printed constants a = 0.101 deg/mm, a_t = 731.2 Pa, b_t = 7.179 /mm, log10 reading)
with a fixed +-1 degree band; the tests use it to check the HTTP plumbing, not physics.
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass, field

import numpy as np

from service.settings import ServiceSettings
from solver.curve import Curve
from solver.errors import InputError
from surrogate import OutOfFamilyError


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


@dataclass
class FakePrediction:
    pressure_pa: np.ndarray
    angle_deg: np.ndarray
    lower_deg: np.ndarray
    upper_deg: np.ndarray
    validity: dict
    model: str = "fake"
    provenance: dict = field(default_factory=lambda: {"source": "tests/service_fakes.py"})


@dataclass
class FakeInverse:
    pressure_pa: np.ndarray
    lower_pa: np.ndarray
    upper_pa: np.ndarray
    validity: dict


class FakeSurrogate:
    """Covers one family: PDMS 1:10 body, Ecoflex 00-30 membrane, T=1, b=1.8, h=0.15."""

    name = "fake"
    provenance = {"source": "tests/service_fakes.py"}
    families = [{"body_material": "pdms_1_10", "membrane_material": "ecoflex_00_30",
                 "T_mm": 1.0, "b_mm": 1.8, "h_mm": 0.15}]

    def _params(self, design):
        if design.family[:2] != ("pdms_1_10", "ecoflex_00_30"):
            raise OutOfFamilyError(f"family {design.family} is not covered: run "
                                   "`balloon precompute` for it")
        return 0.101 * design.L_mm, 731.2 * math.log10(7.179 * design.t_mm)

    def predict(self, design, pressures_pa, level=0.95):
        a, tau = self._params(design)
        p = np.asarray(pressures_pa, float)
        angle = a * np.expm1(p / tau)
        flags = ["pressure_beyond_fe"] if p.max() > 2500 else []
        return FakePrediction(p, angle, angle - 1.0, angle + 1.0,
                              {"in_domain": not flags, "flags": flags, "messages": []})

    def inverse(self, design, angle_deg, level=0.95):
        a, tau = self._params(design)
        angle = np.asarray(angle_deg, float)
        if (angle <= -a).any():
            raise InputError("angle_deg", "not reachable by this design", f"> {-a:.3g}")
        p = tau * np.log1p(angle / a)
        return FakeInverse(p, p - 10.0, p + 10.0, {"in_domain": True, "flags": [],
                                                   "messages": []})


class BrokenSurrogate(FakeSurrogate):
    """Raises an unexpected error: the server must answer 500 without a stack trace."""

    def predict(self, design, pressures_pa, level=0.95):
        raise RuntimeError("secret internal detail")


# -- helpers shared by the service tests ---------------------------------------------------

PROBLEM = "application/problem+json"


def settings_for(tmp_path, **overrides) -> ServiceSettings:
    values = dict(db_path=tmp_path / "curves.h5", surrogate_path=tmp_path / "none.json",
                  models_dir=tmp_path / "models", api_key="test-key", queue_size=2,
                  job_time_limit_s=30)
    values.update(overrides)
    return ServiceSettings(**values)


def assert_problem(response, status: int, field: str | None = None) -> dict:
    """The answer is an RFC 9457 problem with ``status``; ``field`` is in its errors."""
    assert response.status_code == status, response.text
    assert response.headers["content-type"] == PROBLEM
    body = response.json()
    assert body["status"] == status
    assert body["type"].startswith("urn:balloon:problem:")
    assert body["title"] and body["detail"] and body["instance"]
    assert "Traceback" not in response.text
    if field is not None:
        assert field in [e["field"] for e in body["errors"]], body
    return body
