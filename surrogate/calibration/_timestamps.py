"""A logger's timestamp column (``Timestamp``, ``Date``, ``Epoch (s)``) read as a clock.

A logger writes the date and time of each reading: ISO 8601 (``2026-12-07T14:03:11``,
``2026-12-07 14:03:11.5``, ``...Z`` or ``+01:00``), a date with slashes or dots and the
time of day (``07/12/2026 14:03:11``, ``07.12.2026 14:03:11``), or epoch seconds (a
header naming the epoch, ``Epoch (s)``, ``Unix time (ms)``). The fit's time is
``time_s``: seconds since the pump started, the chamber at rest. What the physics uses
is the time between readings of one curve, never the day or the hour:

* with a time column the timestamp adds nothing: it is not read, and the report says so;
* without one, each curve's ``time_s`` is its readings' timestamps less its first
  reading's: the first reading is taken as the pump's start (at rest), as a logger's
  elapsed-time column counts it (_pump_clock.py warns when the gauge already reads
  pressure there);
* a date without a time of day (one specimen a day: benchmarks/lab_rig_sets.py N31)
  gives no time within a curve: not read, said.

Refused, naming the header and the row: a cell no format above reads, a plain number
under a header that names no epoch (epoch seconds or a spreadsheet's day count?), and a
slashed date read day-first and month-first with different times within a curve (a
curve across midnight: 07/12 to 08/12 is a day or a month). Until 2026-12-07 every such
column was an unknown column (N31, N38, N42, N43).
"""

from __future__ import annotations

import datetime as dt
import math
import re

from solver.number_text import is_number_text
from surrogate.calibration._errors import DataError
from surrogate.calibration._headers import split_header, unit_of

#: a header naming a logger's clock (lower case, spaces single)
STAMP_NAMES = ("timestamp", "time stamp", "date", "datetime", "date time", "date/time",
               "date and time", "datum", "zeitstempel", "datum/zeit", "datum zeit")
#: a header naming epoch seconds (a unit of time may follow: ``Epoch (ms)``)
EPOCH_NAMES = ("epoch", "epoch time", "unix time", "unix timestamp", "posix time")
FORMATS = ("ISO 8601 (2026-12-07T14:03:11), a date and the time of day (07/12/2026 "
           "14:03:11, 07.12.2026 14:03:11), or epoch seconds under a header 'Epoch (s)'")
_TIME = r"(?:[T ,]\s*(\d{1,2}):(\d{2})(?::(\d{2}(?:[.,]\d+)?))?)?"
_ZONE = r"\s*(Z|[+-]\d{2}:?\d{2})?"
# ASCII digits only (as every number the project reads: solver/number_text.py)
ISO = re.compile(r"\s*(\d{4})-(\d{1,2})-(\d{1,2})" + _TIME + _ZONE + r"\s*", re.ASCII)
DAY_MONTH = re.compile(r"\s*(\d{1,2})([/.])(\d{1,2})\2(\d{4})" + _TIME + r"\s*", re.ASCII)
MAX_ZONE_S = 14 * 3600     # the furthest UTC offset in use (UTC+14)


def stamp_kind(header: object) -> str | None:
    """'epoch' for a header naming epoch seconds, 'clock' for a date/timestamp header,
    else None."""
    if not isinstance(header, str):
        return None
    name = " ".join(header.lower().split())
    if name in STAMP_NAMES:
        return "clock"
    base, unit = split_header(header)
    base = " ".join(base.lower().split())
    if base in EPOCH_NAMES and (unit is None or (unit_of(unit) or ("",))[0] == "time"):
        return "epoch"
    return "clock" if base in STAMP_NAMES and unit is None else None


def _seconds(day: dt.date, hh: str | None, mm: str | None, ss: str | None) -> float:
    """Seconds since 1970-01-01 of a date and a time of day (UTC, no leap seconds)."""
    whole = (day - dt.date(1970, 1, 1)).days * 86400.0
    return whole + int(hh or 0) * 3600 + int(mm or 0) * 60 + float((ss or "0").replace(",", "."))


def _clock_time(hh: str | None, mm: str | None, ss: str | None) -> bool:
    """A time of day a clock shows (absent parts are 0): hours < 24, minutes and seconds
    < 60."""
    return (int(hh or 0) < 24 and int(mm or 0) < 60
            and float((ss or "0").replace(",", ".")) < 60)


def _zone_s(zone: str | None) -> float | None:
    """A UTC offset ('Z', '+01:00', '-0530') in seconds, None for one no clock uses."""
    if not zone or zone == "Z":
        return 0.0
    hours, minutes = int(zone[1:3]), int(zone[-2:])
    offset = hours * 3600 + minutes * 60
    if minutes >= 60 or offset > MAX_ZONE_S:
        return None
    return -offset if zone[0] == "-" else offset


def _date(y: int, m: int, d: int) -> dt.date | None:
    try:
        return dt.date(y, m, d)
    except ValueError:
        return None


def read_stamp(value: object, kind: str, factor: float, header: str, row: int
               ) -> tuple[float | None, float | None, bool]:
    """(seconds read day-first, seconds read month-first, has a time of day) of a cell;
    a reading that no calendar holds is None. Raises DataError for a cell no format
    reads."""
    text = str(value).strip() if value is not None else ""
    if kind == "epoch" and (isinstance(value, int | float) or is_number_text(text)):
        x = float(text) * factor
        if math.isfinite(x):
            return x, x, True
    m = ISO.fullmatch(text) if kind == "clock" else None
    if m:
        y, mo, d, hh, mm, ss, zone = m.groups()
        day, offset = _date(int(y), int(mo), int(d)), _zone_s(zone)
        if day is not None and offset is not None and _clock_time(hh, mm, ss):
            x = _seconds(day, hh, mm, ss) - offset
            return x, x, hh is not None
    m = DAY_MONTH.fullmatch(text) if kind == "clock" else None
    if m and _clock_time(*m.group(5, 6, 7)):
        a, sep, b, y, hh, mm, ss = m.groups()
        first = _date(int(y), int(b), int(a))
        second = _date(int(y), int(a), int(b)) if sep == "/" else None  # 07.12. day-first
        if first or second:
            return (None if first is None else _seconds(first, hh, mm, ss),
                    None if second is None else _seconds(second, hh, mm, ss),
                    hh is not None)
    said = f"not a time stamp: {text[:40]!r}" if text else "missing value"
    if kind == "clock" and (isinstance(value, int | float) or is_number_text(text)):
        said = (f"a number, {text[:40]!r}: epoch seconds or a spreadsheet's day count? "
                "(not guessed)")
    raise DataError(header, said, row, FORMATS)


def stamp_times(rows: list[dict], header: str, curve_of: list[str]) -> list[float] | None:
    """Each row's time (s) since its curve's first reading from the timestamp column
    ``header`` (``curve_of`` names each row's curve), or None when no cell holds a time
    of day (a date per specimen: not read). Raises DataError (``read_stamp``) for a cell
    no format reads, a date without a time beside ones with it, or a slashed date whose
    two readings give different times within a curve."""
    kind = stamp_kind(header) or "clock"
    _, unit = split_header(header)
    factor = (unit_of(unit) or ("", 1.0))[1] if kind == "epoch" and unit else 1.0
    read = [read_stamp(r.get(header), kind, factor, header, i)
            for i, r in enumerate(rows, start=1)]
    timed = [t for _, _, t in read]
    if not any(timed):
        return None
    if not all(timed):
        i = timed.index(False) + 1
        raise DataError(header, "a date without a time of day beside readings "
                        "with one", i, FORMATS)
    readings = [[x[k] for x in read] for k in (0, 1)]
    ways = [xs for xs in readings if None not in xs]
    if not ways:
        i = next(i for i, x in enumerate(read, 1) if x[0] is None) + 1
        raise DataError(header, "neither day/month nor month/day is a date "
                        "for every row", i, FORMATS)
    relative = [_since_first(xs, curve_of) for xs in ways]
    if any(abs(a - b) > 1e-6 for a, b in zip(relative[0], relative[-1], strict=True)):
        i = next(i for i, (a, b) in enumerate(zip(*relative, strict=True), 1)
                 if abs(a - b) > 1e-6)
        raise DataError(header, "a date read day/month and month/day gives "
                        "different times within a curve (across midnight)", i,
                        "ISO 8601 dates (2026-12-07T14:03:11)")
    return relative[0]


def _since_first(seconds: list[float], curve_of: list[str]) -> list[float]:
    """Each reading's seconds since the earliest reading of its curve."""
    first: dict[str, float] = {}
    for x, c in zip(seconds, curve_of, strict=True):
        first[c] = min(first.get(c, x), x)
    return [x - first[c] for x, c in zip(seconds, curve_of, strict=True)]


def clock_columns_read(rows: list, time_header: str = "time_s"
                       ) -> tuple[list, tuple[dict[str, str | None], ...]]:
    """``rows`` with each timestamp column taken out: read as ``time_s`` when the rows
    have none (``stamp_times``), else not read; and, per such column, how it was read
    ({'header', 'read_as': 'time_s' or None, 'reading': a sentence}). Rows that are not
    all objects are returned as they are (the caller refuses them)."""
    if not all(isinstance(r, dict) for r in rows):
        return rows, ()
    headers = [h for h in dict.fromkeys(k for r in rows for k in r) if stamp_kind(h)]
    notes = []
    for header in headers:
        has_time = any("time_s" in r for r in rows)
        times = None if has_time else stamp_times(
            rows, header, [f"{r.get('curve_id')}\x00{r.get('run')}" for r in rows])
        rows = [{k: v for k, v in r.items() if k != header} for r in rows]
        if times is not None:
            rows = [dict(r, time_s=t) for r, t in zip(rows, times, strict=True)]
            said = ("read as time_s: each curve's seconds since its first reading (taken "
                    "as the pump's start)")
        elif has_time:
            said = f"not read: a logger's clock; the time is `{time_header}`"
        else:
            said = "not read: a date without a time of day (no time within a curve)"
        notes.append({"header": header, "read_as": "time_s" if times is not None else None,
                      "reading": f"`{header}` {said}"})
    return rows, tuple(notes)
