"""Fakes and helpers for the service tests: a tiny in-memory surrogate, the shared
settings and problem assertions; the fake solve functions live in service_solves.py.

The fake surrogate evaluates the paper's exponential model (Eq. 5-6 with the
printed constants a = 0.101 deg/mm, a_t = 731.2 Pa, b_t = 7.179 /mm, log10 reading)
with a fixed +-1 degree band; the tests use it to check the HTTP plumbing, not physics.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from service_solves import (  # noqa: F401 - re-exported for the tests
    crashing_solve,
    failing_solve,
    fast_solve,
    make_curve,
    slow_solve,
)

from service.settings import ServiceSettings
from solver.errors import InputError
from surrogate import OutOfFamilyError


@dataclass
class FakePrediction:
    design: object
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
        return FakePrediction(design, p, angle, angle - 1.0, angle + 1.0,
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
                  emulator_path=tmp_path / "no-emulator.json",
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
