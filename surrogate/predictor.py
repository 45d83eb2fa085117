"""The one interface every model implements (emulator, exponential, paper, calibrated),
its result types (``Prediction``, ``InversePrediction``) and the check of a request's
list of numbers (``number_array``).

Routes, CLI commands and the calibration loop call only these methods, so they never
branch on a model's kind:

    p = model.predict(design, pressures_pa, level=0.95)   -> Prediction
    q = model.inverse(design, angles_deg, level=0.95)     -> InversePrediction

Contract (what every implementation guarantees):
- angles in degrees (signed: negative when the actuator bends towards the membrane,
  as the reversed pair does), pressures in Pa (chamber pressure), force in mN;
- ``lower_deg``/``upper_deg`` a band at ``level`` (two-sided, for a new FE solve of the
  design, not only the model's mean);
- no number the physics does not support: a pressure past the end of the FE's
  converged, stable range for the design gets angle NaN (null over HTTP), and the
  prediction's ``validity`` says so (flag ``past_fe_range``, ``fe_limit_pa`` and why
  the FE stopped);
- a design the model cannot answer for raises ``InputError`` naming the field and the
  allowed range (``OutOfFamilyError`` / ``OutOfBoxError`` carry the nearest design).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from solver.design import Design
from solver.errors import InputError
from solver.settings import SolverSettings

MAX_POINTS = 10_000_000  # the most numbers one call of a predictor takes (a guard)
# The most values one question asks, in one list: an HTTP request's pressures_pa,
# volumes_ul, times_s or angles_deg (the schemas' max_length) and the CLI's --pressures,
# --volumes, --times or --angles-deg alike. The CLI took up to MAX_POINTS (100,000
# pressures answered in 6 s, a 16 MB --json) where HTTP refused 1001.
MAX_ASKED_VALUES = 1000

# The smallest normal double (2.2e-308): a magnitude below it is subnormal, held to fewer
# significant digits than any answer states (1e-310 Pa was answered 7.27e-314 deg, and 5e-324
# ul 6.1e-322 Pa, one significant bit), and is no measurable pressure, volume, time or angle.
SMALLEST_NORMAL = float(np.finfo(float).tiny)


def normal_or_zero(values: object) -> np.ndarray:
    """A float array with every subnormal magnitude (below SMALLEST_NORMAL) and -0.0 read
    as 0.0: what an asked pressure, volume, time or angle is taken as, and what an answer
    states (``finite_list``); NaN and infinity are kept."""
    a = np.array(values, float)
    a[np.abs(a) < SMALLEST_NORMAL] = 0.0
    return a


def number_array(values: object, field_name: str, unit: str) -> np.ndarray:
    """A request's list of numbers as a 1-D float array; InputError naming the field."""
    try:
        a = np.atleast_1d(np.asarray(values, dtype=float))
    except (TypeError, ValueError):
        raise InputError(field_name, f"not a list of numbers: {values!r}") from None
    if a.ndim != 1 or a.size == 0 or a.size > MAX_POINTS:
        raise InputError(field_name, f"{a.size} values with shape {a.shape}",
                         f"1 to {MAX_POINTS} numbers ({unit})")
    if not np.isfinite(a).all():
        raise InputError(field_name, "values must be finite", f"finite numbers ({unit})")
    return a


def band_within_fe(lower: np.ndarray, upper: np.ndarray, limit_deg: float,
                   validity: dict) -> tuple[np.ndarray, np.ndarray]:
    """A band (deg; NaN stays NaN) cut at the FE range's largest angle magnitude
    ``limit_deg``, and said in ``validity`` (flag ``band_capped_at_fe_range``) where it
    was: an answer inside the range whose band reaches past it (105.6 deg against an FE
    limit of 97.3) would state angles the FE never gave. Every model's answer goes
    through it: the exponential model's, the emulator's by pressure and by volume (89.0
    deg against 84.8 by volume before), its balance-model answer (at the FE's angle stop)
    and a saved calibrated model's angle +- z RMSE."""
    lo, hi = np.asarray(lower, float), np.asarray(upper, float)
    cut = (np.abs(lo) > limit_deg * (1 + 1e-9)) | (np.abs(hi) > limit_deg * (1 + 1e-9))
    if cut.any():
        validity["flags"].append("band_capped_at_fe_range")
        validity["messages"].append(
            f"{int(cut.sum())} band(s) cut at {limit_deg:.1f} deg, the largest angle of the "
            "FE's range here: the FE gives no angle beyond it")
    return np.clip(lo, -limit_deg, limit_deg), np.clip(hi, -limit_deg, limit_deg)


FE_PRESSURE_STOP_PA = SolverSettings().max_pressure_pa   # the default FE's last pressure
#: the default FE's volume stop (whole actuator, ul), where the database's curves end at
#: the latest: no design is answered past it
FE_VOLUME_STOP_UL = SolverSettings().max_volume_ul


def pressure_stop_reason(end_pa: float) -> str:
    """Why an FE range ends at the FE's pressure stop (FE_PRESSURE_STOP_PA) rather than at
    ``end_pa`` (Pa), where the model's curves would end: every model says it alike."""
    return (f"the FE's pressure stop ({FE_PRESSURE_STOP_PA:g} Pa, "
            "SolverSettings.max_pressure_pa), reached before the end the model gives "
            f"({end_pa:.0f} Pa)")


# Flags about some of the asked points, not about the design: they never make
# ``validity["in_domain"]`` false, which says whether the design itself is inside the
# model's domain (the emulator's box, the exponential model's fitted family ranges).
POINT_FLAGS = frozenset({
    "past_fe_range", "pressure_beyond_fe", "angle_beyond_fe", "band_capped_at_fe_range",
    "force_band_too_wide", "force_past_fe_range", "past_pressure_maximum",
    "past_fe_pressure_stop", "pressure_outside_calibration", "force_at_free_tip_pressure"})


# Flags about the model's file, not about the design: a saved calibrated model written
# before files carried their checksum.
FILE_FLAGS = frozenset({"saved_without_checksum"})
NOT_ABOUT_THE_DESIGN = POINT_FLAGS | FILE_FLAGS


def design_in_domain(validity: dict) -> bool:
    """Whether the design is inside the model's domain: the model says so, or its only
    flags are about asked points (POINT_FLAGS: past the FE's range, a band cut there, a
    force withheld, ...) or about the model's file (FILE_FLAGS), which keep their own
    flags."""
    flags = set(validity.get("flags", ()))
    return bool(validity.get("in_domain", False)) or not flags - NOT_ABOUT_THE_DESIGN


def one_signed(values: np.ndarray, lower: np.ndarray, upper: np.ndarray, sign: float
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """An answer (angle in deg, or force in mN) and its band for a design whose direction
    the physics fixes (``sign`` +1: it bends away from the membrane, -1: towards it; the
    angle and the blocked tip's force cannot change sign along its curve): nothing past
    zero on the other side -- the lower end floored at 0 for +1, the upper capped at 0
    for -1 -- and no -0.0. NaN stays NaN."""
    values, lower, upper = (np.asarray(a, float) for a in (values, lower, upper))
    if sign > 0:
        values, lower, upper = (np.maximum(a, 0.0) for a in (values, lower, upper))
    else:
        values, lower, upper = (np.minimum(a, 0.0) for a in (values, lower, upper))
    return values + 0.0, lower + 0.0, upper + 0.0      # -0.0 + 0.0 is 0.0


@dataclass(frozen=True)
class Prediction:
    """Angles (deg) at ``pressure_pa`` (Pa) with a band at ``level`` (lower_deg, upper_deg);
    force_mn (mN) and its band when the model has force, else None; volume_ul (injected
    volume, ul) when the model has it. NaN where the answer is past the FE's range."""

    design: Design
    pressure_pa: np.ndarray
    angle_deg: np.ndarray
    lower_deg: np.ndarray
    upper_deg: np.ndarray
    level: float
    validity: dict
    model: str
    form: str
    provenance: dict
    parameters: dict
    force_mn: np.ndarray | None = None
    force_lower_mn: np.ndarray | None = None
    force_upper_mn: np.ndarray | None = None
    volume_ul: np.ndarray | None = None

    def as_dict(self) -> dict[str, object]:
        def lst(a: np.ndarray | None) -> list | None:
            return None if a is None else np.asarray(a).tolist()

        return {"design": self.design.as_dict(), "pressure_pa": lst(self.pressure_pa),
                "angle_deg": lst(self.angle_deg), "lower_deg": lst(self.lower_deg),
                "upper_deg": lst(self.upper_deg), "level": self.level,
                "force_mn": lst(self.force_mn), "force_lower_mn": lst(self.force_lower_mn),
                "force_upper_mn": lst(self.force_upper_mn), "volume_ul": lst(self.volume_ul),
                "validity": dict(self.validity),
                "model": self.model, "form": self.form, "parameters": dict(self.parameters),
                "provenance": dict(self.provenance)}


@dataclass(frozen=True)
class InversePrediction:
    """Pressures (Pa) that give ``angle_deg`` (deg), with a band at ``level``; arrays have
    the length of the requested angles."""

    design: Design
    angle_deg: np.ndarray
    pressure_pa: np.ndarray
    lower_pa: np.ndarray
    upper_pa: np.ndarray
    level: float
    validity: dict
    model: str
    form: str
    provenance: dict
    volume_ul: np.ndarray | None = None        # injected volume for each angle, ul
    volume_lower_ul: np.ndarray | None = None  # its band's lower edge, ul
    volume_upper_ul: np.ndarray | None = None  # its band's upper edge, ul

    def as_dict(self) -> dict[str, object]:
        def opt(a: np.ndarray | None) -> list[float] | None:
            return None if a is None else np.asarray(a, float).tolist()

        return {"design": self.design.as_dict(), "angle_deg": self.angle_deg.tolist(),
                "pressure_pa": self.pressure_pa.tolist(), "lower_pa": self.lower_pa.tolist(),
                "upper_pa": self.upper_pa.tolist(), "volume_ul": opt(self.volume_ul),
                "volume_lower_ul": opt(self.volume_lower_ul),
                "volume_upper_ul": opt(self.volume_upper_ul), "level": self.level,
                "validity": dict(self.validity), "model": self.model, "form": self.form,
                "provenance": dict(self.provenance)}


@runtime_checkable
class Predictor(Protocol):
    """A model that answers angle(pressure) and pressure(angle) for a design."""

    name: str

    def predict(self, design: Design, pressures_pa: object, level: float = 0.95
                ) -> Prediction:
        """Angle (deg) at each pressure (Pa >= 0), with a band at ``level``."""
        ...

    def inverse(self, design: Design, angle_deg: object, level: float = 0.95
                ) -> InversePrediction:
        """Chamber pressure (Pa) giving each angle (deg), with a band at ``level``."""
        ...
