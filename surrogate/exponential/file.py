"""Surrogate files: versioned JSON.

    {"format": "balloon-surrogate", "format_version": 3, "name", "form", "provenance"
     (database path and metadata, record keys, package version, git commit, date),
     "families": [Family.as_dict()...], "report": {...the fit report...}}

Format versions: 3 adds to a fitted family its pressure-volume relation (``"volume"``,
surrogate/exponential/volume_relation.py; null when the data held no volumes); a file of
version 2 or 1 has none and answers by pressure only. 2 stores each parameter covariance
in the fit coordinates (``covariance_names``: log10 b_t in place of b_t); 1 stored it in
b_t (1/mm) and is still read (converted on load, same bands). Writes are atomic
(temporary file + rename): a failed save leaves the old file intact. A file of a newer
format version than this code reads is refused with SurrogateFileError, and so is one whose content
changed since it was written (``content_sha256``, surrogate/file_seal.py) or whose
values do not give a finite answer at the centre of each family (checked on load).
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np

from solver.atomic_file import write_text_atomic
from solver.design import Design
from solver.errors import BalloonError, NotFoundError
from solver.store.integrity import HDF5_HEAD_BYTES, looks_like_hdf5
from surrogate.errors import SurrogateFileError
from surrogate.exponential import equations
from surrogate.exponential.family import family_from_dict
from surrogate.exponential.surrogate import Surrogate
from surrogate.file_seal import check_header, check_seal, seal
from surrogate.json_plain import plain_json
from surrogate.model_file import read_model_file

FORMAT_NAME = "balloon-surrogate"
FORMAT_VERSION = 3  # 3: families may carry "volume"; 2: covariances in log10 b_t


def surrogate_to_dict(s: Surrogate) -> dict:
    return seal({"format": FORMAT_NAME, "format_version": FORMAT_VERSION, "name": s.name,
                 "form": s.form, "provenance": plain_json(s.provenance),
                 "families": [plain_json(f.as_dict()) for f in s.family_fits],
                 "report": plain_json(s.report)})


def surrogate_from_dict(d: dict, origin: str = "<dict>") -> Surrogate:
    version = check_header(d, FORMAT_NAME, FORMAT_VERSION, "a surrogate", origin)
    check_seal(d, origin)
    try:
        families = tuple(family_from_dict(f, version) for f in d["families"])
        if not families:
            raise ValueError("no families")
        s = Surrogate(name=str(d["name"]), family_fits=families,
                      provenance=dict(d.get("provenance", {})), form=d.get("form"),
                      report=dict(d.get("report", {})))
    except (KeyError, TypeError, ValueError, AttributeError, IndexError) as exc:
        raise SurrogateFileError(origin, f"malformed surrogate file ({exc!r})") from None
    for fam in families:
        _check_family(s, fam, origin)
    return s


def _check_family(s: Surrogate, fam, origin: str) -> None:
    """Every form of the family answers with finite numbers at the centre of its own
    domain, forward and inverse, and its domain is a real range: a damaged value that
    still parses (a string, a list, a negative scatter, 1e308) fails here, at loading,
    not inside a request."""
    dom = fam.domain
    try:
        numbers = [*dom.L_mm, *dom.t_mm, dom.pressure_max_pa, dom.angle_max_deg,
                   fam.T_mm, fam.b_mm, fam.h_mm]
        if not all(isinstance(x, float | int) and math.isfinite(x) for x in numbers):
            raise ValueError("a domain or design number is not finite")
        if not (dom.L_mm[0] <= dom.L_mm[1] and dom.t_mm[0] <= dom.t_mm[1]
                and dom.pressure_max_pa > 0 and dom.angle_max_deg > 0):
            raise ValueError("the domain is not a range")
        if fam.default_form not in fam.parameters:
            raise ValueError(f"default_form {fam.default_form!r} is not fitted")
        design = Design(L_mm=sum(dom.L_mm) / 2, t_mm=sum(dom.t_mm) / 2,
                        body_material=fam.body_material,
                        membrane_material=fam.membrane_material,
                        T_mm=fam.T_mm, b_mm=fam.b_mm, h_mm=fam.h_mm)
        for form, par in fam.parameters.items():
            if form != par.form or par.names != equations.PARAMETER_NAMES.get(form):
                raise ValueError(f"{form}: parameter names {list(par.names)} are not "
                                 f"those of the form")
            if not (par.residual_sd >= 0 and par.residual_rel >= 0 and par.band_scale > 0
                    and np.isfinite(np.asarray(par.covariance, float)).all()):
                raise ValueError(f"{form}: scatter, band scale or covariance out of range")
            pred = s.predict(design, [0.0, dom.pressure_max_pa / 10], form=form)
            values = [pred.angle_deg, pred.lower_deg, pred.upper_deg]
            if pred.force_mn is not None:
                values += [pred.force_mn, pred.force_lower_mn, pred.force_upper_mn]
            if not all(np.isfinite(np.asarray(v, float)).all() for v in values):
                raise ValueError(f"{form}: no finite answer at its family's centre")
            if fam.volume is not None:
                by_v = s.predict_volume(design, [0.0, 0.5 * fam.volume.volume_curve_ul(
                    design.L_mm, design.t_mm)[-1]], form=form)
                if not np.isfinite(np.asarray([by_v.angle_deg, by_v.lower_deg,
                                               by_v.upper_deg], float)).all():
                    raise ValueError(f"{form}: no finite answer by volume at its centre")
    except SurrogateFileError:
        raise
    except (BalloonError, ArithmeticError, KeyError, TypeError, ValueError, AttributeError,
            IndexError) as exc:
        raise SurrogateFileError(origin, f"malformed surrogate file (family {fam.label}: "
                                 f"{exc})") from None


def save_surrogate(s: Surrogate, path: str | os.PathLike) -> Path:
    """Write ``s`` as JSON to ``path`` atomically; returns the path."""
    text = json.dumps(surrogate_to_dict(s), indent=1, allow_nan=False)
    return write_text_atomic(path, text)


def load_surrogate(path: str | os.PathLike) -> Surrogate:
    """Read a surrogate file; NotFoundError when missing, SurrogateFileError when unusable."""
    path = Path(path)
    if not path.is_file():
        raise NotFoundError(f"surrogate file {path} does not exist (make one with "
                            "`balloon fit --db DB -o FILE`, or use the model `paper`)")
    raw = read_model_file(path)
    try:  # ValueError: JSONDecodeError, UnicodeDecodeError, an integer of > 4300 digits
        data = json.loads(raw.decode("utf-8"))
    except (ValueError, RecursionError) as exc:
        if looks_like_hdf5(raw[:HDF5_HEAD_BYTES]):   # `--model curves.h5`: said, not decoded
            raise SurrogateFileError(str(path), "this is an HDF5 file (a curve database?), "
                                     "not a model file (a model is a JSON file, or a name)"
                                     ) from None
        raise SurrogateFileError(str(path), f"not valid JSON ({exc})") from None
    return surrogate_from_dict(data, str(path))


def open_surrogate(spec: str | os.PathLike) -> Surrogate:
    """``"paper"`` for the paper preset, else a surrogate file path."""
    if str(spec) == "paper":
        from surrogate.exponential.paper_preset import paper_surrogate

        return paper_surrogate()
    return load_surrogate(spec)
