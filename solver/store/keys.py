"""Stable record keys: the same design and solver settings always give the same key.

A key is the first 32 hex digits (128 bits) of the SHA-256 of a canonical JSON text::

    {"design": Design.as_dict(), "key_version": 2, "settings": SolverSettings.as_dict()}

except that settings added after version 2 (``ADDED_SETTINGS``) are left out while they
hold the value every version-2 record was solved with (for mesh_divisions the former
level 0, "former"; the default is now "balanced"), so every key of version 2 stays valid
and a record with another value gets a key of its own.

Canonical means: the design is validated first (so a default body length and an
explicit 12 mm give the same key), every number is a float rounded to
``SIGNIFICANT_DIGITS`` significant digits (7, 7.0 and 7.0000000000001 agree; -0.0
becomes 0.0), object keys are sorted, and the separators carry no spaces. The
materials enter with their id and their full Ogden parameters, so a custom material
that merely reuses a preset's id still gets its own key.

Changing this canonical form invalidates every stored key: bump ``KEY_VERSION``.
"""

from __future__ import annotations

import hashlib
import json
import math

from solver.design import Design
from solver.errors import InputError
from solver.settings import SolverSettings

KEY_VERSION = 2   # 2: mesh levels redefined (solver/mesh.py), so a level names a new mesh
                  # (the default's move to the balanced level 0 needed no new version:
                  # mesh_divisions is in the key whenever it is not "former", below)
# Settings added after version 2, with the value that keeps a version-2 key.
# mesh_divisions: left out at the former level 0 (called "default" until the balanced mesh
# became the default), so the keys of every record solved on it before hold.
ADDED_SETTINGS = {"mesh_divisions": "former"}
SIGNIFICANT_DIGITS = 10
KEY_HEX_DIGITS = 32


def canonical_number(value: float) -> float:
    """``value`` rounded to SIGNIFICANT_DIGITS significant digits, as a float."""
    x = float(value)
    if not math.isfinite(x):
        raise InputError("record_key", f"non-finite number {value!r} in a design or settings",
                         "finite numbers")
    rounded = float(f"{x:.{SIGNIFICANT_DIGITS}g}")
    return 0.0 if rounded == 0.0 else rounded


def canonical(value: object) -> object:
    """Plain data with every number canonicalised (bools and strings kept as they are)."""
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return value
    if isinstance(value, (int, float)):
        return canonical_number(value)
    if isinstance(value, dict):
        return {str(k): canonical(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [canonical(v) for v in value]
    raise InputError("record_key", f"cannot canonicalise a {type(value).__name__}",
                     "numbers, strings, lists and dicts")


def canonical_json(design: Design, settings: SolverSettings) -> str:
    """The text whose hash is the key (useful to see why two keys differ)."""
    plain = settings.validated().as_dict()
    for name, default in ADDED_SETTINGS.items():
        if plain[name] == default:
            del plain[name]
    data = {"design": design.as_dict(), "key_version": KEY_VERSION, "settings": plain}
    return json.dumps(canonical(data), sort_keys=True, separators=(",", ":"))


def record_key(design: Design, settings: SolverSettings | None = None) -> str:
    """The stable hex key of (design, settings); default settings when None."""
    text = canonical_json(design, settings if settings is not None else SolverSettings())
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:KEY_HEX_DIGITS]
