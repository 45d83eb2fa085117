"""Measured data: validated rows -> ``Observations`` (numpy arrays, one row per observation).

The contract is in docs/measured-data.md. Required columns: curve_id, L_mm, t_mm,
body_material, membrane_material, pressure_pa, angle_deg. Optional: T_mm, b_mm (standard
design's defaults, 1 and 1.8 mm), h_mm (0.15 mm), time_s, flow_ul_s, angle_sd_deg, force_mn,
the pump's dispensed volume (``volume_ul``: _measured_volume.py) and the pump's own log
(``pump``: load, hold or unload). Every row is checked before
anything is built, so a bad file is never half-loaded.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from solver.bounded_read import read_bounded
from solver.byte_order_mark import bom_encoding, byte_line
from solver.design import LIMITS_MM, material_from_input
from solver.errors import InputError
from solver.number_text import NUMBER_FORM, is_number_text
from solver.plain_text import PRINTABLE_WORDS, hidden_character
from solver.store.integrity import HDF5_HEAD_BYTES, looks_like_hdf5
from surrogate.calibration._angle_stop import AngleStop
from surrogate.calibration._csv_dialect import (
    decimal_commas,
    is_blank,
    named_separator,
    separator,
)
from surrogate.calibration._errors import DataError
from surrogate.calibration._extra_columns import extra_columns_read
from surrogate.calibration._headers import (
    UNITS,
    Reading,
    allowed_units,
    canonical_unit,
    header_form,
    read_headers,
)
from surrogate.calibration._history import directions, injected_volume_ul, pump_switches
from surrogate.calibration._layouts import (
    CLOCK_HOW,
    header_below_text,
    is_clock,
    layout_error,
    one_column_per_specimen,
    text_above_header,
    text_below_readings,
)
from surrogate.calibration._measured_volume import (
    check_runs,
    disagreements,
    is_absent,
    volume_directions,
    written_step_ul,
)
from surrogate.calibration._pump_clock import clock_warning
from surrogate.calibration._timestamps import clock_columns_read
from surrogate.json_repeats import loads_with_repeats
from surrogate.measured_cell import CELL_WORDS, cell_problem
from surrogate.volume_control import MAX_FLOW_UL_S, MIN_FLOW_UL_S

REQUIRED = ("curve_id", "L_mm", "t_mm", "body_material", "membrane_material",
            "pressure_pa", "angle_deg")
OPTIONAL = ("T_mm", "b_mm", "h_mm", "time_s", "flow_ul_s", "angle_sd_deg", "force_mn",
            "volume_ul")
#: optional columns that, once present, need a value on every row (the pump's record)
EVERY_ROW = ("time_s", "flow_ul_s", "volume_ul")
#: the pump's own log, optional: what it did in the interval ending at each reading (since
#: the previous one; the first reading: since the start). Given, it is the history
#: (``Observations.direction``) instead of what the readings suggest (_history.py): a
#: leaking chamber's gauge and bend fall during a hold as if it were unloading.
PUMP_COLUMN = "pump"
PUMP_STATES = {"load": 1.0, "hold": 0.0, "unload": -1.0}
#: the run of a specimen, optional: a lab loads one specimen several times. With it a
#: curve is one run (curve_id and run), curve_id names the specimen, and its runs count
#: as one specimen wherever specimens are the units (``Observations.specimen``). A
#: header named by any of ``RUN_NAMES`` (any case) is this column.
RUN_COLUMN = "run"
RUN_NAMES = ("run", "cycle", "repeat", "repetition", "trial")
#: a header naming the specimen (any case, '_' a space), read as curve_id when the file
#: has no curve_id: a lab's 'Sample' or 'Specimen' column (until 2026-12-07 "curve_id:
#: required column is missing": benchmarks/lab_rig_sets.py N40)
CURVE_ID_NAMES = ("specimen", "sample", "specimen id", "sample id")
DEFAULTS = {"T_mm": 1.0, "b_mm": 1.8, "h_mm": 0.15}
MIN_POINTS_PER_CURVE = 4
MAX_ROWS = 200_000
#: the largest data file read (MAX_ROWS rows of ~150 bytes is 30 MB): a file is read up to
#: one byte past it, so /dev/zero or a stray 10 GB file is refused without filling memory
MAX_FILE_BYTES = 64 * 2**20

# column -> (lowest, highest, inclusive lower bound?) for numeric checks; a curve's flow
# rate is the syringe pump's, whose range is one table (surrogate.volume_control): a flow
# of 0 injects nothing (a curve without a pump leaves the column out)
RANGES: dict[str, tuple[float, float, bool]] = {
    # the design's lengths as a design is checked (solver.design.LIMITS_MM): a row of
    # L_mm 5e-324 was calibrated against `paper`, which takes any L, where every FE-based
    # model refused it
    **{name: (*LIMITS_MM[name], True) for name in ("L_mm", "t_mm", "T_mm", "b_mm", "h_mm")},
    "pressure_pa": (-1e5, 1e6, True), "angle_deg": (-720.0, 720.0, True),
    "time_s": (0.0, 1e6, True), "flow_ul_s": (MIN_FLOW_UL_S, MAX_FLOW_UL_S, True),
    "angle_sd_deg": (0.0, 360.0, False), "force_mn": (-1e6, 1e6, True),
    "volume_ul": (0.0, 1e6, True),
}


@dataclass(frozen=True, eq=False)
class Observations:
    """Validated measurements; arrays have one entry per row, sorted by curve then by time
    (or file order when there is no time_s: a lab writes a curve in the order it took it,
    loading, holds and unloading included). ``curve`` and ``family`` index ``curve_ids``
    and ``families``; ``group`` indexes design+flow groups (replicates share a group);
    ``direction`` is +1 loading, -1 unloading, 0 hold (_history.py); ``warnings`` what
    looked wrong but was accepted (kPa-looking pressures, duplicated rows)."""

    curve_ids: tuple[str, ...]
    families: tuple[tuple[str, str, float, float, float], ...]
    curve: np.ndarray
    family: np.ndarray
    group: np.ndarray
    L_mm: np.ndarray
    t_mm: np.ndarray
    pressure_pa: np.ndarray
    angle_deg: np.ndarray
    time_s: np.ndarray
    flow_ul_s: np.ndarray
    angle_sd_deg: np.ndarray
    force_mn: np.ndarray
    sha256: str
    direction: np.ndarray = None  # type: ignore[assignment]
    warnings: tuple[str, ...] = ()
    #: the pump's injected volume at each reading (ul; NaN without time_s and flow_ul_s
    #: or a measured volume), from the whole history of each curve
    #: (_history.injected_volume_ul), or the measured one (``measured_volume_ul``) where
    #: there is no history or it disagrees (_measured_volume.py)
    volume_ul: np.ndarray = None  # type: ignore[assignment]
    #: where the pump changed state between readings (_history.pump_switches): per row
    #: and switch, the injected volume (ul) one reading interval of shift moves; computed
    #: on the whole history, so rows dropped later keep their switches
    switch_after: np.ndarray = None  # type: ignore[assignment]
    switch_at: np.ndarray = None  # type: ignore[assignment]
    switch_names: tuple[str, ...] = ()
    #: the history is the pump's own log (the ``pump`` column), not read off the readings
    pump_logged: bool = False
    #: the headers read as a canonical column in another unit or spelling
    #: (``Pressure (kPa)`` as pressure_pa x 1000: _headers.py), their values converted
    columns_read: tuple[Reading, ...] = ()
    #: the specimen of each row: its curves are the runs of one specimen (the ``run``
    #: column: the same specimen loaded again), at any flow rate; without ``run`` every
    #: curve is a specimen of its own. Specimens, not runs, are the independent units
    #: of the scatter between specimens, the held-out folds and the noise floor.
    specimen: np.ndarray = None  # type: ignore[assignment]
    #: the ``volume_ul`` column (ul; NaN without it), the step of its last written digit
    #: (ul) and, per row, whether ``volume_ul`` is the measured volume
    measured_volume_ul: np.ndarray = None  # type: ignore[assignment]
    volume_step_ul: float = 0.0
    volume_measured: np.ndarray = None  # type: ignore[assignment]
    #: the runs of one specimen, the data's only one, taken as replicates of each other
    #: (``as_replicates``): each run is then a unit of its own
    runs_as_replicates: bool = False
    #: a logger's timestamp columns and how each was read (_timestamps.py): as time_s
    #: (no time column), or not (a time column, or a date without a time of day)
    clock_columns: tuple[dict[str, str | None], ...] = ()
    #: the angle sensor's stop found in the readings (_angle_stop.py; None: none), and
    #: whether they were searched (once, on the whole history: rows taken out keep it)
    angle_stop: AngleStop | None = None
    angle_stop_read: bool = False
    #: a logger's columns of nothing the calibration reads, taken out (_extra_columns.py):
    #: {'header', 'read_as': None, 'reading'}
    columns_not_read: tuple[dict[str, str | None], ...] = ()

    def __post_init__(self) -> None:
        if self.specimen is None:
            object.__setattr__(self, "specimen", np.asarray(self.curve).copy())
        if self.measured_volume_ul is None:
            object.__setattr__(self, "measured_volume_ul", np.full(self.n, np.nan))
        measured = not is_absent(self.measured_volume_ul)
        by_history = self.has_time and self.has_flow
        if not self.angle_stop_read:
            stop = AngleStop.find(self.curve, self.curve_ids, self.group, self.time_s,
                                  self.pressure_pa, self.angle_deg,
                                  self.direction if self.pump_logged else None)
            object.__setattr__(self, "angle_stop", stop)
            object.__setattr__(self, "angle_stop_read", True)
            if stop is not None:
                object.__setattr__(self, "warnings", self.warnings + (stop.warning(),))
        if self.direction is None:
            object.__setattr__(self, "direction", volume_directions(
                self.curve, self.measured_volume_ul, self.volume_step_ul)
                if measured and not by_history else
                directions(self.curve, self.pressure_pa, self.angle_deg, self.time_s,
                           self.group, None if self.angle_stop is None
                           else self.angle_stop.pinned))
        if self.volume_ul is None:
            self._take_volume(measured, by_history)
        if self.volume_measured is None:
            object.__setattr__(self, "volume_measured", np.full(self.n, measured))
        if self.switch_after is None:
            after, at, names = (np.zeros((self.n, 0)), np.zeros((self.n, 0)), ())
            if self.has_volume and by_history:
                keys = [self._program_key(c) for c in range(self.n_curves)]
                after, at, names = pump_switches(self.curve, self.time_s, self.flow_ul_s,
                                                 self.direction, self.volume_ul, keys)
                after, at, names = _without_rows(after, at, names, self.volume_measured)
            object.__setattr__(self, "switch_after", after)
            object.__setattr__(self, "switch_at", at)
            object.__setattr__(self, "switch_names", names)

    def _take_volume(self, measured: bool, by_history: bool) -> None:
        """The injected volume: the pump history's (time_s, flow_ul_s); without them the
        measured one; with both, the measured one on the curves where they disagree
        (their history then read off the measured volume, unless the pump logged it),
        with a warning (_measured_volume.py)."""
        pump = injected_volume_ul(self.curve, self.time_s, self.flow_ul_s, self.direction)
        if not measured:
            object.__setattr__(self, "volume_ul", pump)
            return
        if not by_history:
            object.__setattr__(self, "volume_ul", self.measured_volume_ul.copy())
            return
        off, words = disagreements(self.curve, self.curve_ids, self.measured_volume_ul,
                                   pump, self.volume_step_ul)
        object.__setattr__(self, "volume_ul", np.where(off, self.measured_volume_ul, pump))
        object.__setattr__(self, "volume_measured", off)
        object.__setattr__(self, "warnings", self.warnings + tuple(words))
        if not self.pump_logged:
            object.__setattr__(self, "direction", np.where(off, volume_directions(
                self.curve, self.measured_volume_ul, self.volume_step_ul), self.direction))

    @property
    def volume_source(self) -> str:
        """Where the injected volume comes from, in words (the report's data)."""
        if not self.has_volume:
            return "none"
        if not np.any(self.volume_measured):
            return "pump history"
        return "measured" if np.all(self.volume_measured) else "pump history and measured"

    def _program_key(self, c: int) -> str:
        """Replicates of one design at one flow rate: one pump program."""
        row = int(np.flatnonzero(self.curve == c)[0])
        return (f"{int(self.family[row])},{self.L_mm[row]:g},{self.t_mm[row]:g},"
                f"{self.flow_ul_s[row]:g}")

    @property
    def has_volume(self) -> bool:
        """Every reading's injected volume is known (time_s and flow_ul_s, or
        volume_ul)."""
        return bool(self.n and np.all(np.isfinite(self.volume_ul)))

    @property
    def n(self) -> int:
        return int(self.angle_deg.size)

    @property
    def n_curves(self) -> int:
        return len(self.curve_ids)

    @property
    def n_specimens(self) -> int:
        return int(np.unique(self.specimen).size)

    def as_replicates(self) -> Observations:
        """The runs of the data's one specimen taken as replicates of each other: each run
        a unit of its own (the held-out folds, the noise floor, the replicate-shared
        residual), as if the file named them as curves without the ``run`` column. A lab
        that loads its one actuator several times is answered, not refused: the floor is
        then the runs' repeatability, and what is fitted describes this specimen, not its
        batch (a warning says so)."""
        specimen_id = self.curve_ids[0].rsplit(" run ", 1)[0]
        said = (f"curve_id: the {self.n_curves} curves are runs of one specimen "
                f"({specimen_id!r}), taken as replicates of each other: the noise floor is "
                "the runs' repeatability, and what is fitted describes this specimen, not "
                "its batch (a second specimen tells them apart)")
        return replace(self, specimen=np.asarray(self.curve).copy(),
                       warnings=self.warnings + (said,), runs_as_replicates=True)

    def curve_specimen(self) -> np.ndarray:
        """Specimen index of each curve."""
        out = np.zeros(self.n_curves, dtype=int)
        out[self.curve] = self.specimen
        return out

    def replicate_unit(self) -> np.ndarray:
        """Per row, one index per specimen within its replicate group (design and flow
        rate): a specimen's runs at one flow rate are one unit of the scatter between
        specimens; the curve itself without runs."""
        _, unit = np.unique(np.stack([self.specimen, self.group]), axis=1,
                            return_inverse=True)
        return unit.ravel()

    @property
    def has_time(self) -> bool:
        return bool(np.all(np.isfinite(self.time_s)))

    @property
    def has_flow(self) -> bool:
        return bool(np.all(np.isfinite(self.flow_ul_s)))

    @property
    def flow_varies(self) -> bool:
        if not self.has_flow:
            return False
        return bool(np.ptp(self.flow_ul_s) > 1e-6 * max(1.0, float(np.max(self.flow_ul_s))))

    def curve_family(self) -> np.ndarray:
        """Family index of each curve."""
        out = np.zeros(self.n_curves, dtype=int)
        out[self.curve] = self.family
        return out

    def curve_design(self, i: int) -> dict[str, object]:
        """The design and flow of curve i as plain data."""
        row = int(np.flatnonzero(self.curve == i)[0])
        body, membrane, T, b, h = self.families[int(self.family[row])]
        return {"curve_id": self.curve_ids[i], "L_mm": float(self.L_mm[row]),
                "t_mm": float(self.t_mm[row]), "T_mm": T, "b_mm": b, "h_mm": h,
                "body_material": body, "membrane_material": membrane,
                "flow_ul_s": float(self.flow_ul_s[row])}

    def subset(self, curves: np.ndarray) -> Observations:
        """The observations of the given curve indices (families keep their indices)."""
        return self.rows(np.isin(self.curve, curves))

    def rows(self, keep: np.ndarray) -> Observations:
        """The observations of the rows where ``keep`` (curves left empty vanish)."""
        keep = np.asarray(keep, bool)
        old = np.unique(self.curve[keep])
        remap = np.full(self.n_curves, -1)
        remap[old] = np.arange(old.size)
        _, group = np.unique(self.group[keep], return_inverse=True)
        _, specimen = np.unique(self.specimen[keep], return_inverse=True)
        return Observations(
            tuple(self.curve_ids[i] for i in old), self.families, remap[self.curve[keep]],
            self.family[keep], group, self.L_mm[keep], self.t_mm[keep],
            self.pressure_pa[keep], self.angle_deg[keep], self.time_s[keep],
            self.flow_ul_s[keep], self.angle_sd_deg[keep], self.force_mn[keep], self.sha256,
            self.direction[keep], self.warnings, self.volume_ul[keep],
            self.switch_after[keep], self.switch_at[keep], self.switch_names,
            self.pump_logged, self.columns_read, specimen.ravel(),
            self.measured_volume_ul[keep], self.volume_step_ul, self.volume_measured[keep],
            self.runs_as_replicates, self.clock_columns,
            None if self.angle_stop is None else self.angle_stop.rows(keep), True,
            self.columns_not_read)

    def design(self, i: int):
        """The nominal Design of curve i (the solver's type; W and lengths at defaults)."""
        from solver.design import Design
        from solver.design_space import named_material

        d = self.curve_design(i)
        return Design(L_mm=d["L_mm"], t_mm=d["t_mm"], T_mm=d["T_mm"], b_mm=d["b_mm"],
                      h_mm=d["h_mm"], body_material=named_material(d["body_material"]),
                      membrane_material=named_material(d["membrane_material"]))

    def padded_order(self) -> np.ndarray:
        """(n_curves, max points) row indices in curve order, -1 padded (rows are sorted)."""
        counts = np.bincount(self.curve, minlength=self.n_curves)
        out = np.full((self.n_curves, int(counts.max())), -1, dtype=int)
        starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
        for i, (s, k) in enumerate(zip(starts, counts, strict=False)):
            out[i, :k] = np.arange(s, s + k)
        return out


def _number(value: object, column: str, row: int) -> float:
    if isinstance(value, bool):
        raise _cell_error(column, f"not a number: {value!r}", row)
    if value is None or (isinstance(value, str) and value.strip() == ""):
        return math.nan
    try:
        x = float(value)  # type: ignore[arg-type]
    except OverflowError:
        raise _cell_error(column, "number too large: " + _short(value), row) from None
    except (TypeError, ValueError):   # '0x8', '1,5' in a comma-separated file: the forms
        how = (f"a clock: write {CLOCK_HOW}" if column == "time_s" and is_clock(value)
               else f"numbers in {NUMBER_FORM}")
        raise _cell_error(column, f"not a number: {_short(value)} ({how})", row) from None
    if isinstance(value, str) and not is_number_text(value):   # '1_0' (10), '٧' (7)
        raise _cell_error(column, f"not a number: {_short(value)} (numbers in {NUMBER_FORM})",
                          row)
    if not math.isfinite(x):
        raise _cell_error(column, "not a finite number: " + _short(value), row)
    return x


def range_words(column: str) -> str:
    """What a cell of ``column`` may hold, in words: its range (``RANGES``; units in the
    column's name), or for ``curve_id`` any text naming the curve."""
    if column == "curve_id":
        return ("any non-empty text naming the curve (one specimen at one flow rate): "
                + PRINTABLE_WORDS)
    lo, hi, inclusive = RANGES[column]
    return f"{lo:g} {'<=' if inclusive else '<'} {column} <= {hi:g}"


def _cell_error(column: str, message: str, row: int) -> DataError:
    """A refused cell of ``column`` in data row ``row``, with what the cell may hold."""
    return DataError(column, message, row, range_words(column))


def _short(value: object) -> str:
    text = repr(value)
    return text if len(text) <= 40 else f"{text[:30]}... ({len(text)} characters)"


def _check_range(x: float, column: str, row: int) -> None:
    lo, hi, inclusive = RANGES[column]
    ok = (lo <= x if inclusive else lo < x) and x <= hi
    if not ok:
        what = "negative" if x < 0 and lo >= 0 else "out of range"
        raise _cell_error(column, f"{what}: {x:g}", row)


def observations_from_rows(rows: list[dict[str, object]], strict: bool = False
                           ) -> Observations:
    """Validate rows (dicts of column -> value, as read from CSV or JSON) and build the
    arrays. Raises DataError naming the row (1-based) and the column. What looks wrong
    but is usable (pressures that look like kPa, duplicated rows) is a warning in
    ``Observations.warnings``; with ``strict`` it is a DataError instead."""
    if not isinstance(rows, list) or not rows:
        raise DataError("rows", "no data rows", None, "at least one curve of "
                        f"{MIN_POINTS_PER_CURVE} points")
    if len(rows) > MAX_ROWS:
        raise DataError("rows", f"{len(rows)} rows", None, f"at most {MAX_ROWS}")
    # first: a list of lists of rows (`[[{...}, ...]]`) was "curve_id: required column is
    # missing", its first row's columns read as none
    not_object = next((i for i, r in enumerate(rows, 1) if not isinstance(r, dict)), None)
    if not_object is not None:
        raise DataError("rows", "a row must be an object of column -> value", not_object,
                        "an object of the columns " + ", ".join(REQUIRED + OPTIONAL))
    rows = [_plain_keys(r, i) if isinstance(r, dict) else r for i, r in enumerate(rows, 1)]
    headers = list(dict.fromkeys(k for r in rows if isinstance(r, dict) for k in r))
    try:
        readings = read_headers(headers, tuple(RANGES)) | specimen_reading(headers)
    except DataError as exc:     # a units row, a clock for a unit: said so (_layouts.py)
        raise layout_error(exc, rows[0] if isinstance(rows[0], dict) else None) from None
    converted = {r.column: r for r in readings.values() if r.header != r.column}
    if converted:       # the file's names -> the canonical columns, values converted below
        rename = {r.header: r.column for r in converted.values()}
        rows = [{rename.get(k, k): v for k, v in r.items()} if isinstance(r, dict) else r
                for r in rows]
    rows = _run_named(rows, headers)
    time_header = converted["time_s"].header if "time_s" in converted else "time_s"
    rows, clocks = clock_columns_read(rows, time_header)
    known = set(REQUIRED) | set(OPTIONAL) | {PUMP_COLUMN, RUN_COLUMN}
    columns = set(rows[0]) if isinstance(rows[0], dict) else set()
    for name in REQUIRED:
        if name not in columns:     # a logger's text above the header, sent as rows?
            below = header_below_text([list(r.values()) if isinstance(r, dict) else []
                                       for r in rows], REQUIRED, tuple(RANGES))
            if below is not None and columns:
                raise text_above_header([", ".join(map(str, rows[0]))] * (below + 1))
            raise _missing(name, columns)
    rows, not_read = extra_columns_read(rows, known)   # (text above the header: refused)
    present = [c for c in OPTIONAL if c in columns]
    parsed = []
    written: list[float] = []    # the volume_ul column as written (its last digit)
    for i, raw in enumerate(rows, start=1):
        extra = sorted(set(raw) - known)
        if extra:       # named as the file names it, cut short (a 10,000-character key)
            name = str(extra[0])
            raise DataError(name if len(name) <= 64 else f"{name[:40]}... ({len(name)} "
                            "characters)", "unknown column", i,
                            ", ".join(REQUIRED + OPTIONAL + (PUMP_COLUMN, RUN_COLUMN)))
        rec: dict[str, object] = {}
        cid = raw.get("curve_id")
        if cid is None or str(cid).strip() == "":
            raise _cell_error("curve_id", "empty curve id", i)
        rec["curve_id"] = _label(cid, "curve_id", i)
        if RUN_COLUMN in columns:        # one run of the specimen curve_id
            rec["specimen"] = rec["curve_id"]
            rec["curve_id"] = f"{rec['curve_id']} run {_run_label(raw.get(RUN_COLUMN), i)}"
        for name in ("body_material", "membrane_material"):
            value = str(raw.get(name, "") or "").strip()
            try:    # a preset, or one with every mu scaled (pdms_1_10*1.3), as a design's
                rec[name] = material_from_input(value, name).id
            except InputError as exc:
                raise DataError(name, exc.detail, i, exc.allowed) from None
        try:
            for name in ("L_mm", "t_mm", "pressure_pa", "angle_deg"):
                x = _number(raw.get(name), name, i) * _factor(converted, name)
                if math.isnan(x):
                    raise _cell_error(name, "missing value", i)
                _check_range(x, name, i)
                rec[name] = x
            for name in OPTIONAL:
                if name == "volume_ul" and name not in present:
                    continue    # absent: not in the row (its sha256 as before the column)
                x = (_number(raw.get(name), name, i) * _factor(converted, name)
                     if name in present else math.nan)
                if math.isnan(x):
                    if name in present and name in EVERY_ROW:
                        raise _cell_error(name, "missing value (the column is present, so "
                                          "every row needs one)", i)
                    x = DEFAULTS.get(name, math.nan)
                else:
                    _check_range(x, name, i)
                    if name == "volume_ul":
                        written.append(x / _factor(converted, name))
                rec[name] = x
        except DataError as exc:
            raise _as_written(exc, converted) from None
        if PUMP_COLUMN in columns:
            rec[PUMP_COLUMN] = _pump_state(raw.get(PUMP_COLUMN), i)
        parsed.append(rec)
    parsed, warnings = _suspicious(parsed, present, strict)
    if PUMP_COLUMN in columns:
        present = present + [PUMP_COLUMN]
    step = written_step_ul(written, _factor(converted, "volume_ul")) if written else 0.0
    try:
        obs = _build(parsed, present, tuple(warnings), tuple(converted.values()), step)
    except DataError as exc:     # a measured volume's run, named as the file names it
        raise _as_written(exc, converted) from None
    obs = replace(obs, clock_columns=clocks) if clocks else obs
    obs = replace(obs, columns_not_read=not_read) if not_read else obs
    if strict and len(obs.warnings) > len(warnings):   # the pump's log, a sensor's stop
        column, _, message = obs.warnings[len(warnings)].partition(": ")
        raise DataError(column, message + " (refused: strict)", None, "data without "
                        "warnings (drop --strict to accept with a warning)")
    return obs


def _factor(converted: dict[str, Reading], column: str) -> float:
    """What the values of ``column`` are multiplied by (its header's unit -> its own)."""
    return converted[column].factor if column in converted else 1.0


def _as_written(exc: DataError, converted: dict[str, Reading]) -> DataError:
    """A refused cell of a converted column, named by the file's header (over HTTP the
    field is ``rows.<i>.<the key sent>``) and saying how it was read."""
    reading = converted.get(exc.column)
    if reading is None:
        return exc
    return DataError(reading.header, f"{exc.detail.removeprefix(f'row {exc.row}: ')} "
                     f"({reading.words()})", exc.row, exc.allowed)


def specimen_reading(headers: list) -> dict[str, Reading]:
    """{header: Reading as curve_id} for a header of ``CURVE_ID_NAMES`` ('Sample') in a
    file without curve_id; empty otherwise. Two such headers are a DataError naming
    both."""
    if "curve_id" in headers:
        return {}
    named = [h for h in headers if isinstance(h, str)
             and " ".join(h.replace("_", " ").lower().split()) in CURVE_ID_NAMES]
    if len(named) > 1:
        raise DataError(named[1], f"{named[0]!r} and {named[1]!r} both name the specimen",
                        None, "one column naming the specimen (curve_id)")
    return {named[0]: Reading(named[0], "curve_id", 1.0)} if named else {}


def _run_named(rows: list, headers: list) -> list:
    """``rows`` with a header of ``RUN_NAMES`` ('Cycle', 'Repeat') named ``run``; two such
    headers are a DataError naming both."""
    named = [h for h in headers if isinstance(h, str) and h.strip().lower() in RUN_NAMES]
    if len(named) > 1:
        raise DataError(named[1], f"{named[0]!r} and {named[1]!r} both name the run of a "
                        "specimen", None, "one run column")
    if not named or named[0] == RUN_COLUMN:
        return rows
    return [{(RUN_COLUMN if k == named[0] else k): v for k, v in r.items()}
            if isinstance(r, dict) else r for r in rows]


def _label(value: object, column: str, row: int) -> str:
    """A free-text cell (a curve's id, a run's label) stripped, refused when it holds a
    character a terminal or a page would obey or hide (``solver.plain_text``): the
    label is echoed in every report and error."""
    text = str(value).strip()
    hidden = hidden_character(text)
    if hidden is not None:
        raise DataError(column, f"a control or invisible character {hidden} in "
                        f"{_short(text)}", row, PRINTABLE_WORDS)
    return text


def _run_label(value: object, row: int) -> str:
    """A run's label as text ('2' of 2, 2.0 or ' 2 '); an empty one is a DataError."""
    if isinstance(value, float) and value.is_integer():
        value = int(value)
    text = "" if value is None or isinstance(value, bool) else str(value).strip()
    if text.replace(".", "", 1).isdecimal() and float(text).is_integer():
        text = str(int(float(text)))
    if text:
        text = _label(text, RUN_COLUMN, row)
    if not text or len(text) > 40:
        raise DataError(RUN_COLUMN, "missing run" if not text else "run label of "
                        f"{len(text)} characters", row, "a run label (1, 2, 3 or any short "
                        "text) in every row once the column is present")
    return text


def _pump_state(value: object, row: int) -> float:
    """+1 / 0 / -1 from the pump column's load / hold / unload (any case, spaces)."""
    text = str(value).strip().lower() if isinstance(value, str) else None
    if text not in PUMP_STATES:
        raise DataError(PUMP_COLUMN, "not a pump state: " + _short(value), row,
                        " or ".join(PUMP_STATES) + " (what the pump did since the previous "
                        "reading)")
    return PUMP_STATES[text]


KPA_MAX_PA = 30.0   # no actuator of this kind bends visibly below 30 Pa
KPA_MIN_ANGLE_DEG = 3.0


def _suspicious(parsed: list[dict[str, object]], present: list[str], strict: bool
                ) -> tuple[list[dict[str, object]], list[str]]:
    """Drop exact duplicate rows and flag kPa-looking pressures: warnings, or DataError
    when ``strict``."""
    warnings: list[tuple[str, str, int | None]] = []
    keys = [json.dumps(rec, sort_keys=True, default=str) for rec in parsed]
    rows_of: dict[str, list[int]] = {}
    for i, rec in enumerate(parsed):
        rows_of.setdefault(str(rec["curve_id"]), []).append(i)
    drop: set[int] = set()
    factors: dict[str, int] = {}
    for cid, idx in rows_of.items():
        if "time_s" in present:  # the same reading at the same time: a copy
            seen: set[str] = set()
            for i in idx:
                if keys[i] in seen:
                    drop.add(i)
                seen.add(keys[i])
            if len(seen) < len(idx):
                factors[cid] = round(len(idx) / len(seen))
            continue
        seq = [keys[i] for i in idx]  # without time: the curve repeats as a whole
        for k in range(len(seq) // MIN_POINTS_PER_CURVE, 1, -1):
            if len(seq) % k == 0 and seq == seq[:len(seq) // k] * k:
                drop.update(idx[len(seq) // k:])
                factors[cid] = k
                break
    kept = [rec for i, rec in enumerate(parsed) if i not in drop]
    if drop:
        first = min(drop)
        curves = sorted(factors)
        warnings.append(("rows", f"{len(drop)} duplicated rows (every column equal; x"
                         f"{max(factors.values())} in curve_id "
                         f"{', '.join(map(repr, curves[:3]))}{' ...' if len(curves) > 3 else ''}"
                         f", first copy at row {first + 1}): duplicates dropped", first + 1))
    by_curve: dict[str, list[dict[str, object]]] = {}
    for rec in kept:
        by_curve.setdefault(str(rec["curve_id"]), []).append(rec)
    p_max = max(abs(float(r["pressure_pa"])) for r in kept)  # type: ignore[arg-type]
    a_max = max(abs(float(r["angle_deg"])) for r in kept)  # type: ignore[arg-type]
    if 0.0 < p_max < KPA_MAX_PA and a_max > KPA_MIN_ANGLE_DEG:
        warnings.append(("pressure_pa", f"pressures reach only {p_max:g} Pa while angles "
                         f"reach {a_max:.1f} deg: they look like kPa (x1000 gives "
                         f"{1000 * p_max:g} Pa); convert pressure_pa to Pa", None))
    else:
        warnings += _mixed_units(kept)
    clock = clock_warning(by_curve) if "time_s" in present and "flow_ul_s" in present \
        else None
    if clock:
        warnings.append(clock)
    if strict and warnings:
        column, message, row = warnings[0]
        raise DataError(column, message + " (refused: strict)", row,
                        "data without warnings (drop --strict to accept with a warning)")
    return kept, [f"{c}: {m}" for c, m, _ in warnings]


def _mixed_units(kept: list[dict[str, object]]) -> list[tuple[str, str, int | None]]:
    """Pressures in kPa beside pressures in Pa: a curve whose pressures stay below
    ``KPA_MAX_PA`` while it bends (when others do not), or, within a curve, a step of
    about x1000 between neighbouring rows (one below ``KPA_MAX_PA``) while the angle
    stays about the same (unloading to zero pressure straightens the actuator too)."""
    out: list[tuple[str, str, int | None]] = []
    rows: dict[str, list[tuple[int, float, float]]] = {}
    for i, rec in enumerate(kept):
        rows.setdefault(str(rec["curve_id"]), []).append(
            (i, abs(float(rec["pressure_pa"])), abs(float(rec["angle_deg"]))))  # type: ignore
    small = [cid for cid, r in rows.items()
             if 0.0 < max(p for _, p, _ in r) < KPA_MAX_PA
             and max(a for _, _, a in r) > KPA_MIN_ANGLE_DEG]
    if small:
        top = max(p for _, p, _ in rows[small[0]])
        out.append(("pressure_pa", f"curve_id {small[0]!r}"
                    f"{f' (and {len(small) - 1} more)' if len(small) > 1 else ''} reaches "
                    f"only {top:g} Pa while it bends and other curves reach more: mixed "
                    f"units? (x1000 gives {1000 * top:g} Pa); convert pressure_pa to Pa",
                    rows[small[0]][0][0] + 1))
    for cid, r in rows.items():
        for (_, p0, a0), (i, p1, a1) in zip(r, r[1:]):
            lo, hi = min(p0, p1), max(p0, p1)
            a_lo, a_hi = (a0, a1) if p0 < p1 else (a1, a0)
            # a kPa reading bends like its Pa neighbour; a curve unloaded to zero does not
            bends = a_lo > max(KPA_MIN_ANGLE_DEG, 0.5 * a_hi)
            if 0.0 < lo < KPA_MAX_PA and 300.0 <= hi / lo <= 3000.0 and bends:
                out.append(("pressure_pa", f"row {i + 1}: curve_id {cid!r} jumps from "
                            f"{p0:g} to {p1:g} Pa (about x1000): mixed kPa and Pa? convert "
                            "pressure_pa to Pa", i + 1))
                break
    return out


def _build(parsed: list[dict[str, object]], present: list[str],
           warnings: tuple[str, ...] = (), columns_read: tuple[Reading, ...] = (),
           volume_step_ul: float = 0.0) -> Observations:
    by_curve: dict[str, list[int]] = {}
    for i, rec in enumerate(parsed):
        by_curve.setdefault(str(rec["curve_id"]), []).append(i)
    design_keys = ("L_mm", "t_mm", "T_mm", "b_mm", "h_mm", "body_material",
                   "membrane_material")
    for cid, idx in by_curve.items():
        first = parsed[idx[0]]
        for j in idx[1:]:
            for key in design_keys + ("flow_ul_s",):
                a, b = first[key], parsed[j][key]
                if a != b and not (isinstance(a, float) and math.isnan(a) and b != b):
                    raise DataError(key, f"curve {cid!r} changes {key} from {a!r} to {b!r}; "
                                    "one curve is one specimen at one flow rate", j + 1,
                                    f"one {key} in every row of curve {cid!r} ({a!r} in "
                                    "its first)")
        if len(idx) < MIN_POINTS_PER_CURVE:
            raise DataError("curve_id", f"curve {cid!r} has {len(idx)} points", idx[-1] + 1,
                            f"at least {MIN_POINTS_PER_CURVE} points per curve")
        if "time_s" in present:
            times = [float(parsed[j]["time_s"]) for j in idx]  # type: ignore[arg-type]
            if len(set(times)) != len(times):
                raise DataError("time_s", f"curve {cid!r} repeats a time", idx[-1] + 1,
                                "distinct times within a curve")
    _same_design_per_specimen(parsed, by_curve, design_keys)
    curve_ids = tuple(by_curve)
    specimens: dict[str, int] = {}
    specimen_of = [specimens.setdefault(str(parsed[by_curve[c][0]].get("specimen", c)),
                                        len(specimens)) for c in curve_ids]
    families: dict[tuple, int] = {}
    groups: dict[tuple, int] = {}
    rows_sorted: list[tuple[int, int, int, dict]] = []
    for ci, cid in enumerate(curve_ids):
        idx = by_curve[cid]  # file order = history order without time_s
        if "time_s" in present:
            idx = sorted(idx, key=lambda j: float(parsed[j]["time_s"]))  # type: ignore
        rec = parsed[idx[0]]
        fam = (str(rec["body_material"]), str(rec["membrane_material"]),
               round(float(rec["T_mm"]), 6), round(float(rec["b_mm"]), 6),  # type: ignore
               round(float(rec["h_mm"]), 6))  # type: ignore[arg-type]
        fi = families.setdefault(fam, len(families))
        flow = rec["flow_ul_s"]
        gkey = fam + (round(float(rec["L_mm"]), 6), round(float(rec["t_mm"]), 6),  # type: ignore
                      None if flow != flow else round(float(flow), 6))  # type: ignore
        gi = groups.setdefault(gkey, len(groups))
        rows_sorted += [(ci, fi, gi, parsed[j]) for j in idx]
        if "volume_ul" in present:
            check_runs(cid, [float(parsed[j]["volume_ul"]) for j in idx],  # type: ignore
                       [j + 1 for j in idx], volume_step_ul,
                       [float(parsed[j][PUMP_COLUMN]) for j in idx]  # type: ignore
                       if PUMP_COLUMN in present else None)

    def col(name: str) -> np.ndarray:
        return np.array([float(r[name]) for _, _, _, r in rows_sorted])

    return Observations(
        curve_ids, tuple(families), np.array([c for c, _, _, _ in rows_sorted]),
        np.array([f for _, f, _, _ in rows_sorted]), np.array([g for _, _, g, _ in rows_sorted]),
        col("L_mm"), col("t_mm"), col("pressure_pa"), col("angle_deg"), col("time_s"),
        col("flow_ul_s"), col("angle_sd_deg"), col("force_mn"), _hash(parsed),
        direction=col(PUMP_COLUMN) if PUMP_COLUMN in present else None, warnings=warnings,
        pump_logged=PUMP_COLUMN in present, columns_read=columns_read,
        specimen=np.array([specimen_of[c] for c, _, _, _ in rows_sorted], dtype=int),
        measured_volume_ul=col("volume_ul") if "volume_ul" in present else None,
        volume_step_ul=volume_step_ul)


def _same_design_per_specimen(parsed: list[dict[str, object]],
                              by_curve: dict[str, list[int]], keys: tuple[str, ...]) -> None:
    """The runs of one specimen are of one design (a DataError naming the run that
    changes it)."""
    first: dict[str, int] = {}
    for cid, idx in by_curve.items():
        spec = parsed[idx[0]].get("specimen")
        if spec is None:
            continue
        j0 = first.setdefault(str(spec), idx[0])
        for key in keys:
            a, b = parsed[j0][key], parsed[idx[0]][key]
            if a != b:
                raise DataError(key, f"specimen {spec!r} changes {key} from {a!r} to {b!r} "
                                f"in {cid!r}; its runs are one specimen", idx[0] + 1,
                                f"one {key} in every run of specimen {spec!r}")


def _hash(parsed: list[dict[str, object]]) -> str:
    """sha256 of the canonical rows (independent of row order, column order and number
    formatting)."""
    lines = sorted(json.dumps(r, sort_keys=True, allow_nan=True, default=str) for r in parsed)
    text = "\n".join(lines)
    return hashlib.sha256(text.encode()).hexdigest()


def _plain_keys(row: dict, i: int) -> dict:
    """``row`` with its column names stripped of spaces and of a byte-order mark (a CSV
    converted to JSON by a tool that kept the BOM: '\ufeffcurve_id' answered "curve_id:
    required column is missing"); two names that become one are a DataError."""
    out = {(k.lstrip("\ufeff").strip() if isinstance(k, str) else k): v
           for k, v in row.items()}
    if len(out) != len(row):
        raise DataError("rows", "a column is named twice (up to spaces)", i,
                        "each column once per row")
    return out


def read_csv_rows(text: str) -> list[dict[str, object]]:
    """Rows of a CSV text (header line first; '#' comment lines and blank lines are
    skipped: a blank line between a comment and the header had made an empty header; so
    are a spreadsheet's empty rows, separators only). A field beyond the csv module's
    size limit is a DataError naming its row and column. Lines may end in LF, CR LF or CR
    alone (a spreadsheet's "CSV (Macintosh)": read as one line, it was blamed on the
    field size, its CR garbling the terminal's line). Fields are separated by ',', or by
    ';' or tabs with ',' as the decimal mark (a German Excel's CSV; _csv_dialect.py), or
    by the one a first line 'sep=;' names (Excel's hint, read, not data). A
    column without a name in the header (a trailing separator) is dropped when it is
    empty on every row."""
    numbered = [(n, ln) for n, ln in enumerate(io.StringIO(text, newline=None), 1)
                if not is_blank(ln) and not ln.lstrip().startswith("#")]
    lines = [ln for _, ln in numbered]
    if not lines:
        raise DataError("header", "the file is empty", None,
                        "a header line naming the columns " + ", ".join(REQUIRED))
    sep = named_separator(lines[0])        # Excel's 'sep=;' above the header
    if sep is not None:
        numbered, lines = numbered[1:], lines[1:]
        if not lines:
            raise DataError("header", "the file holds only its 'sep=' line", None,
                            "a header line naming the columns " + ", ".join(REQUIRED))
    sep = sep or separator(lines[0])
    try:
        names = [n.strip() for n in next(csv.reader(lines[:1], delimiter=sep))]
    except csv.Error as exc:
        raise _csv_error(exc, lines, 0, sep) from None
    unnamed = {k: f"column {k + 1}" for k, n in enumerate(names) if n == ""}
    names = [unnamed.get(k, n) for k, n in enumerate(names)]
    if len(set(names)) != len(names):
        raise DataError("header", "a column name is repeated", 0, "each column once")
    try:                                            # 'Pressure (kPa)' is pressure_pa
        readings = read_headers(names, tuple(RANGES))
    except DataError as exc:     # a units row, a clock for a unit: said so (_layouts.py)
        first = next(csv.reader(lines[1:2], delimiter=sep), [])
        raise layout_error(exc, dict(zip(names, (c.strip() for c in first)))) from None
    readings |= specimen_reading(names)             # 'Sample' is curve_id
    for name in REQUIRED:
        if name not in names and name not in {r.column for r in readings.values()}:
            below = header_below_text([[ln] for ln in lines[1:]], REQUIRED, tuple(RANGES))
            if below is not None:       # a logger's text above the header (_layouts.py)
                raise text_above_header(lines[:below + 1], numbered[below + 1][0])
            raise _missing(name, set(names))
    reader = csv.DictReader(lines[1:], fieldnames=names, delimiter=sep)
    out = []
    i = 0
    while True:
        try:
            raw = next(reader)
        except StopIteration:
            break
        except csv.Error as exc:
            raise _csv_error(exc, lines, i + 1, sep) from None
        i += 1
        if i > MAX_ROWS:     # refused before building the rest (a 10^6-row file)
            raise DataError("rows", f"more than {MAX_ROWS} rows", None,
                            f"at most {MAX_ROWS}")
        if None in raw:
            raise DataError("row", "more values than columns", i,
                            "one value per column of the header")
        if [str(v).strip() for v in raw.values()] == names and not unnamed:
            # two exports joined (`cat a.csv b.csv`): said so, not "unknown material"
            raise DataError("row", "repeats the header line (two files joined?)", i,
                            "one header line at the top: delete the repeated ones")
        out.append({k.strip(): (v if v is None else v.strip()) for k, v in raw.items()})
    last = len(out)                  # a logger's text after the last reading (_layouts.py)
    while last and text_below_readings(out[last - 1], 0) is not None:
        last -= 1
    if last < len(out):
        raise text_below_readings(out[last], numbered[last + 1][0])
    for name in unnamed.values():
        filled = next((j for j, r in enumerate(out, 1) if r.get(name)), None)
        if filled is not None:
            raise DataError(name, "holds values but has no name in the header", filled,
                            "a header naming every column that holds values")
        for r in out:
            r.pop(name, None)
    return decimal_commas(out, tuple(RANGES) + tuple(readings), sep)


def _missing(name: str, columns: set) -> DataError:
    """A required column is missing: one line naming it, and the column the file has in
    its place when one looks like it (a unit added to a name read as no quantity:
    'pressure gauge (kPa)'; a case or space changed: 'Curve_ID')."""
    def base(text: str) -> str:
        text = str(text).lower().replace("(", "[").split("[")[0].strip()
        return text.replace(" ", "_")

    def unit_of(text: str) -> str:   # 'p (mbar)', 'p [mbar]', 'p_mbar' -> 'mbar'
        text = str(text).lower().replace("(", "[").replace(")", "]")
        inside = text.split("[", 1)[1].split("]")[0] if "[" in text else ""
        return (inside or text.rsplit("_", 1)[-1]).strip()

    wide = one_column_per_specimen(columns, tuple(RANGES)) if name == "curve_id" else None
    if wide is not None:
        return wide
    stem = name.rsplit("_", 1)[0]
    unit = canonical_unit(name)
    dimension = unit[1] if unit else None
    near = sorted(c for c in map(str, columns)
                  if base(c) in (name, stem) or base(c).rsplit("_", 1)[0] == stem
                  or (dimension and UNITS.get(unit_of(c), ("",))[0] == dimension))
    how = (f"name it {header_form(name)} with {allowed_units(dimension)}" if dimension
           else f"the column must be named exactly {name}")
    found = f" (found {_short(near[0])}: {how})" if near else ""
    return DataError(name, "required column is missing" + found, None,
                     "columns " + ", ".join(REQUIRED))


def _csv_error(exc: csv.Error, lines: list[str], row: int, sep: str) -> DataError:
    """One line for an unreadable CSV row: its number and the column of its longest
    field (the csv module's field size limit is what usually fails)."""
    header = [h.strip() for h in lines[0].split(sep)] if lines else []
    fields = lines[row].split(sep) if row < len(lines) else [""]
    k = max(range(len(fields)), key=lambda j: len(fields[j]))
    column = header[k] if k < len(header) else f"column {k + 1}"
    return DataError(column, f"unreadable CSV field of {len(fields[k].strip())} "
                     f"characters ({exc})", row or None,
                     f"fields of at most {csv.field_size_limit()} characters")


# what a lab's data file is when it is not text: told by its first bytes (all of these
# were read as "UTF-16 without a byte-order mark"; an HDF5 file: looks_like_hdf5)
FILE_SIGNATURES = ((b"PK\x03\x04", "a zip archive (an Excel .xlsx or .ods workbook?)"),
                   (b"\xd0\xcf\x11\xe0", "an old Excel .xls workbook"),
                   (b"\x89PNG", "a PNG image"), (b"%PDF", "a PDF document"),
                   (b"\x1f\x8b", "a gzip-compressed file (unpack it first: gunzip)"),
                   (b"\xfd7zXZ\x00", "an xz-compressed file (unpack it first: unxz)"))


def decode_text(data: bytes, name: str) -> str:
    """Text of a measured-data file: UTF-8, or UTF-16/32 with a byte-order mark. Anything
    else (latin-1 from a spreadsheet, UTF-16 without BOM) is one DataError naming the
    file, the line and the expected encoding."""
    if (encoding := bom_encoding(data)) is not None:
        try:
            text = data.decode(encoding)
        except UnicodeDecodeError as exc:
            raise DataError("file", f"{name}: line {byte_line(data, exc.start, encoding)}: not "
                            f"valid {encoding} after its byte-order mark", None,
                            "UTF-8 text") from None
        if "\x00" in text:
            raise _stray_nul(text, name)
        return text
    # an HDF5 file where HDF5 looks for its signature (a sealed curve database has it
    # after its seal, solver/store/integrity.py), or another kind by its first bytes
    what = ("an HDF5 file (a curve database?)" if looks_like_hdf5(data[:HDF5_HEAD_BYTES])
            else next((w for signature, w in FILE_SIGNATURES if data.startswith(signature)),
                      None))
    if what is not None:
        raise DataError("file", f"{name}: this is {what}, not text", None,
                        "a CSV file (UTF-8, comma-separated; a spreadsheet's 'Save as: "
                        "CSV UTF-8') or JSON rows")
    if b"\x00" in data:
        raise _nul_error(data, name)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data[:exc.start].count(b"\n") + 1
        raise DataError("file", f"{name}: line {line} (data row {line - 1}): byte "
                        f"0x{data[exc.start]:02x} is not UTF-8 (latin-1 or Windows-1252 from "
                        "a spreadsheet?)", None, "UTF-8 text (or UTF-16 with a byte-order "
                        "mark): save the file as CSV UTF-8") from None


def _nul_error(data: bytes, name: str) -> DataError:
    """A file with a NUL byte (no text file holds one): UTF-16 without its byte-order mark
    when NULs fill every other byte of its start (the high bytes of ASCII text), else a
    stray NUL at its line and column, which once read as "UTF-16 without a byte-order
    mark" in the first 4 kB and, past them, as a row of empty cells ("unknown material
    ''")."""
    head = data[:200]
    if len(head) >= 4 and max(head[0::2].count(0), head[1::2].count(0)) >= 0.4 * (
            len(head) // 2):
        line = data[:data.index(b"\x00")].count(b"\n") + 1
        return DataError("file", f"{name}: line {line}: it looks like UTF-16 without a "
                         "byte-order mark", None, "UTF-8 text (or UTF-16 with a byte-order "
                         "mark): save the file as CSV UTF-8")
    return _stray_nul(data.decode("utf-8", "replace"), name)


def _stray_nul(text: str, name: str) -> DataError:
    """The first NUL of ``text`` (a file's decoded text) by its line and column."""
    at = text.index("\x00")
    line, column = text.count("\n", 0, at) + 1, at - text.rfind("\n", 0, at)
    return DataError("file", f"{name}: line {line}, column {column}: a NUL byte (0x00), which "
                     "no text file holds: not a text file, or a damaged one?", None,
                     "UTF-8 text without NUL bytes (a spreadsheet's 'Save as: CSV UTF-8')")


def load_observations(path: str | Path, strict: bool = False) -> Observations:
    """Read a CSV file (or JSON: a list of row objects, or {"rows": [...]}) and validate."""
    path = Path(path)
    text = decode_text(read_bounded(path, MAX_FILE_BYTES, "file", f"a data file ({MAX_ROWS} "
                                    "rows)"), path.name)
    if path.suffix.lower() == ".json":
        try:
            data, repeat = loads_with_repeats(text)
        except (ValueError, RecursionError) as exc:  # JSONDecodeError, an integer of
            # > 4300 digits, or nesting deeper than the parser's recursion limit
            raise DataError("file", f"{path.name}: not valid JSON: {_short(str(exc))}",
                            None, "a JSON list of row objects, or {\"rows\": [...]}"
                            ) from None
        if repeat is not None:   # json keeps the last: {"angle_deg": 5, "angle_deg": 50}
            index = [p for p in repeat[:2] if isinstance(p, int)]
            raise DataError(str(repeat[-1])[:60], f"{path.name}: {_short(repeat[-1])} is "
                            "given twice in one object; which value is meant is not "
                            "guessed", index[0] + 1 if index else None,
                            "each column once per row")
        rows = data.get("rows") if isinstance(data, dict) else data
    else:
        rows = read_csv_rows(text)
    _check_cells(rows)
    return observations_from_rows(rows, strict)  # type: ignore[arg-type]


def _check_cells(rows: object) -> None:
    """Each cell of a data file's rows held to the one rule of a measured cell
    (``surrogate.measured_cell``, POST /v1/calibrate's too), a CSV file's as a JSON
    file's: a CSV curve_id of 10,000 characters was taken, where JSON refused 201. A
    DataError names the row (1-based) and the column."""
    for i, row in enumerate(rows if isinstance(rows, list) else [], start=1):
        for column, value in (row.items() if isinstance(row, dict) else ()):
            if (problem := cell_problem(value)) is not None:
                raise DataError(str(column)[:60], problem, i, CELL_WORDS)


def _without_rows(after: np.ndarray, at: np.ndarray, names: tuple[str, ...],
                  rows: np.ndarray) -> tuple[np.ndarray, np.ndarray, tuple[str, ...]]:
    """The pump switches (``_history.pump_switches``) with ``rows`` taken out (curves
    whose measured volume is used: it holds where the pump switched) and the switches
    left on no row dropped."""
    after, at = np.where(rows[:, None], 0.0, after), np.where(rows[:, None], 0.0, at)
    keep = np.any(after != 0, axis=0) | np.any(at != 0, axis=0)
    return after[:, keep], at[:, keep], tuple(n for n, k in zip(names, keep, strict=True)
                                              if k)
