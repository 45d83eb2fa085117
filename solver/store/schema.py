"""The HDF5 layout of the curve database (docs/database.md describes it for other tools).

    /                                 attrs: format, schema_version, created_utc,
                                             updated_utc, n_records, user metadata
    /records/<key>/                   one group per record; attrs: key, status, reason
        design/                       attrs: L_mm t_mm T_mm b_mm h_mm W_mm body_length_mm
                                             chamber_offset_mm (mm), body_material_id,
                                             body_material_mu_kpa[], body_material_alpha[],
                                             membrane_material_id, _mu_kpa[], _alpha[]
        settings/                     attrs: every SolverSettings field
        curve/                        datasets (n = converged steps incl. the undeformed
                                      state): pressure_pa, volume_ul, time_s, angle_deg,
                                      tip_displacement_mm (n x 2), max_membrane_stretch,
                                      force_mn, newton_iterations (int64), residual_norm,
                                      negative_eigenvalues (int64), optional
                                      volume_control_negative_eigenvalues (int64);
                                      attrs: status, reason, pressure_maximum_index,
                                      n_dofs, wall_time_s, optional branch_switch_index
            timings_s/                attrs: seconds per solver phase
        provenance/                   attrs: package_version, git_commit, created_utc,
                                             wall_time_s, status, reason, host

A record group's ``sha256`` attribute is the checksum of its curve, curve attributes and
provenance (``record_checksum``); a reader recomputes it, so that a flipped byte is an
error, never a wrong number (records written before it have none and are read as they
are; design and settings are checked by their key). Version history: 1 -- first layout
(the two optional members, added with issue 12, are absent from older records and read as
None / -1).
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from solver.curve import STATUSES, Curve
from solver.design import LIMITS_MM, Design, design_from_dict
from solver.errors import InputError
from solver.materials import stored_material
from solver.settings import LEGACY_MESH_DIVISIONS, SolverSettings, settings_from_dict
from solver.store.errors import NotACurveStoreError, SchemaVersionError
from solver.store.keys import ADDED_SETTINGS, record_key
from solver.store.record import Record

FORMAT = "balloon-actuator-curves"
SCHEMA_VERSION = 1
RECORDS = "records"
MATERIAL_ROLES = ("body_material", "membrane_material")
INT_ARRAYS = ("newton_iterations", "negative_eigenvalues")
VOLUME_CONTROL_NEGATIVE = "volume_control_negative_eigenvalues"   # optional dataset
JSON_SUFFIX = "_json"
MAX_ATTRS = 1000  # far more than any object here has


def plain(value: object) -> object:
    """An HDF5 attribute value as plain Python (str, int, float, bool, list)."""
    if isinstance(value, bytes):
        return value.decode("utf-8")
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    return value


def read_attrs(obj: h5py.HLObject) -> dict[str, Any]:
    """Attributes as plain values; names ending in ``_json`` are decoded JSON."""
    out: dict[str, Any] = {}
    for count, (name, value) in enumerate(obj.attrs.items()):
        if count > MAX_ATTRS:  # a damaged attribute list can make HDF5 iterate forever
            raise ValueError(f"more than {MAX_ATTRS} attributes: the object is damaged")
        value = plain(value)
        if name.endswith(JSON_SUFFIX) and isinstance(value, str):
            out[name[: -len(JSON_SUFFIX)]] = json.loads(value)
        else:
            out[name] = value
    return out


def write_attrs(obj: h5py.HLObject, items: dict[str, object]) -> None:
    """Scalars and numeric lists as attributes; dicts and other lists as ``<name>_json``."""
    for name, value in items.items():
        if isinstance(value, (str, bool, int, float)):
            obj.attrs[name] = value
        elif (isinstance(value, (list, tuple)) and value
              and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)):
            obj.attrs[name] = np.asarray(value, dtype=float)
        else:
            obj.attrs[name + JSON_SUFFIX] = json.dumps(value, sort_keys=True)


def check_schema(f: h5py.File, path: Path | str) -> None:
    """Refuse files that are not curve databases or have a newer schema."""
    if plain(f.attrs.get("format")) != FORMAT:
        raise NotACurveStoreError("db", f"{path} is not a curve database (no format = "
                                  f"{FORMAT!r} attribute)", "a file written by balloon precompute")
    found = int(plain(f.attrs.get("schema_version", 0)))  # type: ignore[call-overload]
    if found > SCHEMA_VERSION:
        raise SchemaVersionError(
            f"{path} has database schema version {found}, but this balloon-actuator reads "
            f"versions up to {SCHEMA_VERSION}: upgrade the package (pip install -U "
            f"balloon-actuator) or regenerate the file with `balloon precompute`")
    if found < 1:
        raise NotACurveStoreError("db", f"{path} has an invalid schema_version {found}",
                                  f"1 <= schema_version <= {SCHEMA_VERSION}")


def init_file(f: h5py.File, created_utc: str) -> None:
    f.attrs["format"] = FORMAT
    f.attrs["schema_version"] = SCHEMA_VERSION
    f.attrs["created_utc"] = created_utc
    f.attrs["updated_utc"] = created_utc
    f.attrs["n_records"] = 0
    f.require_group(RECORDS)


def validate_record(record: Record) -> None:
    """Raise InputError unless the record is consistent and storable."""
    if not isinstance(record, Record):
        raise InputError("record", f"expected a Record, got {type(record).__name__}")
    expected = record_key(record.design, record.settings)
    if record.key != expected:
        raise InputError("key", f"record key {record.key!r} is not the key of its design and "
                         f"settings", f"record_key(design, settings) = {expected}")
    curve = record.curve
    if curve.status not in STATUSES:
        raise InputError("status", f"got {curve.status!r}", " | ".join(STATUSES))
    n = len(curve)
    for name in Curve.ARRAY_FIELDS:
        shape = np.shape(getattr(curve, name))
        wanted = (n, 2) if name == "tip_displacement_mm" else (n,)
        if shape != wanted:
            raise InputError(f"curve.{name}", f"shape {shape} does not match {n} steps",
                             f"shape {wanted}")
    vneg = curve.volume_control_negative_eigenvalues
    if vneg is not None and np.shape(vneg) != (n,):
        raise InputError(f"curve.{VOLUME_CONTROL_NEGATIVE}",
                         f"shape {np.shape(vneg)} does not match {n} steps", f"shape ({n},)")


def record_checksum(record: Record) -> str:
    """sha256 of what the key does not cover: the curve's arrays (as stored: float64 or
    int64), its status, reason and scalars, and the provenance."""
    curve = record.curve
    h = hashlib.sha256()
    for name in Curve.ARRAY_FIELDS:
        dtype = np.int64 if name in INT_ARRAYS else np.float64
        h.update(name.encode())
        h.update(np.ascontiguousarray(getattr(curve, name), dtype=dtype).tobytes())
    rest = {"status": curve.status, "reason": curve.reason,
            "pressure_maximum_index": int(curve.pressure_maximum_index),
            "n_dofs": int(curve.n_dofs), "wall_time_s": float(curve.wall_time_s),
            "timings_s": {k: float(v) for k, v in curve.timings_s.items()},
            "provenance": dict(record.provenance)}
    h.update(json.dumps(rest, sort_keys=True, default=str).encode())
    return h.hexdigest()


def write_record(group: h5py.Group, record: Record) -> None:
    """Write ``record`` into the empty group ``group``."""
    design = record.design.as_dict()
    curve = record.curve
    group.attrs["key"] = record.key
    group.attrs["sha256"] = record_checksum(record)
    group.attrs["status"] = curve.status
    group.attrs["reason"] = curve.reason
    g = group.create_group("design")
    for name in LIMITS_MM:
        g.attrs[name] = float(design[name])  # type: ignore[arg-type]
    for role in MATERIAL_ROLES:
        material = getattr(record.design, role)
        g.attrs[f"{role}_id"] = material.id
        g.attrs[f"{role}_mu_kpa"] = np.asarray(material.mu_kpa, dtype=float)
        g.attrs[f"{role}_alpha"] = np.asarray(material.alpha, dtype=float)
    write_attrs(group.create_group("settings"), record.settings.as_dict())
    g = group.create_group("curve")
    for name in Curve.ARRAY_FIELDS:
        dtype = np.int64 if name in INT_ARRAYS else np.float64
        g.create_dataset(name, data=np.asarray(getattr(curve, name), dtype=dtype))
    g.attrs["status"] = curve.status
    g.attrs["reason"] = curve.reason
    g.attrs["pressure_maximum_index"] = int(curve.pressure_maximum_index)
    if curve.volume_control_negative_eigenvalues is not None:
        g.create_dataset(VOLUME_CONTROL_NEGATIVE, data=np.asarray(
            curve.volume_control_negative_eigenvalues, dtype=np.int64))
    g.attrs["branch_switch_index"] = int(curve.branch_switch_index)
    g.attrs["n_dofs"] = int(curve.n_dofs)
    g.attrs["wall_time_s"] = float(curve.wall_time_s)
    write_attrs(g.create_group("timings_s"), {k: float(v) for k, v in curve.timings_s.items()})
    write_attrs(group.create_group("provenance"), dict(record.provenance))


def read_design(group: h5py.Group) -> Design:
    attrs = read_attrs(group["design"])
    data: dict[str, object] = {name: attrs[name] for name in LIMITS_MM}
    for role in MATERIAL_ROLES:
        data[role] = stored_material(attrs[f"{role}_id"], attrs[f"{role}_mu_kpa"],
                                     attrs[f"{role}_alpha"])
    return design_from_dict(data)


def read_settings(group: h5py.Group) -> SolverSettings:
    """A record's settings; a record stored before the balanced mesh became the default
    names the former level 0 "default": read as "former" (its key is unchanged,
    solver/store/keys.py), and one stored before a setting existed was solved with the
    value ``ADDED_SETTINGS`` gives it (no mesh_divisions: the former level 0), not with
    today's default."""
    attrs = dict(read_attrs(group["settings"]))
    for added, value in ADDED_SETTINGS.items():
        attrs.setdefault(added, value)
    name = attrs.get("mesh_divisions")
    if isinstance(name, str) and name in LEGACY_MESH_DIVISIONS:
        attrs["mesh_divisions"] = LEGACY_MESH_DIVISIONS[name]
    return settings_from_dict(attrs)


def read_curve(group: h5py.Group) -> Curve:
    g = group["curve"]
    arrays = {name: np.asarray(g[name][()]) for name in Curve.ARRAY_FIELDS}
    attrs = read_attrs(g)
    return Curve(**arrays, status=str(attrs["status"]), reason=str(attrs["reason"]),
                 pressure_maximum_index=int(attrs["pressure_maximum_index"]),  # type: ignore
                 volume_control_negative_eigenvalues=(
                     np.asarray(g[VOLUME_CONTROL_NEGATIVE][()])
                     if VOLUME_CONTROL_NEGATIVE in g else None),
                 branch_switch_index=int(attrs.get("branch_switch_index", -1)),  # type: ignore
                 n_dofs=int(attrs["n_dofs"]),
                 wall_time_s=float(attrs["wall_time_s"]),
                 timings_s={k: float(v) for k, v in read_attrs(g["timings_s"]).items()})


def read_record(group: h5py.Group) -> Record:
    """The stored record, checked: its design and settings must still give its key and
    the curve's arrays must agree in length (ValueError otherwise: damage)."""
    record = Record(key=str(plain(group.attrs["key"])), design=read_design(group),
                    settings=read_settings(group), curve=read_curve(group),
                    provenance=read_attrs(group["provenance"]))
    if record.key != group.name.rsplit("/", 1)[-1]:
        raise ValueError(f"the record's key attribute {record.key[:12]} is not its name")
    try:
        validate_record(record)
    except InputError as exc:
        raise ValueError(f"inconsistent record: {exc}") from None
    stored = group.attrs.get("sha256")
    if stored is not None and plain(stored) != record_checksum(record):
        raise ValueError("checksum mismatch: the stored curve or provenance has changed")
    return record


def read_summary(group: h5py.Group) -> dict[str, Any]:
    """Key, status, reason, design, settings and step count without loading the curve."""
    design = read_attrs(group["design"])
    flat: dict[str, Any] = {name: design[name] for name in LIMITS_MM}
    for role in MATERIAL_ROLES:
        flat[role] = design[f"{role}_id"]
    return {"key": plain(group.attrs["key"]), "status": plain(group.attrs["status"]),
            "reason": plain(group.attrs["reason"]), "design": flat,
            "settings": read_attrs(group["settings"]),
            "n_steps": int(group["curve/pressure_pa"].shape[0]),
            "provenance": read_attrs(group["provenance"])}


# -- the summary index ----------------------------------------------------------------------
# Every record's ``read_summary`` row, kept at the root as one JSON document (UTF-8 bytes
# in a chunked uint8 dataset with a fletcher32 checksum per chunk), rewritten by every
# publish (``update_summary_index``). HDF5 reads an attribute in ~0.15 ms here (HDF5 2.0):
# the 2403 shipped records' rows took 16 s from their attributes, ~0.1 s from the index.
# Derived data only: a reader uses it when it names exactly the records the file holds
# (``read_summary_index``), and reads the attributes otherwise (a file of older code, or
# one older code added records to).
SUMMARY_INDEX = "summary_index"
INDEX_CHUNK_BYTES = 1 << 16     # resized and overwritten by the next publish


def read_summary_index(f: h5py.File) -> dict[str, dict[str, Any]] | None:
    """The file's summary rows by record key, or None when it has no index, or one that
    cannot be read (a chunk's checksum, its JSON) or is not rows keyed by their key."""
    if SUMMARY_INDEX not in f:
        return None
    try:
        data = f[SUMMARY_INDEX][()]
        rows = json.loads(np.asarray(data, dtype=np.uint8).tobytes().decode("utf-8"))
    except (OSError, ValueError, TypeError, KeyError):
        return None
    if not isinstance(rows, dict) or not all(
            isinstance(row, dict) and row.get("key") == key for key, row in rows.items()):
        return None
    return rows


def write_summary_index(f: h5py.File, rows: dict[str, dict[str, Any]]) -> None:
    """Store ``rows`` (key -> summary row) as the file's summary index, overwriting the
    present one in place."""
    data = np.frombuffer(json.dumps(rows, sort_keys=True, separators=(",", ":"),
                                    ).encode("utf-8"), dtype=np.uint8)
    if SUMMARY_INDEX not in f:
        f.create_dataset(SUMMARY_INDEX, shape=(0,), maxshape=(None,), dtype=np.uint8,
                         chunks=(INDEX_CHUNK_BYTES,), fletcher32=True)
    index = f[SUMMARY_INDEX]
    index.resize((data.size,))
    index[:] = data


def update_summary_index(f: h5py.File, changed: set[str] | frozenset[str],
                         keep: bool = True) -> None:
    """Make the index of ``f`` name exactly its records: the present rows kept (with
    ``keep``), except those of the records in ``changed`` (just written) and of records
    it lacks, read from their attributes (all of them for a file without an index, or
    without ``keep``)."""
    group = f[RECORDS]
    old = (read_summary_index(f) if keep else None) or {}
    rows = {key: old[key] if key in old and key not in changed else read_summary(group[key])
            for key in sorted(group)}
    write_summary_index(f, rows)
