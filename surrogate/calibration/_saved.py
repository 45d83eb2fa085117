"""Saved augmented models: ``save_model`` / ``load_model`` and ``CalibratedModel``.

A calibration against a design-space baseline (the emulator) is saved and answered by
``_saved_design.py`` (``DesignSpaceCalibratedModel``); this module's format is that of a
calibration against a per-family model (the exponential and paper models):

A saved model is one JSON file ``<models_dir>/<name>.json`` holding the fitted family
parameters, the selected effects' values and the provenance (data sha256, starting model,
report summary). ``CalibratedModel.predict(design, pressures_pa, level)`` answers like the
surrogate's ``predict``: a quasi-static angle at gauge pressure, with a band of
+/- z(level) x the cross-validated error after calibration.

No number past the FE's range (as every Predictor): the file's ``fe_range`` is where
the baseline of the calibration still answered for the measured designs (its largest
pressure and angle magnitude, found at saving); past it, or past the measured pressures
when a file of older code has no ``fe_range``, the angle is NaN (null over HTTP) with the
flag ``past_fe_range``.

Both formats are sealed as the emulator and exponential files are (surrogate/file_seal.py:
``"content_sha256"``, the sha256 of the rest as canonical JSON; the file itself stays
indented): a file changed after saving -- a digit raised, a value truncated -- is refused
on load with ``SavedModelError``, never answered with other numbers. A file of earlier
versions carries no checksum: it is read as before and every answer is flagged
``saved_without_checksum``, saying how to have it checked. A save killed before it was
published leaves its temporary file (``.lab1.json.k3j9x_2a.tmp``, perhaps empty):
``remove_stale_temporaries``, when the models directory is opened, removes those older
than a minute, never a save in progress.
"""

from __future__ import annotations

import json
import math
import os
import re
import stat
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from statistics import NormalDist
from typing import Any

import numpy as np

from solver.atomic_file import write_text_atomic, write_text_exclusive
from solver.errors import BalloonError, ExistsError, InputError
from surrogate.calibration._errors import ModelNotFoundError
from surrogate.calibration._forward import chamber_pressure_pa, static_angle_deg
from surrogate.calibration._saved_design import (
    DESIGN_FORMAT,
    UNSEALED_FLAG,
    DesignSpaceCalibratedModel,
    checked_design_document,
    design_document,
    unsealed_message,
)
from surrogate.exponential.equations import TAU_FORM
from surrogate.file_seal import KEY as SEAL_KEY
from surrogate.file_seal import seal, seal_broken
from surrogate.model_file import read_model_file
from surrogate.predictor import band_within_fe

FORMAT = "balloon.calibrated-model/1"
# read with fullmatch: ``$`` alone lets a final newline through ('lab1\n' saved a file
# 'lab1\n.json' beside 'lab1.json')
NAME_PATTERN = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,63}")
# the built-in models' names (service/models.py): a saved model of one could never be chosen
RESERVED = ("emulator", "exponential", "fitted", "paper")
# the temporary file solver.atomic_file writes a model through (mkstemp's 8 characters)
TEMPORARY = re.compile(r"\.(" + NAME_PATTERN.pattern + r")\.json\.[a-z0-9_]{8}\.tmp")
STALE_AFTER_S = 60.0    # a save takes milliseconds: one in progress is never this old


class ModelExistsError(ExistsError, InputError):
    """A model of that name is already saved (HTTP 409; the CLI's one line): saving never
    replaces one, and of two concurrent saves of one name exactly one wins."""

    def __init__(self, name: str) -> None:
        InputError.__init__(self, "name", f"a model named {name!r} already exists",
                            "a new name")
        self.name = name


@dataclass(frozen=True)
class CalibratedPrediction:
    """Same fields as the surrogate's Prediction."""

    pressure_pa: np.ndarray
    angle_deg: np.ndarray
    lower_deg: np.ndarray
    upper_deg: np.ndarray
    validity: dict
    model: str
    provenance: dict = field(default_factory=dict)

    def as_dict(self) -> dict[str, Any]:
        return {"pressure_pa": self.pressure_pa.tolist(), "angle_deg": self.angle_deg.tolist(),
                "lower_deg": self.lower_deg.tolist(), "upper_deg": self.upper_deg.tolist(),
                "validity": self.validity, "model": self.model, "provenance": self.provenance}


@dataclass(frozen=True)
class CalibratedModel:
    name: str
    families: tuple[dict, ...]
    effects: dict[str, float]
    rmse_deg: float
    flow_ul_s: float | None
    domain: dict
    provenance: dict
    sealed: bool = True     # False: a file saved before the checksum (UNSEALED_FLAG)

    def _family(self, design) -> dict:
        fam = design.family
        for f in self.families:
            if (f["body_material"], f["membrane_material"], round(f["T_mm"], 6),
                    round(f["b_mm"], 6), round(f["h_mm"], 6)) == fam:
                return f
        raise InputError("design", f"calibrated model {self.name!r} does not cover family "
                         f"{fam}", "families: " + "; ".join(
                             f"{f['body_material']}/{f['membrane_material']} T {f['T_mm']:g}"
                             f" b {f['b_mm']:g} h {f['h_mm']:g}" for f in self.families))

    def predict(self, design, pressures_pa, level: float = 0.95) -> CalibratedPrediction:
        """Quasi-static angle (deg) at gauge pressures (Pa); viscoelastic lag is not applied
        (it vanishes at rest), the inlet drop uses the calibration's flow rate."""
        if not 0.0 < level < 1.0:
            raise InputError("level", f"got {level!r}", "0 < level < 1")
        f = self._family(design)
        p = np.asarray(pressures_pa, dtype=float)
        fam = np.array([f["a_deg_per_mm"], f["a_t_pa"], f["b_t_per_mm"], f.get("c", 0.0)])
        values = dict(self.effects)
        q = self.flow_ul_s if self.flow_ul_s is not None else 0.0
        pc = chamber_pressure_pa(p, np.full_like(p, q), values)
        angle = static_angle_deg(pc, design.L_mm, design.t_mm, fam, values)
        angle = angle + values.get("offset_deg", 0.0)
        half = NormalDist().inv_cdf(0.5 + level / 2.0) * self.rmse_deg
        flags, messages = [], []
        d = self.domain
        for name, value in (("L_mm", design.L_mm), ("t_mm", design.t_mm)):
            lo, hi = d[name]
            if not lo - 1e-9 <= value <= hi + 1e-9:
                flags.append(f"{name}_outside_calibration")
                messages.append(f"{name} = {value:g} is outside the calibrated {lo:g}..{hi:g}")
        if p.size and (p.min() < d["pressure_pa"][0] - 1e-9 or p.max() > d["pressure_pa"][1]):
            flags.append("pressure_outside_calibration")
            messages.append(f"pressures beyond the measured {d['pressure_pa'][0]:.0f}.."
                            f"{d['pressure_pa'][1]:.0f} Pa are extrapolated")
        if "tau_v_s" in values:
            messages.append("viscoelastic lag not applied: the prediction is quasi-static")
        if "R_pa_per_ul_s" in values:
            messages.append(f"inlet pressure drop at the calibration flow {q:g} ul/s")
        lim_p, lim_a, whose = self._fe_limits()
        past = (p > lim_p * (1 + 1e-9)) | (np.abs(angle) > lim_a * (1 + 1e-9))
        if past.any():
            flags.append("past_fe_range")
            messages.append(f"{int(past.sum())} answer(s) past {whose} (up to {lim_p:.0f} Pa"
                            + (f" and {lim_a:.1f} deg" if math.isfinite(lim_a) else "")
                            + "): no number is given there (null)")
        angle = np.where(past, np.nan, angle)
        validity = {"in_domain": not flags, "flags": flags, "messages": messages,
                    "fe_limit_pa": lim_p,
                    "fe_limit_angle_deg": lim_a if math.isfinite(lim_a) else None}
        if not self.sealed:     # about the file, not the design: in_domain as it is
            flags.append(UNSEALED_FLAG)
            messages.append(unsealed_message(self.name))
        lower, upper = angle - half, angle + half
        if math.isfinite(lim_a):
            lower, upper = band_within_fe(lower, upper, lim_a, validity)
        return CalibratedPrediction(p, angle, lower, upper, validity, self.name,
                                    dict(self.provenance))

    def _fe_limits(self) -> tuple[float, float, str]:
        """(pressure Pa, angle magnitude deg, what they are) beyond which no number."""
        fe = self.domain.get("fe_range")
        if fe:
            top = fe.get("angle_deg")
            return (float(fe["pressure_pa"]), math.inf if top is None else float(top),
                    "the FE's range")
        return float(self.domain["pressure_pa"][1]), math.inf, "the measured pressures"

    def family_parameters(self, design) -> dict:
        f = self._family(design)
        return {k: f[k] for k in ("a_deg_per_mm", "a_t_pa", "b_t_per_mm", "c")} | {
            "tau_form": TAU_FORM,
            "effects": dict(self.effects), "residual_sd_deg": self.rmse_deg}


FE_PROBE_PA = np.linspace(0.0, 50_000.0, 501)  # far past any FE curve (MAX_PRESSURE_PA)


def fe_range(cal) -> dict[str, float]:
    """Where the calibration's baseline still gives numbers for the measured designs: its
    largest pressure (Pa) and angle magnitude (deg) over them (every Predictor gives NaN
    past the FE's range). Designs it refuses are skipped; none answering: the measured
    pressures."""
    obs, top_p, top_a = cal.obs, 0.0, 0.0
    seen = set()
    for c in range(obs.n_curves):
        design = obs.design(c)
        if repr(design) in seen:
            continue
        seen.add(repr(design))
        try:
            pred = cal.baseline.predictor.predict(design, FE_PROBE_PA)
        except BalloonError:
            continue
        angle = np.asarray(pred.angle_deg, dtype=float)
        ok = np.isfinite(angle)
        if ok.any():
            top_p = max(top_p, float(FE_PROBE_PA[ok].max()))
            top_a = max(top_a, float(np.abs(angle[ok]).max()))
    if top_p == 0.0:
        return {"pressure_pa": float(np.max(obs.pressure_pa)), "angle_deg": None}
    return {"pressure_pa": top_p, "angle_deg": top_a}


def _check_name(name: str) -> str:
    if (not isinstance(name, str) or not NAME_PATTERN.fullmatch(name) or name in RESERVED
            or name.lower().endswith(".json")):     # saved as "lab1.json.json" before
        raise InputError("name", f"invalid model name {name!r}",
                         "1-64 letters, digits, '_', '.', '-', starting with a letter or "
                         "digit, without .json (the file's ending is added); not "
                         + ", ".join(repr(n) for n in RESERVED))
    return name


def save_model(cal, name: str, models_dir: str | Path, overwrite: bool = False) -> Path:
    """Write the calibrated model (atomically). Refuses to replace an existing model
    unless ``overwrite``."""
    from surrogate.calibration._api import saveable

    _check_name(name)
    saveable(cal)       # what the saved formats can stand for (InputError naming save)
    models_dir = Path(models_dir)
    path = models_dir / f"{name}.json"
    if path.exists() and not overwrite:  # early answer; the create below decides
        raise ModelExistsError(name)
    if "families" not in cal.report["fitted"]:   # a design-space baseline (_saved_design)
        return _write(path, design_document(cal, name), name, overwrite)
    r, obs = cal.report, cal.obs
    effects = dict(cal.after.values)
    flows = r["data"]["flow_rates_ul_s"]
    doc = {
        "format": FORMAT, "name": name,
        "families": [{k: v for k, v in f.items() if k != "tau_law_pinned"}
                     for f in r["fitted"]["families"]],
        "effects": effects,
        "effect_parameters": r["fitted"]["effects"],
        "selected_effects": r["selected_effects"],
        "rmse_deg": r["rmse_after_deg"],
        "flow_ul_s": float(np.median(flows)) if flows else None,
        "domain": {"L_mm": [float(obs.L_mm.min()), float(obs.L_mm.max())],
                   "t_mm": [float(obs.t_mm.min()), float(obs.t_mm.max())],
                   "pressure_pa": [float(obs.pressure_pa.min()),
                                   float(obs.pressure_pa.max())],
                   "fe_range": fe_range(cal)},
        "provenance": {"data_sha256": obs.sha256, "base_model": r["model"].get("name"),
                       "selected_effects": r["selected_effects"],
                       "fitted_values": {k: v["value"] for k, v in r["fitted"]["effects"].items()},
                       "rmse_model_deg": r["rmse_model_deg"],
                       "rmse_before_deg": r["rmse_before_deg"],
                       "rmse_after_deg": r["rmse_after_deg"],
                       "noise_floor_deg": r["noise_floor_deg"],
                       "residual_structured_after": r["residual_structured_after"],
                       "created_utc": datetime.now(UTC).isoformat(timespec="seconds")},
    }
    return _write(path, doc, name, overwrite)


def _write(path: Path, doc: dict, name: str, overwrite: bool) -> Path:
    """Write ``doc`` sealed (its content checksum) as indented JSON at ``path``: atomically
    replacing (``overwrite``), or created atomically so that of two concurrent saves of one
    name exactly one wins. The checksum is of ``doc`` as read back (tuples as lists, keys
    as text), so that loading it finds the same."""
    plain = json.loads(json.dumps(doc, allow_nan=False))
    text = json.dumps(seal(plain), indent=1, allow_nan=False)
    if overwrite:
        write_text_atomic(path, text)
    else:
        try:  # atomic create: of two concurrent saves of one name exactly one wins
            write_text_exclusive(path, text)
        except FileExistsError:
            raise ModelExistsError(name) from None
    return path



class SavedModelError(BalloonError):
    """A saved model file is damaged or not one this code reads (not valid JSON, wrong
    format or version, missing keys, wrong types). Names the model, never the path: a
    server answers 503 with it."""

    def __init__(self, name: str, problem: str) -> None:
        super().__init__(f"the saved model {name!r} cannot be used: {problem}")
        self.name = name
        self.problem = problem


FAMILY_TEXT = ("body_material", "membrane_material")
FAMILY_NUMBERS = ("T_mm", "b_mm", "h_mm", "a_deg_per_mm", "a_t_pa", "b_t_per_mm")


def _finite(value: object) -> bool:
    return (isinstance(value, int | float) and not isinstance(value, bool)
            and math.isfinite(value))


def _checked(doc: object, name: str, design_space: Callable[[], Any] | None = None,
             sealed: bool = True) -> CalibratedModel | DesignSpaceCalibratedModel:
    """The model of a parsed file, every key and type checked (SavedModelError on the
    first problem), so that a damaged file fails here and never inside a prediction;
    ``sealed``: whether the file carried its checksum (``_seal_checked``)."""
    def bad(what: str) -> SavedModelError:
        return SavedModelError(name, what)

    if not isinstance(doc, dict):
        raise bad("the file is not a JSON object")
    fmt = doc.get("format")
    if fmt == DESIGN_FORMAT:
        return checked_design_document(doc, name, bad, design_space, sealed)
    if fmt != FORMAT:
        if isinstance(fmt, str) and fmt.startswith(FORMAT.rsplit("/", 1)[0] + "/"):
            raise bad(f"format {fmt!r} is not {FORMAT!r} (a newer version of "
                      "balloon-actuator wrote it?)")
        raise bad(f"not a calibrated model (format {fmt!r}, expected {FORMAT!r})")
    for key, kind in (("name", str), ("families", list), ("effects", dict),
                      ("domain", dict), ("provenance", dict)):
        if not isinstance(doc.get(key), kind):
            raise bad(f"{key!r} is missing or not a {kind.__name__}")
    if not doc["families"]:
        raise bad("'families' is empty")
    for i, fam in enumerate(doc["families"]):
        if not isinstance(fam, dict):
            raise bad(f"families[{i}] is not an object")
        for key in FAMILY_TEXT:
            if not isinstance(fam.get(key), str):
                raise bad(f"families[{i}].{key} is missing or not text")
        for key in FAMILY_NUMBERS:
            if not _finite(fam.get(key)):
                raise bad(f"families[{i}].{key} is missing or not a finite number")
        if "c" in fam and not _finite(fam["c"]):
            raise bad(f"families[{i}].c is not a finite number")
    for key, value in doc["effects"].items():
        if not _finite(value):
            raise bad(f"effects.{key} is not a finite number")
    for key in ("L_mm", "t_mm", "pressure_pa"):
        pair = doc["domain"].get(key)
        if not (isinstance(pair, list) and len(pair) == 2 and all(map(_finite, pair))):
            raise bad(f"domain.{key} is missing or not [low, high]")
    fe = doc["domain"].get("fe_range")  # absent in files of older code
    if fe is not None and not (isinstance(fe, dict) and _finite(fe.get("pressure_pa"))
                               and (_finite(fe.get("angle_deg")) or fe.get("angle_deg") is None)):
        raise bad("domain.fe_range is not {pressure_pa, angle_deg} (finite numbers)")
    for key in ("rmse_deg", "flow_ul_s"):
        if key not in doc or not (doc[key] is None or _finite(doc[key])):
            raise bad(f"{key!r} is missing or not a finite number (or null)")
    rmse = doc["rmse_deg"]
    return CalibratedModel(doc["name"], tuple(doc["families"]),
                           {k: float(v) for k, v in doc["effects"].items()},
                           float(rmse) if rmse is not None else math.nan, doc["flow_ul_s"],
                           doc["domain"], doc["provenance"], sealed)


def _seal_checked(doc: object, name: str) -> bool:
    """Whether the parsed file carries its content checksum (False: saved by an earlier
    version, read as before and flagged); SavedModelError when it carries one that does
    not match what was read."""
    if not isinstance(doc, dict) or SEAL_KEY not in doc:
        return False
    if not isinstance(doc[SEAL_KEY], str) or seal_broken(doc):
        raise SavedModelError(name, "its content changed since it was saved (the "
                              "content_sha256 checksum does not match): restore the file "
                              "from a copy, or calibrate its data again under a new name")
    return True


def load_model(name: str, models_dir: str | Path,
               design_space: Callable[[], Any] | None = None
               ) -> CalibratedModel | DesignSpaceCalibratedModel:
    """A saved calibrated model by name: ModelNotFoundError when there is none,
    SavedModelError when its file is damaged or malformed. ``design_space`` gives the
    design-space baseline (the emulator) a calibration against it answers through."""
    models_dir = Path(models_dir)
    if not isinstance(name, str) or not NAME_PATTERN.fullmatch(name):
        raise ModelNotFoundError(f"no model {name!r}")
    path = models_dir / f"{name}.json"
    if not path.is_file():
        known = sorted(p.stem for p in models_dir.glob("*.json")) if models_dir.is_dir() else []
        raise ModelNotFoundError(f"no model {name!r} in {models_dir}; known: "
                                 + ", ".join(list(RESERVED) + known))
    try:  # read within the model files' bound: never a huge or endless file read whole
        raw = read_model_file(path)
    except InputError as exc:
        raise SavedModelError(name, exc.detail) from None
    try:  # ValueError: JSONDecodeError, UnicodeDecodeError, an integer of > 4300 digits
        doc = json.loads(raw.decode("utf-8"))
    except (ValueError, RecursionError) as exc:
        raise SavedModelError(name, f"not valid JSON ({type(exc).__name__})") from None
    return _checked(doc, name, design_space, _seal_checked(doc, name))


def remove_stale_temporaries(models_dir: str | Path, older_than_s: float = STALE_AFTER_S
                             ) -> list[str]:
    """Remove from ``models_dir`` the temporary files of saves that never finished (a
    process killed between writing and publishing leaves ``.lab1.json.k3j9x_2a.tmp``,
    perhaps empty, that nothing else removes): only regular files named as a save names
    them (``TEMPORARY``) and last changed more than ``older_than_s`` ago, so a save in
    progress is never touched. The names removed, sorted; a file that cannot be removed
    (read-only directory) is left, as is a missing directory."""
    folder, removed = Path(models_dir), []
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return removed
    now = time.time()
    for entry in entries:
        if not TEMPORARY.fullmatch(entry.name):
            continue
        try:
            info = entry.stat(follow_symlinks=False)
            if stat.S_ISREG(info.st_mode) and now - info.st_mtime > older_than_s:
                os.unlink(folder / entry.name)
                removed.append(entry.name)
        except OSError:     # gone meanwhile, or not ours to remove
            continue
    return sorted(removed)
