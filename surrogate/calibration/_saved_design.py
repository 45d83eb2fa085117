"""A saved calibration against a design-space baseline (the emulator): the lab's actuators,
as the baseline at the design changed by the physical effects the calibration selected.

    model = load_model("lab1", models_dir, design_space=lambda: emulator)
    model.predict(design, pressures_pa)        # chamber pressure, Pa -> angle, deg
    model.predict_volume(design, volumes_ul)   # injected volume, ul -> angle, deg
    model.inverse(design, angles_deg)          # angle, deg -> chamber pressure, Pa

What is applied: the design stage's effects (membrane thickness, the layers' stiffness,
the chamber length): they are what the lab's process makes, so they hold for any design of
the calibrated material pairs. What is recorded and named in every answer, not applied:
gauge and camera effects (the lab's instruments), time effects (creep, relaxation, a leak,
a drifting gauge: the protocol) and line effects (air in the line: the rig). Answers are
the actuator's, at chamber pressure, as every Predictor's are.

Band: the baseline's at the changed design, each side widened in quadrature by every
applied parameter's own uncertainty (its sd from the calibration), propagated by a finite
difference (the answer at value + sd, or value - sd where that leaves the box).

File (``<models_dir>/<name>.json``): ``{"format": DESIGN_FORMAT, "name", "baseline",
"pairs": [[body, membrane], ...], "applied": {effect id: {parameter: {value, sd, unit}}},
"recorded": {effect id: {parameter: {value, sd, unit}}}, "rmse_deg", "domain": {L_mm,
t_mm, pressure_pa}, "provenance", "content_sha256"}`` (the seal: ``_saved.py``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from datetime import UTC, datetime
from typing import Any

import numpy as np

from solver.design_space import recognise
from solver.errors import InputError
from surrogate.calibration.effects import EFFECTS
from surrogate.predictor import one_signed

DESIGN_FORMAT = "balloon.calibrated-design-model/1"
CALIBRATED_W_MM = 3.0     # measured data carry no width: the paper's, the loader's default
# on every answer of a model whose file has no content checksum (saved by earlier versions)
UNSEALED_FLAG = "saved_without_checksum"

# the answer's arrays with a band (value, lower, upper), per call: each is widened
BANDS = {"predict": (("angle_deg", "lower_deg", "upper_deg"),
                     ("force_mn", "force_lower_mn", "force_upper_mn")),
         "predict_volume": (("angle_deg", "lower_deg", "upper_deg"),
                            ("force_mn", "force_lower_mn", "force_upper_mn")),
         "inverse": (("pressure_pa", "lower_pa", "upper_pa"),
                     ("volume_ul", "volume_lower_ul", "volume_upper_ul"))}


def design_document(cal: Any, name: str) -> dict[str, Any]:
    """The file's content for a calibration ``cal`` against a design-space baseline."""
    r, obs = cal.report, cal.obs
    params = r["fitted"]["effects"]
    applied: dict[str, dict] = {}
    recorded: dict[str, dict] = {}
    for effect_id in r["selected_effects"]:
        effect = EFFECTS[effect_id]
        table = applied if effect.stage == "design" else recorded
        table[effect_id] = {p.name: {k: params[p.name][k] for k in ("value", "sd", "unit")}
                            for p in effect.parameters}
    designs = [obs.curve_design(c) for c in range(obs.n_curves)]
    # by preset, as ``changed`` asks: a lab's pdms_1_10*1.3 body is a pdms_1_10 actuator
    pairs = sorted({(_preset(d.body_material)[0], _preset(d.membrane_material)[0])
                    for d in (obs.design(c) for c in range(obs.n_curves))})

    def span(name: str) -> list[float]:
        values = [float(d[name]) for d in designs]
        return [min(values), max(values)]

    return {
        "format": DESIGN_FORMAT, "name": name, "baseline": cal.baseline.name,
        "pairs": [list(p) for p in pairs], "applied": applied, "recorded": recorded,
        "rmse_deg": r["rmse_after_deg"],
        "domain": {**{n: span(n) for n in ("L_mm", "t_mm", "T_mm", "b_mm", "h_mm")},
                   "W_mm": [CALIBRATED_W_MM, CALIBRATED_W_MM],
                   "pressure_pa": [float(obs.pressure_pa.min()),
                                   float(obs.pressure_pa.max())]},
        "provenance": {"data_sha256": obs.sha256, "base_model": r["model"].get("name"),
                       "baseline_provenance": _plain(getattr(cal.baseline.predictor,
                                                             "provenance", {})),
                       "selected_effects": r["selected_effects"],
                       "rmse_model_deg": r["rmse_model_deg"],
                       "rmse_before_deg": r["rmse_before_deg"],
                       "rmse_after_deg": r["rmse_after_deg"],
                       "noise_floor_deg": r["noise_floor_deg"],
                       "residual_structured_after": r["residual_structured_after"],
                       "created_utc": datetime.now(UTC).isoformat(timespec="seconds")}}


def _plain(provenance: dict) -> dict:
    """The baseline's provenance, its text and numbers only (no local paths)."""
    keep = ("created_utc", "package_version", "git_commit", "n_records", "format_version")
    return {k: provenance[k] for k in keep if isinstance(provenance.get(k), str | int | float)}


@dataclass(frozen=True)
class DesignSpaceCalibratedModel:
    """A saved calibration against a design-space baseline (module docstring). The
    baseline is resolved on first use (``design_space``): the service's loaded emulator."""

    name: str
    baseline_name: str
    pairs: tuple[tuple[str, str], ...]
    applied: dict[str, dict]
    recorded: dict[str, dict]
    rmse_deg: float
    domain: dict
    provenance: dict
    design_space: Callable[[], Any]
    sealed: bool = True     # False: a file saved before the checksum (UNSEALED_FLAG)

    # ---- the three answers -------------------------------------------------------------
    def predict(self, design, pressures_pa, level: float = 0.95):
        return self._answer("predict", design, pressures_pa, level)

    def predict_volume(self, design, volumes_ul, level: float = 0.95, band: bool = True):
        return self._answer("predict_volume", design, volumes_ul, level)

    def inverse(self, design, angles_deg, level: float = 0.95):
        return self._answer("inverse", design, angles_deg, level)

    # ---- how ------------------------------------------------------------------------------
    def changed(self, design, shifted: str | None = None, sign: float = 1.0):
        """``design`` as the lab makes it: every applied effect's ``design`` transform at
        its value (``shifted``: that parameter at value + sign x sd)."""
        pair = (_preset(design.body_material)[0], _preset(design.membrane_material)[0])
        if pair not in self.pairs:
            raise InputError("body_material", f"the calibrated model {self.name!r} knows the "
                             f"lab's {'/'.join(pair)} actuators only as calibrated on other "
                             "materials", "the calibrated pairs: "
                             + ", ".join("/".join(p) for p in self.pairs))
        out = design
        for effect_id, params in self.applied.items():
            (pname, p), = params.items()
            value = p["value"] + (sign * p["sd"] if pname == shifted else 0.0)
            out = EFFECTS[effect_id].design(out, value)
        return out

    def _answer(self, call: str, design, xs, level: float):
        baseline = self.design_space()
        try:
            base = getattr(baseline, call)(self.changed(design), xs, level=level)
        except InputError as exc:
            raise InputError(exc.field, f"the design as the lab makes it ({self._changes()}): "
                             f"{exc.detail}", exc.allowed) from None
        bands = [b for b in BANDS[call] if getattr(base, b[0], None) is not None
                 and getattr(base, b[1], None) is not None]
        spread = {b[0]: np.zeros(np.shape(getattr(base, b[0]))) for b in bands}
        left_out = []
        for params in self.applied.values():
            (pname, p), = params.items()
            if not p["sd"] or not math.isfinite(p["sd"]):
                continue
            moved = None
            for sign in (1.0, -1.0):
                try:
                    moved = getattr(baseline, call)(self.changed(design, pname, sign), xs,
                                                    level=level)
                    break
                except InputError:
                    continue
            if moved is None:
                left_out.append(pname)
                continue
            for main, _, _ in bands:
                if getattr(moved, main, None) is None:
                    continue
                d = np.asarray(getattr(moved, main), float) - np.asarray(getattr(base, main),
                                                                          float)
                spread[main] += np.where(np.isfinite(d), d, 0.0) ** 2
        widened = {}
        for main, lo_name, hi_name in bands:
            m = np.asarray(getattr(base, main), float)
            lo = m - np.asarray(getattr(base, lo_name), float)
            hi = np.asarray(getattr(base, hi_name), float) - m
            lower, upper = m - np.sqrt(lo**2 + spread[main]), m + np.sqrt(hi**2 + spread[main])
            # an answer of one sign keeps it (the angle and force of a design that bends
            # one way, a pressure, a volume): its band too
            finite = m[np.isfinite(m)]
            if finite.size and (np.all(finite >= 0) or np.all(finite <= 0)):
                _, lower, upper = one_signed(m, lower, upper,
                                             1.0 if np.all(finite >= 0) else -1.0)
            widened[lo_name], widened[hi_name] = lower, upper
        validity = self._validity(base.validity, design, left_out)
        return replace(base, design=design, validity=validity, model=self.name, **widened)

    def _changes(self) -> str:
        words = [f"{pname} {p['value']:+.4g} +/- {p['sd']:.2g} {p['unit']}"
                 if p["unit"] != "-" else f"{pname} x {p['value']:.4g} +/- {p['sd']:.2g}"
                 for params in self.applied.values() for pname, p in params.items()]
        return ", ".join(words) or "the nominal design: no physical effect selected"

    def _validity(self, base: dict, design, left_out: list[str]) -> dict:
        flags = list(base.get("flags", []))
        messages = list(base.get("messages", []))
        if not self.sealed:
            flags.append(UNSEALED_FLAG)
            messages.append(unsealed_message(self.name))
        messages.append(f"calibrated model {self.name!r} (against {self.baseline_name!r}): "
                        f"the design as the lab makes it, {self._changes()}"
                        + ("; the band includes these sizes' own uncertainty" if self.applied
                           else "")
                        + (f" except {', '.join(left_out)}'s (its design +- sd leaves the "
                           "box)" if left_out else ""))
        if self.recorded:
            messages.append("not applied, the lab's instruments and protocol (fix or "
                            "correct them there): " + "; ".join(
                                f"{eid} " + ", ".join(
                                    f"{n} = {p['value']:.4g}"
                                    + (f" {p['unit']}" if p["unit"] != "-" else "")
                                    for n, p in params.items())
                                for eid, params in self.recorded.items()))
        for effect_id, layer in (("body_stiffness", "body_material"),
                                 ("membrane_stiffness", "membrane_material")):
            asked = getattr(design, layer)
            scale = _preset(asked)[1]
            if effect_id in self.applied and scale != 1.0:
                (pname, p), = self.applied[effect_id].items()
                messages.append(f"{layer} {asked.id!r} is scaled already: the lab's {pname} "
                                f"x {p['value']:.4g} multiplies it (x "
                                f"{scale * p['value']:.4g} of the preset in all)")
        for name in ("L_mm", "t_mm", "T_mm", "b_mm", "h_mm", "W_mm"):
            if name not in self.domain:       # T, b, h, W: files of the first version
                continue
            lo, hi = self.domain[name]
            value = getattr(design, name)
            if not lo * (1 - 1e-9) - 1e-12 <= value <= hi * (1 + 1e-9) + 1e-12:
                flags.append(f"{name}_outside_calibration")
                messages.append(f"{name} = {value:g} mm is outside the calibrated "
                                f"{lo:g}..{hi:g} mm: the effects are carried over")
        return {**base, "flags": flags, "messages": messages}


def unsealed_message(name: str) -> str:
    """What every answer of a saved model whose file carries no checksum says: it is
    answered as before, an edit to it would not be noticed, and how to have it sealed."""
    return (f"saved model {name!r} carries no checksum (saved by an earlier version): an "
            "edit to its file would go unnoticed; to have it checked, calibrate its data "
            "again and save it under a new name (the data's sha256 is its "
            "provenance.data_sha256)")


def _preset(material) -> tuple[str, float]:
    """(preset id, stiffness scale) of a layer's material (``recognise``); an inline
    material that is no scaled preset keeps its own id (no calibrated pair has it)."""
    return recognise(material) or (material.id, 1.0)


def checked_design_document(doc: dict, name: str, bad: Callable[[str], Exception],
                            design_space: Callable[[], Any] | None, sealed: bool = True
                            ) -> DesignSpaceCalibratedModel:
    """The model of a parsed DESIGN_FORMAT file, every key and type checked (``bad`` makes
    the error), so that a damaged file fails here and never inside a prediction;
    ``sealed``: whether the file carried its checksum (checked by the caller)."""
    def finite(v: object) -> bool:
        return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)

    for key, kind in (("name", str), ("baseline", str), ("pairs", list), ("applied", dict),
                      ("recorded", dict), ("domain", dict), ("provenance", dict)):
        if not isinstance(doc.get(key), kind):
            raise bad(f"{key!r} is missing or not a {kind.__name__}")
    pairs = doc["pairs"]
    if not pairs or not all(isinstance(p, list) and len(p) == 2
                            and all(isinstance(x, str) for x in p) for p in pairs):
        raise bad("'pairs' is not a list of [body, membrane]")
    for table in ("applied", "recorded"):
        for effect_id, params in doc[table].items():
            effect = EFFECTS.get(effect_id)
            if effect is None or (table == "applied") != (effect.stage == "design"):
                raise bad(f"{table}.{effect_id} is not a catalogued effect of this kind")
            names = {p.name for p in effect.parameters}
            if not isinstance(params, dict) or set(params) != names:
                raise bad(f"{table}.{effect_id} does not hold {sorted(names)}")
            for pname, p in params.items():
                if not (isinstance(p, dict) and finite(p.get("value"))
                        and (p.get("sd") is None or finite(p.get("sd")))
                        and isinstance(p.get("unit"), str)):
                    raise bad(f"{table}.{effect_id}.{pname} is not {{value, sd, unit}}")
                lo, hi = next(q.fit_bounds for q in effect.parameters if q.name == pname)
                if not lo <= p["value"] <= hi or (p.get("sd") or 0.0) < 0:
                    raise bad(f"{table}.{effect_id}.{pname} = {p['value']!r} is outside what "
                              f"a calibration fits ({lo:g}..{hi:g})")
    for key in ("L_mm", "t_mm", "pressure_pa", "T_mm", "b_mm", "h_mm", "W_mm"):
        pair = doc["domain"].get(key)
        if pair is None and key in ("T_mm", "b_mm", "h_mm", "W_mm"):
            continue
        if not (isinstance(pair, list) and len(pair) == 2 and all(map(finite, pair))):
            raise bad(f"domain.{key} is missing or not [low, high]")
    rmse = doc.get("rmse_deg")
    if rmse is not None and not finite(rmse):
        raise bad("'rmse_deg' is not a finite number (or null)")
    if design_space is None:
        raise bad(f"it was calibrated against {doc['baseline']!r}, which is not loaded here")
    applied = {eid: {n: {"value": float(p["value"]),
                         "sd": float(p["sd"]) if p.get("sd") is not None else 0.0,
                         "unit": p["unit"]} for n, p in params.items()}
               for eid, params in doc["applied"].items()}
    return DesignSpaceCalibratedModel(
        doc["name"], doc["baseline"], tuple(tuple(p) for p in pairs), applied,
        doc["recorded"], float(rmse) if rmse is not None else math.nan, doc["domain"],
        doc["provenance"], design_space, sealed)
