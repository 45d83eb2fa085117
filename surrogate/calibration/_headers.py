"""A lab's column headers with units (``Pressure (kPa)``, ``Angle [°]``, ``p / psi``,
``t [min]``, ``Flow (ml/min)``) read as the canonical columns (``pressure_pa``, ...).

A header is a quantity and a unit: ``name (unit)``, ``name [unit]``, ``name / unit``,
``name_unit`` or ``name unit``. The quantity is one of the canonical numeric columns
(``_data.RANGES``), named by its own stem (``pressure`` of ``pressure_pa``) or a synonym
(``QUANTITY_NAMES``); the unit is one of ``UNITS`` of the same dimension. The canonical
column's own unit is read off its name (``pa`` of ``pressure_pa``, ``ul_s`` = ul/s of
``flow_ul_s``), so the factor is the ratio of the two units' factors: ``Pressure (kPa)``
is pressure_pa x 1000. The values are multiplied once, when the rows are read
(``_data.observations_from_rows``), and every check after that (ranges, kPa-looking
pressures) sees the canonical unit.

Refused, naming the header: a known quantity in an unknown unit (``Angle (grad)``: the
gradian or the German "Grad" = degree? not guessed), a unit of another dimension
(``Pressure (s)``), a quantity named without a unit, two headers read as one column, and
and a header longer than any lab's. An injected volume (``Volume (ml)``, ``V [mm^3]``) is
the column ``volume_ul`` (_measured_volume.py). Exact canonical names are read as they are.
"""

from __future__ import annotations

import functools
import math
import re
from dataclasses import dataclass

from surrogate.calibration._errors import DataError

#: unit (lower case; 'u' for micro) -> (dimension, factor to the dimension's base unit:
#: Pa, deg, s, ul, mN). A flow unit is a volume unit per time unit (``ml/min``).
UNITS: dict[str, tuple[str, float]] = {
    "pa": ("pressure", 1.0), "hpa": ("pressure", 100.0), "kpa": ("pressure", 1000.0),
    "mbar": ("pressure", 100.0), "bar": ("pressure", 1e5),
    "psi": ("pressure", 6894.757293168361), "mmhg": ("pressure", 133.322387415),
    "deg": ("angle", 1.0), "°": ("angle", 1.0), "degree": ("angle", 1.0),
    "degrees": ("angle", 1.0), "rad": ("angle", 180.0 / math.pi),
    "s": ("time", 1.0), "sec": ("time", 1.0), "ms": ("time", 1e-3), "min": ("time", 60.0),
    "h": ("time", 3600.0),
    "ul": ("volume", 1.0), "ml": ("volume", 1000.0), "nl": ("volume", 1e-3),
    "mm^3": ("volume", 1.0), "mm3": ("volume", 1.0), "mm³": ("volume", 1.0),
    "cm^3": ("volume", 1000.0), "cm3": ("volume", 1000.0), "cm³": ("volume", 1000.0),
    "cc": ("volume", 1000.0),
    "cmh2o": ("pressure", 98.0665), "mmh2o": ("pressure", 9.80665),
    # inches of water (a differential gauge's, a Magnehelic's): 25.4 mm of water
    "inh2o": ("pressure", 249.08891), "inwc": ("pressure", 249.08891),
    "mn": ("force", 1.0), "n": ("force", 1000.0), "gf": ("force", 9.80665),
}

#: canonical numeric column -> the names a lab gives its quantity besides the column's own
#: stem (``pressure`` of pressure_pa); any case, except single letters, read as listed
#: (``t`` is time, ``T`` a temperature or the body thickness).
QUANTITY_NAMES: dict[str, tuple[str, ...]] = {
    "pressure_pa": ("p", "P", "druck", "gauge pressure"),
    "angle_deg": ("bending angle", "bend angle", "theta", "θ", "winkel"),
    "time_s": ("t", "zeit"),
    "flow_ul_s": ("flow rate", "q", "Q", "pump rate", "fluss", "durchfluss", "flussrate",
                  "förderrate"),
    "force_mn": ("f", "F", "tip force", "blocked force", "kraft"),
    "angle_sd_deg": ("angle sd", "angle uncertainty"),
    "volume_ul": ("v", "V", "injected volume", "vol", "dispensed volume", "pump volume",
                  "volumen"),
}
#: a longer header names no quantity (its every split read would take a second at 10,000
#: characters: a stray key over HTTP)
MAX_HEADER_CHARS = 100
#: a lab's file has some 20 columns (a logger's, some 100); more is no table of readings
#: (a JSON row of 200,000 stray keys: a server's CPU for seconds before any other check)
MAX_COLUMNS = 1000


def unit_of(text: str) -> tuple[str, float] | None:
    """(dimension, factor) of a unit as written (``kPa``, ``µl``, ``ml/min``, ``ul_s``)."""
    text = text.strip().lower().replace("µ", "u").replace("μ", "u").replace(" ", "")
    text = text.removesuffix(".")
    if text in UNITS:
        return UNITS[text]
    for sep in ("/", "_", "per"):
        if sep in text:
            top, _, bottom = text.partition(sep)
            a, b = UNITS.get(top), UNITS.get(bottom)
            if a and b and a[0] == "volume" and b[0] == "time":
                return "flow", a[1] / b[1]
    return None


def canonical_unit(column: str) -> tuple[str, str, float] | None:
    """(stem, dimension, factor) of a canonical column, read off its name:
    ``pressure_pa`` -> ('pressure', 'pressure', 1), ``flow_ul_s`` -> ('flow', 'flow', 1);
    None for a column in no unit of ``UNITS`` (the design's lengths, named exactly)."""
    parts = column.split("_")
    for k in range(1, len(parts)):
        unit = unit_of("_".join(parts[k:]))
        if unit is not None:
            return "_".join(parts[:k]), unit[0], unit[1]
    return None


def split_header(header: str) -> tuple[str, str | None]:
    """(quantity, unit or None) of a header: 'Pressure (kPa)', 'p [mbar]', 'p / psi'."""
    m = re.fullmatch(r"(.*?)\s*[(\[]\s*([^()\[\]]*?)\s*[)\]]\s*", header)
    if m:
        return m.group(1), m.group(2)
    if "/" in header:
        name, _, unit = header.partition("/")
        return name, unit
    return header, None


@dataclass(frozen=True)
class Reading:
    """How one header was read: the canonical ``column`` and the ``factor`` its values
    are multiplied by (1 for an exact name)."""

    header: str
    column: str
    factor: float

    def words(self) -> str:
        return f"`{self.header}` read as {self.column} x {self.factor:.6g}"

    def as_dict(self) -> dict[str, object]:
        return {"header": self.header, "column": self.column, "factor": self.factor,
                "reading": self.words()}


def _key(name: str) -> str:
    """A quantity's name as compared: lower case (single letters as written), '_' and
    runs of spaces one space."""
    name = " ".join(name.replace("_", " ").split())
    return name if len(name) == 1 else name.lower()


@functools.lru_cache(maxsize=8)
def _names(numeric: tuple[str, ...]) -> dict[str, str]:
    """quantity name (``_key``) -> canonical column (made once per set of columns: made
    per header, a row of 200,000 stray keys took 37 s of a server's CPU to refuse).
    Read only."""
    out: dict[str, str] = {}
    for column in numeric:
        unit = canonical_unit(column)
        if unit is None:
            continue
        for name in (column, unit[0]) + QUANTITY_NAMES.get(column, ()):
            out[_key(name)] = column
    return out


def read_header(header: str, numeric: tuple[str, ...]) -> Reading | None:
    """The reading of one header, None when it names no quantity (a text column, an
    unknown column: the caller says so). Raises DataError naming the header for a known
    quantity in an unknown unit or without a unit."""
    if header in numeric:
        return Reading(header, header, 1.0)
    if len(header) > MAX_HEADER_CHARS:     # no lab's header: an unknown column, said short
        return None
    names = _names(numeric)
    splits = [split_header(header)]
    parts = header.split("_")   # 'p_mbar', 'Flow_ml_min': every split of the name
    splits += [("_".join(parts[:k]), "_".join(parts[k:])) for k in range(1, len(parts))]
    for name, unit_text in splits:
        key = _key(name)
        if key not in names:
            continue
        column = names[key]
        if unit_text is None and key == _key(column):
            return Reading(header, column, 1.0)     # 'Angle_deg': the name in its case
        _, dimension, own = canonical_unit(column)  # type: ignore[misc]
        unit = unit_of(unit_text) if unit_text else None
        if unit is None or unit[0] != dimension:
            if unit_text is not None and "_" in unit_text:
                continue            # 'time_of_day': an underscore that is no unit
            said = f"{unit_text!r} is not a unit of" if unit_text else "no unit is given for"
            raise DataError(header, f"read as {column}, but {said} {dimension}", None,
                            f"{header_form(column)} with {allowed_units(dimension)}")
        return Reading(header, column, unit[1] / own)
    return _unit_after_space(header, names)


def _unit_after_space(header: str, names: dict[str, str]) -> Reading | None:
    """A header whose last word is its unit, ``Pressure kPa``, ``Flow ul/s`` (a logger's
    habit; until 2026-12-07 "pressure_pa: required column is missing":
    benchmarks/lab_rig_sets.py N39); None unless the rest names a quantity and the word
    is a unit of its dimension (``Pressure gauge`` stays a column of no quantity)."""
    name, _, unit_text = header.strip().rpartition(" ")
    column = names.get(_key(name)) if name else None
    unit = unit_of(unit_text) if column else None
    if column is None or unit is None:
        return None
    _, dimension, own = canonical_unit(column)  # type: ignore[misc]
    return Reading(header, column, unit[1] / own) if unit[0] == dimension else None


def allowed_units(dimension: str) -> str:
    """The units of a dimension in words (a flow: volume / time)."""
    if dimension == "flow":
        return "a volume unit per time unit: ul/s, ml/min, ..."
    units = [u for u, (d, _) in UNITS.items() if d == dimension]
    return "one of " + ", ".join(units)


def header_form(column: str) -> str:
    """How a header of ``column``'s quantity is written: 'pressure (unit)'."""
    return f"{column}, or '{canonical_unit(column)[0]} (unit)'"  # type: ignore[index]


def read_headers(headers: list[str], numeric: tuple[str, ...]) -> dict[str, Reading]:
    """header -> Reading for every header naming a numeric quantity (exact canonical
    names included, factor 1). Raises DataError for a header that cannot be read
    (``read_header``), for two headers read as one column, naming both, and for more
    than ``MAX_COLUMNS`` headers."""
    if len(headers) > MAX_COLUMNS:
        raise DataError("columns", f"{len(headers)} distinct column names", None,
                        f"at most {MAX_COLUMNS} columns")
    out: dict[str, Reading] = {}
    by_column: dict[str, str] = {}
    for header in headers:
        if not isinstance(header, str):
            continue
        reading = read_header(header, numeric)
        if reading is None:
            continue
        if reading.column in by_column:
            first = by_column[reading.column]
            raise DataError(header, f"{first!r} and {header!r} are both read as "
                            f"{reading.column}", None, f"one column of {reading.column}: "
                            "drop or rename the other")
        by_column[reading.column] = header
        out[header] = reading
    return out
