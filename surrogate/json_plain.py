"""JSON-safe copies of model files' contents, shared by every model file writer."""

from __future__ import annotations

import math
from typing import Any

import numpy as np


def plain_json(obj: Any) -> Any:
    """JSON-safe copy: numpy to Python, NaN/inf to None, tuples to lists."""
    if isinstance(obj, dict):
        return {str(k): plain_json(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        if obj and set(map(type, obj)) == {float} and all(map(math.isfinite, obj)):
            return list(obj)          # a row of finite floats, the bulk of a model file
        return [plain_json(v) for v in obj]
    if isinstance(obj, np.ndarray):
        if obj.dtype.kind in "iub" or (obj.dtype.kind == "f" and np.isfinite(obj).all()):
            return obj.tolist()       # Python ints, floats and bools already
        return plain_json(obj.tolist())
    if isinstance(obj, (np.floating, float)):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (np.bool_,)):
        return bool(obj)
    if obj is None or isinstance(obj, (str, int, bool)):
        return obj
    return str(obj)
