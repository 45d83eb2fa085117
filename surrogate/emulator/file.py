"""Emulator files: versioned JSON, written atomically, validated on load.

    save_emulator(emulator, "service/data/emulator.json")
    emulator = load_emulator("service/data/emulator.json")

The file holds each pair's training inputs and outputs and the GP hyperparameters (the
factorisations are recomputed on load, in milliseconds), the band scales, the FE range
data and the fit report. The angle and force nodes are stored and checked, so a file
made with other nodes is refused rather than misread.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np

from solver.atomic_file import write_text_atomic
from surrogate.emulator.emulator import Emulator, PairEmulator
from surrogate.emulator.features import ANGLE_NODES_DEG, FORCE_PRESSURE_NODES_PA
from surrogate.emulator.vector_gp import vector_gp_from_dict
from surrogate.errors import SurrogateFileError

FORMAT_NAME = "balloon-emulator"
FORMAT_VERSION = 1


def _plain(value: object) -> object:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.ndarray):
        return _plain(value.tolist())
    if isinstance(value, (np.floating, np.integer)):
        return _plain(value.item())
    return value


def emulator_to_dict(e: Emulator) -> dict:
    pairs = []
    for pe in e.pairs.values():
        pairs.append({
            "pair": list(pe.pair), "sign": pe.sign, "band_scale": pe.band_scale,
            "fe_limit_angle_deg": pe.fe_limit_angle_deg, "fe_stop_reason": pe.fe_stop_reason,
            "coordinates": pe.coordinates.tolist(), "keys": list(pe.keys),
            "failed": [[np.asarray(u).tolist(), a, r] for u, a, r in pe.failed],
            "curves": pe.curves.as_dict(),
            "force": None if pe.force is None else pe.force.as_dict(),
            "force_band_scale": pe.force_band_scale, "force_limit_pa": pe.force_limit_pa})
    return _plain({"format": FORMAT_NAME, "format_version": FORMAT_VERSION, "name": e.name,
                   "angle_nodes_deg": ANGLE_NODES_DEG.tolist(),
                   "force_pressure_nodes_pa": FORCE_PRESSURE_NODES_PA.tolist(),
                   "provenance": e.provenance, "report": e.report, "pairs": pairs})


def emulator_from_dict(d: object, origin: str = "<dict>") -> Emulator:
    if not isinstance(d, dict) or d.get("format") != FORMAT_NAME:
        raise SurrogateFileError(origin, f"not an emulator file (format is not "
                                 f"\"{FORMAT_NAME}\")")
    version = d.get("format_version")
    if not isinstance(version, int) or version > FORMAT_VERSION:
        raise SurrogateFileError(origin, f"format version {version!r} is newer than this "
                                 f"code reads ({FORMAT_VERSION}); upgrade balloon-actuator")
    if (d.get("angle_nodes_deg") != ANGLE_NODES_DEG.tolist()
            or d.get("force_pressure_nodes_pa") != FORCE_PRESSURE_NODES_PA.tolist()):
        raise SurrogateFileError(origin, "made with other curve nodes than this code uses; "
                                 "refit it with `balloon fit`")
    try:
        pairs = {}
        for p in d["pairs"]:
            pair = (str(p["pair"][0]), str(p["pair"][1]))
            pairs[pair] = PairEmulator(
                pair=pair, sign=float(p["sign"]), curves=vector_gp_from_dict(p["curves"]),
                band_scale=float(p["band_scale"]),
                fe_limit_angle_deg=float(p["fe_limit_angle_deg"]),
                fe_stop_reason=str(p["fe_stop_reason"]),
                coordinates=np.array(p["coordinates"], float),
                keys=tuple(str(k) for k in p["keys"]),
                force=None if p["force"] is None else vector_gp_from_dict(p["force"]),
                force_band_scale=float(p["force_band_scale"]),
                force_limit_pa=float(p["force_limit_pa"]),
                failed=tuple((np.array(u, float), float(a), str(r)) for u, a, r in p["failed"]))
        return Emulator(name=str(d["name"]), pairs=pairs, provenance=dict(d["provenance"]),
                        report=dict(d.get("report") or {}))
    except (KeyError, TypeError, ValueError, IndexError, np.linalg.LinAlgError) as exc:
        raise SurrogateFileError(origin, f"damaged emulator file ({type(exc).__name__}: "
                                 f"{exc})") from None


def save_emulator(e: Emulator, path: str | os.PathLike) -> Path:
    return write_text_atomic(path, json.dumps(emulator_to_dict(e), separators=(",", ":")))


def load_emulator(path: str | os.PathLike) -> Emulator:
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
        data = json.loads(text)
    except FileNotFoundError:
        raise
    except (OSError, UnicodeDecodeError, json.JSONDecodeError, RecursionError) as exc:
        raise SurrogateFileError(path.name, f"cannot be read ({type(exc).__name__})"
                                 ) from None
    return emulator_from_dict(data, path.name)
