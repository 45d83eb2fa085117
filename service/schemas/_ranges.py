"""Read the numeric limits of request schemas, to state them in validation errors."""

from __future__ import annotations

import typing
from collections.abc import Iterable
from typing import Any

import annotated_types as at
from pydantic import BaseModel
from pydantic.fields import FieldInfo


def _num(value: Any) -> str:
    """A limit as written: whole numbers in full (65536, not 6.5536e+04), others short."""
    x = float(value)
    return str(int(x)) if x.is_integer() and abs(x) < 1e15 else f"{x:g}"


def _bounds(metadata: Iterable[Any]) -> tuple[str | None, str | None, int | None, int]:
    lo = hi = None
    max_len = None
    min_len = 0
    for m in metadata:
        if isinstance(m, at.Ge):
            lo = f"{_num(m.ge)} <= "
        elif isinstance(m, at.Gt):
            lo = f"{_num(m.gt)} < "
        elif isinstance(m, at.Le):
            hi = f" <= {_num(m.le)}"
        elif isinstance(m, at.Lt):
            hi = f" < {_num(m.lt)}"
        elif isinstance(m, at.MaxLen):
            max_len = m.max_length
        elif isinstance(m, at.MinLen):
            min_len = m.min_length
    return lo, hi, max_len, min_len


def _item_metadata(annotation: Any) -> list[Any]:
    """Constraints on the items of ``list[Annotated[float, Field(...)]]``."""
    out: list[Any] = []
    for arg in typing.get_args(annotation):
        if typing.get_origin(arg) is typing.Annotated:
            for extra in typing.get_args(arg)[1:]:
                out.extend(extra.metadata if isinstance(extra, FieldInfo) else [extra])
        else:
            out.extend(_item_metadata(arg))
    return out


def field_ranges(models: Iterable[type[BaseModel]]) -> dict[str, str]:
    """``{field name: "lo <= name <= hi"}`` over the models; a name must mean one range.
    A list whose items have a range has ``name.*`` too, an item's range alone (an item's
    error is not told its list's "1-1000 values")."""
    ranges: dict[str, str] = {}
    for model in models:
        for name, info in model.model_fields.items():
            lo, hi, max_len, min_len = _bounds(info.metadata)
            ilo, ihi, _, _ = _bounds(_item_metadata(info.annotation))
            parts = []
            if lo or hi:
                parts.append(f"{lo or ''}{name}{hi or ''}")
            if ilo or ihi:
                parts.append(f"each {ilo or ''}{name}{ihi or ''}")
                ranges[f"{name}.*"] = parts[-1]
            kinds = set(typing.get_args(info.annotation)) | {info.annotation}
            if max_len is not None:     # "" for a name was told "at most 64 characters"
                parts.append((f"{min_len}-{max_len} " if min_len else f"at most {max_len} ")
                             + ("characters" if str in kinds else "values"))
            if bool in kinds:
                parts.append("true or false")
            if not parts:
                continue
            text = "; ".join(parts)
            if ranges.get(name, text) != text:
                raise ValueError(f"field {name!r} has two ranges: {ranges[name]} / {text}")
            ranges[name] = text
    return ranges
