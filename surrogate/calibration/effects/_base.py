"""What every effect of the catalogue is: parameters with units, a forward transform at
one stage of the model, a plausible range, identifiability conditions and a sentence.

The augmented model, in the order it is evaluated (docs/calibration.md):

    p_chamber = pressure stage (p_gauge, flow, direction)     pressure effects
    design'   = design stage (nominal design)                 physical effects
    static    = baseline.predict(design', p_chamber)          the Predictor
    angle     = time stage (static along each curve's time)   time effects
    observed  = angle stage (angle)                           measurement effects

and by injected volume (the pump's two observables), before the baseline is read:

    V_line    = time stage (V_pump along each curve's time)   a leak
    V_chamber = volume stage (V_line, the baseline's p(V))    line effects

Adding an effect is one file in this package (a subclass with its transform, its
interpretation and how a lab measures it on its own) plus its test;
``effects/__init__.py`` lists the instances.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

STAGES = ("pressure", "volume", "design", "time", "angle")


@dataclass(frozen=True)
class EffectParameter:
    """One parameter. ``fit_bounds`` are hard limits of the optimiser; ``plausible`` the
    range expected for this device; ``null`` the value that switches the effect off."""

    name: str
    unit: str
    null: float
    fit_bounds: tuple[float, float]
    plausible: tuple[float, float]
    start: float
    description: str
    tested: bool = True  # False: a shape parameter, undefined when the effect is off

    def as_dict(self) -> dict[str, object]:
        return {"name": self.name, "unit": self.unit, "null": _finite(self.null),
                "bounds": [_finite(b) for b in self.fit_bounds],
                "plausible": list(self.plausible), "description": self.description}


def _finite(x: float) -> float | None:
    return x if math.isfinite(x) else None


@dataclass(frozen=True)
class DataTraits:
    """What the data allow, for identifiability: see ``surrogate.calibration._history``."""

    has_time: bool
    has_flow: bool
    n_flow_rates: int
    has_unloading: bool
    has_holds: bool
    n_thicknesses_max: int  # most membrane thicknesses in one family
    n_lengths_max: int
    open_parameters: tuple[str, ...]  # what the baseline leaves open ("amplitude", ...)
    #: read as the pump's two observables (bend and gauge against the injected volume)
    by_volume: bool = False

    @property
    def pump_varies(self) -> bool:
        """A hold, the unloading or a second flow rate: what tells a rate or a delay from
        a fixed shift along the curve."""
        return self.has_holds or self.has_unloading or self.n_flow_rates >= 2


class Effect:
    """Base class. Subclasses set the class attributes and implement their stage's
    transform (one of ``chamber_pressure`` with its inverse ``gauge_pressure``,
    ``chamber_volume``, ``design``, ``lag``, ``observed``)."""

    id: str = ""
    title: str = ""
    stage: str = ""
    kind: str = ""  # "physical" | "measurement" | "time"
    parameters: tuple[EffectParameter, ...] = ()
    description: str = ""
    #: how a lab measures this effect on its own (told when the data cannot tell it from
    #: another effect)
    measure_directly: str = ""
    #: open baseline parameters this effect is exactly (then it is not fitted)
    same_as_open: tuple[str, ...] = ()
    #: catalogue effects that together make exactly the readings this effect makes,
    #: whatever the data (the physics says so, not a fit), their sizes from this effect's
    #: by ``exactly_as_params`` and why in ``exactly_as_why``: named beside a selection of
    #: this effect with what tells them apart (``_exact_alike``)
    exactly_as: tuple[str, ...] = ()
    exactly_as_why: str = ""
    #: a time effect's ``lag`` acts on the bend ("angle") or, by injected volume, on the
    #: chamber pressure the gauge reads ("gauge"); or its ``delivered_volume`` on the
    #: volume the pump put in ("volume": a leak)
    lags: str = "angle"

    # ---- identifiability -------------------------------------------------------------
    def not_identifiable(self, data: DataTraits) -> tuple[str, str] | None:
        """None when the data can tell this effect from the baseline's misfit, else
        (reason, what to measure)."""
        for name in self.same_as_open:
            if name in data.open_parameters:
                return (f"exactly a change of the baseline's open {name.replace('_', ' ')}",
                        "use a baseline that fixes it (the emulator, --model emulator)")
        return None

    # ---- transforms (one per stage; the default is the identity) ---------------------
    def chamber_pressure(self, p_pa: np.ndarray, flow_ul_s: np.ndarray,
                         direction: np.ndarray, values: dict[str, float]) -> np.ndarray:
        return p_pa

    def gauge_pressure(self, p_pa: np.ndarray, flow_ul_s: np.ndarray,
                       direction: np.ndarray, values: dict[str, float]) -> np.ndarray:
        """The inverse of ``chamber_pressure``: what the gauge reads for a chamber pressure
        (the pressure-by-volume channel predicts the gauge's reading at the injected
        volume, _volume.py). A pressure effect implements both."""
        return p_pa

    def chamber_volume(self, pump_ul: np.ndarray, v_grid_ul: np.ndarray,
                       p_grid_pa: np.ndarray, design_index: np.ndarray,
                       values: dict[str, float]) -> np.ndarray:
        """The chamber's volume (ul) at each row's pump volume, given the baseline's
        chamber pressure ``p_grid_pa`` (n_designs, volumes; Pa) at chamber volumes
        ``v_grid_ul`` and each row's design (by injected volume only)."""
        return pump_ul

    def design(self, design, value: float):
        return design

    def lag(self, static_deg: np.ndarray, time_s: np.ndarray, valid: np.ndarray,
            values: dict[str, float]) -> np.ndarray:
        """The quasi-static bend (deg; or chamber pressure, Pa, where ``lags`` is "gauge")
        along each curve's time (n_curves, substeps), as the material delays it."""
        return static_deg

    def delivered_volume(self, pump_ul: np.ndarray, time_s: np.ndarray, valid: np.ndarray,
                         pressure_at, values: dict[str, float]) -> np.ndarray:
        """The volume (ul) still in the line and chamber along each curve's time
        (n_curves, instants), given the pump's and ``pressure_at(volume_ul)``, the
        chamber's pressure (Pa) of each curve's design at one volume per curve."""
        return pump_ul

    def observed(self, angle_deg: np.ndarray, values: dict[str, float]) -> np.ndarray:
        return angle_deg

    def exactly_as_params(self, params: dict[str, dict]) -> dict[str, dict]:
        """The sizes of ``exactly_as``'s parameters ({name: {value, sd, unit}}) that make
        the readings this effect makes with ``params``."""
        return {}

    # ---- words ----------------------------------------------------------------------
    def interpret(self, params: dict[str, dict], data: dict) -> str:
        """One or two sentences a lab can act on; ``params`` {name: {value, sd, unit}},
        ``data`` the report's ``data`` (``unloading``, ``holds``, ``has_time_s``, ...)."""
        return self.title + ": " + ", ".join(
            f"{n} = {p['value']:.3g} +/- {p['sd']:.2g} {p['unit']}" for n, p in params.items())

    def as_dict(self) -> dict[str, object]:
        return {"id": self.id, "title": self.title, "kind": self.kind, "stage": self.stage,
                "needs": list(self.needs), "description": self.description,
                "measure_directly": self.measure_directly,
                "parameters": [p.as_dict() for p in self.parameters]}

    needs: tuple[str, ...] = ()  # optional data columns it needs


def needs_volume_channel(data: DataTraits, what: str = "the bend and the gauge"
                         ) -> tuple[str, str] | None:
    """The reason and the measurement an effect that only the injected volume tells (the
    pump's two observables) is not identifiable, or None when the data are read so."""
    if data.by_volume:
        return None
    return (f"needs {what} read against the injected volume (time_s and flow_ul_s, "
            "replicate curves, a baseline that gives the volume)",
            "record time_s and flow_ul_s of every reading, with replicates, and calibrate "
            "against the emulator")


def physical_nodes(p: EffectParameter, n: int,
                   bounds: tuple[float, float] | None = None) -> np.ndarray:
    """Grid of a design-stage parameter's values at which the baseline is tabulated, over
    ``bounds`` (default its fit bounds)."""
    lo, hi = p.fit_bounds if bounds is None else bounds
    if lo > 0 and hi / lo > 2.5:
        return np.geomspace(lo, hi, n)
    return np.linspace(lo, hi, n)
