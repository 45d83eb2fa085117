"""Emulator files: versioned JSON, written atomically, validated on load.

    save_emulator(emulator, "service/data/emulator.json")
    emulator = load_emulator("service/data/emulator.json")

The file holds each pair's training inputs and outputs and the GP hyperparameters (the
factorisations are recomputed on load: some 600 Cholesky factorisations of n x n, n up to
the largest group's design count), the band scales, the FE range data and the fit report.
The angle and force nodes are stored and checked, so a file made with other nodes is
refused rather than misread.

Loading is the service's start-up cost, paid again by every app a test or a batch job
builds, so ``load_emulator`` keeps the last ``LOAD_CACHE_SIZE`` emulators it built, keyed
by the file's content (its BLAKE2 digest: a changed file is always read afresh; an
Emulator is immutable, so sharing one is safe). The factorisations run with OpenBLAS held
to one thread: numpy's Cholesky of a 370 x 370 matrix took 2.6 ms on one thread and 49 ms
on two while the other core was busy (its threads spin-wait for each other), which made
a load 21 s instead of a few on a shared machine (benchmarks/RESULTS.md, ninth session).
"""

from __future__ import annotations

import functools
import hashlib
import json
import math
import os
import threading
from collections import OrderedDict
from pathlib import Path

import numpy as np
from threadpoolctl import ThreadpoolController

from solver.atomic_file import write_text_atomic
from solver.design_space import SAMPLED
from surrogate.emulator.balance import BalanceModel, balance_model_from_dict
from surrogate.emulator.blocked_range import blocked_range_from_dict
from surrogate.emulator.curve_gps import CurveGPs
from surrogate.emulator.early_ended_nodes import EarlyEndedRows
from surrogate.emulator.emulator import Emulator
from surrogate.emulator.features import ANGLE_NODES_DEG, FORCE_PRESSURE_NODES_PA, N_NODES
from surrogate.emulator.force_gps import force_gps_from_dict
from surrogate.emulator.pair_emulator import FORCE_FORMS, PairEmulator
from surrogate.emulator.shape_gps import (
    TOP_PRESSURE_FROM,
    TOP_SHAPE_NODES_DEG,
    VOLUME_SHAPE_NODES_DEG,
    ShapeGPs,
    shape_gps_from_dict,
    shape_scaling,
)
from surrogate.emulator.stretch_hazard import stretch_hazard_from_dict
from surrogate.emulator.variance_nodes import FORMAT_7_NODES
from surrogate.emulator.vector_gp import MEANS_ONLY, vector_gp_from_dict
from surrogate.errors import SurrogateFileError
from surrogate.file_seal import canonical_text, check_header, check_seal, seal
from surrogate.json_plain import plain_json
from surrogate.model_file import read_model_file

FORMAT_NAME = "balloon-emulator"
FORMAT_VERSION = 18  # 18: turn_band_scales, a balance model's band multipliers for a
                     # curve that turns back (balance.py; 17 read: none, the plain ones);
                     # 17: force_band_factor, the force band's half-widths' multiplier
                     # from FE curves of random blocked-tip designs (force_calibration.py;
                     # 16 read: 1, not calibrated);
                     # 16: stretch_hazard, the emulated membrane stretch and the flag
                     # high_membrane_stretch (stretch_hazard.py; 15 read: none, no flag);
                     # 15: blocked_range, where each design's blocked-tip FE curve ends
                     # (blocked_range.py; 14 read: none, the group's force range); the
                     # force GPs in segments, each node conditioned on every design that
                     # reaches it (force_gps.py; 14 read: one VectorGP);
                     # failed_end_volume_ul, the early-ended curves' last FE injected
                     # volumes (reduced), which cap the range by volume near them
                     # (pair_emulator.PairEmulator.end_volume_cap_ul; 14 read: none, no cap);
                     # 14: top_pressure_gps, the pressure nodes from 45 deg read with the
                     # shape below (shape_gps.py; 13 read: none, the curve GPs' own);
                     # 13: volume_gps, the volume nodes read with the pressure curve's
                     # shape (shape_gps.py; 12 read: none, the curve GPs' own);
                     # 12: balance_models, the signed angle by volume at a group's
                     # stiffness balance (balance.py; 11 read: none, refused there);
                     # 11: early_ended_nodes, the early-ended database curves' GP
                     # outputs (early_ended_nodes; 10 read: none);
                     # 10: volume_rise_anchor, the volume nodes above it as their rise
                     # (curve_gps; 9 read: none, plain log V / theta);
                     # 9: force_form "angle_ratio" (8 read: their own form);
                     # 8: variance_nodes, chosen per fit (7 read: FORMAT_7_NODES);
                     # 7: near_failed_band_scale (6 read: none, the group's bands);
                     # 6: range_model, the emulated end of the FE curve (5 read: none);
                     # 5: fe_max_volume_ul, the FE's volume stop (4 read: none); 4:
                     # force_form (3 read: F/p); 3: band_scale per output node (2 read, one
                     # multiplier)


def emulator_to_dict(e: Emulator) -> dict:
    pairs = []
    for pe in e.pairs.values():
        pairs.append({
            "pair": pe.pair, "sign": pe.sign, "band_scale": pe.band_scale.tolist(),
            "fe_limit_angle_deg": pe.fe_limit_angle_deg, "fe_stop_reason": pe.fe_stop_reason,
            "coordinates": pe.coordinates.tolist(), "keys": list(pe.keys),
            "failed": [[np.asarray(u).tolist(), a, r] for u, a, r in pe.failed],
            "failed_end_volume_ul": None if pe.failed_end_volume_ul is None
            else np.asarray(pe.failed_end_volume_ul, float).tolist(),
            "curves": pe.curves.gp.as_dict(),
            "volume_rise_anchor": pe.curves.volume_rise_anchor,
            "early_ended_nodes": None if pe.curves.early_ended is None else {
                "u": pe.curves.early_ended.u, "y": pe.curves.early_ended.y},
            "volume_gps": None if pe.curves.volume is None else pe.curves.volume.as_dict(),
            "top_pressure_gps": None if pe.curves.top_pressure is None
            else pe.curves.top_pressure.as_dict(),
            "force": None if pe.force is None else pe.force.as_dict(),
            "force_band_scale": pe.force_band_scale, "force_band_factor": pe.force_band_factor,
            "force_limit_pa": pe.force_limit_pa,
            "force_form": pe.force_form, "fe_max_volume_ul": pe.fe_max_volume_ul,
            "range_model": None if pe.range_model is None else pe.range_model.as_dict(),
            "near_failed_band_scale": None if pe.near_failed_band_scale is None
            else pe.near_failed_band_scale.tolist(),
            "blocked_range": None if pe.blocked_range is None else pe.blocked_range.as_dict(),
            "stretch_hazard": None if pe.stretch_hazard is None
            else pe.stretch_hazard.as_dict()})
    return seal(plain_json({
        "format": FORMAT_NAME, "format_version": FORMAT_VERSION, "name": e.name,
        "angle_nodes_deg": ANGLE_NODES_DEG.tolist(),
        "force_pressure_nodes_pa": FORCE_PRESSURE_NODES_PA.tolist(),
        "provenance": e.provenance, "report": e.report, "pairs": pairs,
        "sign_models": {g: m.as_dict() for g, m in e.sign_models.items()},
        "balance_models": {g: m.as_dict() for g, m in e.balance_models.items()},
        "variance_nodes": np.asarray(e.variance_nodes).tolist()}))


def emulator_from_dict(d: object, origin: str = "<dict>", raw: bytes | None = None
                       ) -> Emulator:
    """The emulator in the parsed file ``d`` (``raw``: the bytes it was parsed from, for a
    fast checksum check), validated; SurrogateFileError naming ``origin`` otherwise."""
    version = check_header(d, FORMAT_NAME, FORMAT_VERSION, "an emulator", origin)
    assert isinstance(d, dict)  # check_header refused anything else
    if (d.get("angle_nodes_deg") != ANGLE_NODES_DEG.tolist()
            or d.get("force_pressure_nodes_pa") != FORCE_PRESSURE_NODES_PA.tolist()):
        raise SurrogateFileError(origin, "made with other curve nodes than this code uses; "
                                 "refit it with `balloon fit`")
    check_seal(d, origin, raw)
    try:
        report = dict(d.get("report") or {})
        _check_group_coverage(report)
        for p in d["pairs"]:   # the cheap checks first: a damaged file costs no factorisation
            _precheck_pair(p)
        variance_nodes = _variance_nodes(d.get("variance_nodes"))
        balance_models = (_balance_models(d.get("balance_models"),
                                          set(d.get("sign_models") or {}))
                          if version >= 12 else {})
        # then each pair's small models (~100-600 designs, ~0.02 s a pair): a damaged one is
        # refused before the curves' GPs are factorised (~0.4-0.9 s a pair)
        small = [(blocked_range_from_dict(p.get("blocked_range")),
                  stretch_hazard_from_dict(p.get("stretch_hazard"))) for p in d["pairs"]]
        pairs = {}
        for p, (blocked, hazard) in zip(d["pairs"], small, strict=True):
            pair = str(p["pair"])
            pairs[pair] = PairEmulator(
                pair=pair, sign=float(p["sign"]),
                curves=CurveGPs(vector_gp_from_dict(p["curves"]),
                                _rise_anchor(p.get("volume_rise_anchor")),
                                _early_ended_rows(p.get("early_ended_nodes")),
                                *_shape_gps(p)),
                band_scale=_band_scales(p["band_scale"]),
                fe_limit_angle_deg=float(p["fe_limit_angle_deg"]),
                fe_stop_reason=str(p["fe_stop_reason"]),
                coordinates=np.array(p["coordinates"], float),
                keys=tuple(str(k) for k in p["keys"]),
                force=None if p["force"] is None else force_gps_from_dict(p["force"]),
                force_band_scale=float(p["force_band_scale"]),
                force_band_factor=float(p.get("force_band_factor", 1.0)),
                force_limit_pa=float(p["force_limit_pa"]),
                failed=tuple((np.array(u, float), float(a), str(r)) for u, a, r in p["failed"]),
                force_form=str(p.get("force_form", FORCE_FORMS[0])),
                fe_max_volume_ul=None if p.get("fe_max_volume_ul") is None
                else float(p["fe_max_volume_ul"]),
                range_model=None if p.get("range_model") is None
                else vector_gp_from_dict(p["range_model"]),
                near_failed_band_scale=None if p.get("near_failed_band_scale") is None
                else _band_scales(p["near_failed_band_scale"]),
                blocked_range=blocked, failed_end_volume_ul=_end_volumes(p),
                stretch_hazard=hazard)
        sign_models = {str(g): vector_gp_from_dict(m)
                       for g, m in (d.get("sign_models") or {}).items()}
        if not pairs:
            raise ValueError("no pairs")
        for pe in pairs.values():
            _check_pair(pe)
        for group, m in sign_models.items():
            _check_gp(m, f"sign model {group}")
        return Emulator(name=str(d["name"]), pairs=pairs, provenance=dict(d["provenance"]),
                        report=report, sign_models=sign_models,
                        variance_nodes=variance_nodes,
                        balance_models=balance_models)
    except (KeyError, TypeError, ValueError, IndexError, AttributeError, ArithmeticError,
            np.linalg.LinAlgError) as exc:
        raise SurrogateFileError(origin, f"damaged emulator file ({type(exc).__name__}: "
                                 f"{exc})") from None


def _precheck_pair(p: dict) -> None:
    """A pair's stored numbers that need no GP, checked before any is factorised (band
    scales, sign, coordinates against keys, the curves' centre and scale, the FE and force
    limits, the force form; ValueError, TypeError or KeyError otherwise). ``_check_pair``
    checks the GPs once built."""
    _rise_anchor(p.get("volume_rise_anchor"))
    early = _early_ended_rows(p.get("early_ended_nodes"))
    if early is not None and early.y.shape[1] != 2 * N_NODES:
        raise ValueError(f"pair {p['pair']}: early_ended_nodes y must have {2 * N_NODES} "
                         "outputs per curve")
    for name, nodes, _ in _SHAPE_FIELDS:
        shape = p.get(name)
        if shape is not None:
            if not isinstance(shape, dict) or not isinstance(shape.get("gp"), dict):
                raise ValueError(f"pair {p['pair']}: {name} must be an object with gp, "
                                 "shape_nodes_deg, shape_low, shape_span, pressure_lengths "
                                 "and shape_alpha")
            shape_scaling(shape, name, nodes)
    if p.get("top_pressure_gps") is not None and p.get("volume_gps") is None:
        raise ValueError(f"pair {p['pair']}: top_pressure_gps needs volume_gps (both read "
                         "the pressure GPs alone)")
    scales = _band_scales(p["band_scale"])
    if scales.shape != (2 * N_NODES,) or not np.isfinite(scales).all() or (scales <= 0).any():
        raise ValueError(f"pair {p['pair']}: band scales must be {2 * N_NODES} positive "
                         "numbers")
    near = p.get("near_failed_band_scale")
    if near is not None:
        near = _band_scales(near)
        if near.shape != (2 * N_NODES,) or not np.isfinite(near).all() or (near < 1).any():
            raise ValueError(f"pair {p['pair']}: near_failed_band_scale must be "
                             f"{2 * N_NODES} numbers >= 1")
    if abs(float(p["sign"])) != 1.0:
        raise ValueError(f"pair {p['pair']}: sign must be +1 or -1")
    coordinates = np.array(p["coordinates"], float)
    if coordinates.ndim != 2 or len(coordinates) != len(p["keys"]):
        raise ValueError(f"pair {p['pair']}: coordinates and keys do not agree")
    for name in ("center", "scale", "residual_var"):
        values = np.array(p["curves"][name], float)
        if values.ndim != 1 or not np.isfinite(values).all():
            raise ValueError(f"pair {p['pair']}: curves {name} must be finite numbers")
    scalars = {name: float(p[name]) for name in (
        "fe_limit_angle_deg", "force_band_scale", "force_limit_pa")}
    scalars["force_band_factor"] = float(p.get("force_band_factor", 1.0))  # 17 and later
    if not all(math.isfinite(v) and v > 0 for v in scalars.values()):
        raise ValueError(f"pair {p['pair']}: FE limit, force band scale and factor and "
                         "force limit must be positive numbers")
    form = str(p.get("force_form", FORCE_FORMS[0]))
    if form not in FORCE_FORMS:
        raise ValueError(f"pair {p['pair']}: force_form {form!r} is not one of "
                         f"{', '.join(FORCE_FORMS)}")
    _end_volumes(p)
    volume = p.get("fe_max_volume_ul")
    if volume is not None and not (math.isfinite(float(volume)) and float(volume) > 0):
        raise ValueError(f"pair {p['pair']}: fe_max_volume_ul must be a positive number")
    if not np.isfinite(coordinates).all():
        raise ValueError(f"pair {p['pair']}: coordinates are not finite")


def _end_volumes(p: dict) -> np.ndarray | None:
    """A pair's early-ended curves' last FE injected volumes (reduced ul, one per entry of
    ``failed``; None before format 15); ValueError when damaged."""
    value = p.get("failed_end_volume_ul")
    if value is None:
        return None
    numbers = isinstance(value, list) and all(
        isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
    out = np.array(value if numbers else [], float)
    if (not numbers or out.shape != (len(p["failed"]),) or not np.isfinite(out).all()
            or (out <= 0).any()):
        raise ValueError(f"pair {p['pair']}: failed_end_volume_ul must be one positive "
                         "number (ul) per early-ended curve of failed")
    return out


def _check_group_coverage(report: dict) -> None:
    """The calibration's per-group coverage, which queries read for the flag
    ``band_undercovers_random_designs`` (``validity.random_design_coverage``): each cell a
    share in [0, 1] or None, with non-negative counts of points and curves."""
    cal = report.get("random_design_calibration") or {}
    for pair, axes in (cal.get("group_coverage_after") or {}).items():
        for axis, sides in axes.items():
            for side, cell in sides.items():
                share = cell["coverage"]
                counts = (cell["points"], cell["curves"])
                if (share is not None and not (isinstance(share, (int, float))
                                               and 0.0 <= share <= 1.0)) or not all(
                        isinstance(c, int) and not isinstance(c, bool) and c >= 0
                        for c in counts):
                    raise ValueError(f"report: group_coverage_after {pair} {axis} {side} "
                                     "must hold a coverage in [0, 1] (or null) and counts "
                                     "of points and curves >= 0")


def _check_gp(gp, what: str) -> None:
    """A GP that gives finite means at its own first training input (the shapes of every
    stored array must agree for that) and a non-negative variance there (its first
    output's GP, by triangular solves). Not the VectorGP's variance: that makes the
    kernels' L^-1 and K (n x n each), which only the kernels a query asks a variance of
    should hold, when it first does (made here for every kernel: 1.25 GB more, loading
    1-2 s longer)."""
    x0 = gp.gps[0].x[:1]
    mean = gp.predict(x0[0], MEANS_ONLY)[0]
    var = gp.gps[0].predict(x0)[1]
    if not (np.isfinite(mean).all() and np.isfinite(var).all() and (var >= 0).all()):
        raise ValueError(f"{what}: no finite answer at its own training design")


def _rise_anchor(value: object) -> int | None:
    """The file's volume rise anchor: an angle-node index below the last, or none (files
    before format 10; ValueError otherwise: damage)."""
    if value is None:
        return None
    if type(value) is not int or not 0 <= value < N_NODES - 1:
        raise ValueError(f"volume_rise_anchor {value!r}: an angle-node index from 0 to "
                         f"{N_NODES - 2}")
    return value


def _early_ended_rows(value: object) -> EarlyEndedRows | None:
    """The file's early-ended curves' GP outputs (None before format 11; ValueError,
    TypeError or KeyError when damaged: EarlyEndedRows checks shapes and the pattern)."""
    if value is None:
        return None
    if not isinstance(value, dict) or not {"u", "y"} <= value.keys():
        raise ValueError("early_ended_nodes must be an object with u and y")
    u = np.array(value["u"], float)
    if (u.ndim != 2 or u.shape[1] != len(SAMPLED)
            or not ((u >= -1e-6) & (u <= 1 + 1e-6)).all()):
        raise ValueError(f"early_ended_nodes u must be unit-cube coordinates (m, "
                         f"{len(SAMPLED)})")
    return EarlyEndedRows(u, np.array(value["y"], float))


# the file's fields of GPs read with the pressure curve's shape, with the shape nodes a
# file that stored none meant (format 13's volume GPs) and the node outputs they give
_SHAPE_FIELDS = (("volume_gps", VOLUME_SHAPE_NODES_DEG, N_NODES),
                 ("top_pressure_gps", TOP_SHAPE_NODES_DEG, N_NODES - TOP_PRESSURE_FROM))


def _shape_gps(p: dict) -> tuple[ShapeGPs | None, ShapeGPs | None]:
    """A pair's volume GPs and top pressure GPs (None each before formats 13 and 14;
    ValueError, TypeError or KeyError when damaged): inputs the unit coordinates and the
    shape numbers, one output per node they give."""
    out = []
    for name, nodes, outputs in _SHAPE_FIELDS:
        value = p.get(name)
        if value is None:
            out.append(None)
            continue
        shape = shape_gps_from_dict(value, name, nodes)   # its form checked by _precheck_pair
        if (shape.gp.gps[0].x.shape[1] != len(SAMPLED) + len(shape.shape_low)
                or len(shape.gp.center) != outputs):
            raise ValueError(f"{name}: inputs must be {len(SAMPLED)} unit coordinates and "
                             f"{len(shape.shape_low)} shape numbers, outputs "
                             f"{outputs}")
        out.append(shape)
    return out[0], out[1]


def _balance_models(value: object, sign_groups: set) -> dict[str, BalanceModel]:
    """The file's balance models by group (none before format 12); ValueError when one is
    damaged or belongs to a group without a sign model (it would never be asked)."""
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise ValueError("balance_models must be an object by material group")
    out = {}
    for group, d in value.items():
        if group not in sign_groups:
            raise ValueError(f"balance_models {group}: no sign model for this group")
        model = balance_model_from_dict(d)
        _check_gp(model.gp, f"balance model {group}")
        out[str(group)] = model
    return out


def _band_scales(value: object) -> np.ndarray:
    """Per-node band multipliers; a format-2 file's single multiplier applies to all."""
    if isinstance(value, (int, float)):
        return np.full(2 * N_NODES, float(value))
    return np.asarray(value, float)


def _check_pair(pe: PairEmulator) -> None:
    """The GPs of one built pair answer at their own training designs (ValueError
    otherwise); every stored number that needs no GP was checked before building
    (``_precheck_pair``)."""
    _check_gp(pe.curves.gp, f"pair {pe.pair}")   # finite GP outputs: finite node outputs
    for name, shape in (("volume_gps", pe.curves.volume),
                        ("top_pressure_gps", pe.curves.top_pressure)):
        if shape is not None:
            _check_gp(shape.gp, f"pair {pe.pair} {name}")
    if pe.curves.early_ended is not None:
        mean = pe.curves.predict(pe.curves.early_ended.u[0], MEANS_ONLY, early_weight=1.0)[0]
        if not np.isfinite(mean).all():
            raise ValueError(f"pair {pe.pair}: early_ended_nodes give no finite answer at "
                             "their own first design")
    if pe.force is not None:
        _check_gp(pe.force, f"pair {pe.pair} force")
    if pe.range_model is not None:
        _check_gp(pe.range_model, f"pair {pe.pair} range model")
    if pe.blocked_range is not None:
        _check_gp(pe.blocked_range.model, f"pair {pe.pair} blocked range")
    if pe.stretch_hazard is not None:
        _check_gp(pe.stretch_hazard.model, f"pair {pe.pair} stretch hazard")


def _variance_nodes(nodes: object) -> np.ndarray:
    """The file's variance nodes (FORMAT_7_NODES before format 8): increasing pressure-node
    indices from the first to the last (ValueError otherwise: damage)."""
    if nodes is None:
        return FORMAT_7_NODES.copy()
    out = np.asarray(nodes)
    if (out.ndim != 1 or out.size < 2 or out.dtype.kind not in "iu" or out[0] != 0
            or out[-1] != len(ANGLE_NODES_DEG) - 1 or (np.diff(out) <= 0).any()):
        raise ValueError(f"variance_nodes {nodes!r}: increasing node indices from 0 to "
                         f"{len(ANGLE_NODES_DEG) - 1}")
    return out.astype(int)


def save_emulator(e: Emulator, path: str | os.PathLike) -> Path:
    """Write ``e`` as canonical JSON (``file_seal.canonical_text``: its checksum is then
    verified on the bytes when loaded)."""
    return write_text_atomic(path, canonical_text(emulator_to_dict(e)))


LOAD_CACHE_SIZE = 2


@functools.cache
def one_blas_thread() -> object:
    """Keep this process's OpenBLAS on one thread from now on (once per process: the
    limit object is kept). An emulator query is a few products of (n, n) matrices with
    n ~ 450: threads buy nothing there, and on a loaded 2-core machine they cost -- the
    same design search took 48 s with OpenBLAS's default threads against 7 s on one
    (`balloon inverse --angle-deg 30 --pressure-pa 1500 --L-range 10 10 -n 3`, load ~5,
    2026-12-06). A process that loads an emulator queries it (the service, predict,
    inverse, calibrate); the FE solves run in processes of their own (the service's job
    workers, `balloon solve`), and PARDISO's threads are MKL's, not OpenBLAS's."""
    return ThreadpoolController().select(internal_api="openblas").limit(limits=1)


_loaded: OrderedDict[tuple[str, bytes], Emulator] = OrderedDict()
_loaded_lock = threading.Lock()


def load_emulator(path: str | os.PathLike) -> Emulator:
    """The emulator in the file at ``path``, validated (SurrogateFileError naming the file,
    never its directory); the same object again while the file's content is unchanged."""
    path = Path(path)
    try:
        raw = read_model_file(path)
    except (FileNotFoundError, IsADirectoryError):
        raise
    except OSError as exc:
        raise SurrogateFileError(path.name, f"cannot be read ({type(exc).__name__})"
                                 ) from None
    key = (path.name, hashlib.blake2b(raw, digest_size=32).digest())
    with _loaded_lock:
        if key in _loaded:
            _loaded.move_to_end(key)
            return _loaded[key]
    try:  # ValueError: JSONDecodeError, UnicodeDecodeError, an integer of > 4300 digits
        data = json.loads(raw.decode("utf-8"))
    except (ValueError, RecursionError) as exc:
        raise SurrogateFileError(path.name, f"cannot be read ({type(exc).__name__})"
                                 ) from None
    one_blas_thread()       # for the loading's algebra and the queries after it
    emulator = emulator_from_dict(data, path.name, raw)
    with _loaded_lock:
        _loaded[key] = emulator
        while len(_loaded) > LOAD_CACHE_SIZE:
            _loaded.popitem(last=False)
    return emulator
