"""Grid files: which designs a precompute job solves (TOML; docs/database.md has examples).

    name = "example"                       # optional, free text
    description = "..."                    # optional, free text
    pairs = [["pdms_1_10", "ecoflex_00_30"]]   # (body, membrane) material ids
    L_mm = {start = 4.1, stop = 17.1, num = 14}  # a range: num evenly spaced values
    t_mm = [0.5, 0.75, 1.0]                # or a list, or one number
    T_mm = 1.0                             # parameters left out keep Design's defaults

    [settings]                             # SolverSettings fields; defaults otherwise
    mesh_level = 1

    [materials.soft]                       # optional custom Ogden materials, usable in pairs
    mu_kpa = [1.0]
    alpha = [2.0]

    [[sweep]]                              # optional: several sweeps, whose union is solved;
    pairs = [["pdms_1_15", "ecoflex_00_30"]]   # each takes the top-level values as defaults
    L_mm = [4.1, 11.1]

Every sweep is the Cartesian product of its pairs and parameter values. Everything
is checked before any solve: unknown keys, lengths out of range (negative ones
included), unknown materials (and custom ones that reuse a built-in id), empty lists or
ranges, designs that do not fit, settings of the wrong type or range and more than
MAX_POINTS designs raise GridError naming the file, the line, the key and the allowed
values.
"""

from __future__ import annotations

import hashlib
import itertools
import math
import re
import sys
import tomllib
from dataclasses import dataclass, replace
from pathlib import Path

from solver.bounded_read import read_bounded
from solver.byte_order_mark import bom_encoding, byte_line
from solver.design import LIMITS_MM, Design
from solver.design_space import REUSED_ID_ALLOWED, reused_id
from solver.errors import InputError
from solver.materials import (
    MATERIAL_ID_PATTERN,
    MATERIAL_ID_WORDS,
    MATERIALS,
    TERM_WORDS,
    OgdenMaterial,
    make_material,
)
from solver.number_text import unheld, unheld_words, written_float
from solver.precompute.lines import deepest, key_lines, line_of, longest_key
from solver.settings import SolverSettings, range_words, settings_from_dict
from solver.store.keys import canonical_number, record_key

PARAMETERS = tuple(LIMITS_MM)
SWEEP_KEYS = ("pairs", "name", *PARAMETERS)
SAMPLE_KEYS = ("pairs", "name", "n", "seed", "skip", "faces", "tips",
               "blocked_max_pressure_pa")
TOP_KEYS = ("description", "materials", "settings", "sweep", "sample", *SWEEP_KEYS)
BLOCKED_MAX_PRESSURE_PA = 3000.0   # blocked-tip force curves: to this chamber pressure
#                                    (past the emulator's force range, 2500 Pa)
RANGE_KEYS = ("start", "stop", "num")
MAX_POINTS = 100_000
NUM_WORDS = f"an integer 1 <= num <= {MAX_POINTS}"   # a range's num, in every refusal
# A grid is ranges, lists and [[sample]] tables: the shipped ones are 1-9 kB (emulator.toml,
# 2105 designs). 1 MiB is over 100 times that, and holds some 28,000 designs written out one
# [[sweep]] each (two lengths: 3.7 MiB for the 100,000 of MAX_POINTS); refused before
# tomllib parses it, whose cost is about 1 s per MiB (a 16 MiB file of unknown keys, the
# limit until 2026-12-08, cost 5-16 s and 440 MB to refuse).
MAX_GRID_BYTES = 2**20
MAX_NESTING = 100  # what a grid needs is 3 ([[body, membrane], ...] in a table)
MAX_KEY_PARTS = 10  # what a grid needs is 3 (materials.soft.mu_kpa)


class GridError(InputError):
    """A grid file is invalid; ``path`` and ``line`` say where."""

    def __init__(self, path: str, line: int, field: str, message: str,
                 allowed: str | None = None) -> None:
        super().__init__(field, message, allowed)
        self.path = path
        self.line = line

    def __str__(self) -> str:
        text = f"{self.path}, line {self.line}: {self.field}: {self.detail}"
        return text + (f" (allowed: {self.allowed})" if self.allowed else "")


@dataclass(frozen=True)
class GridPoint:
    """One design to solve, with its record key."""

    key: str
    design: Design
    settings: SolverSettings


@dataclass(frozen=True)
class Grid:
    """A parsed, validated grid: its source, settings and the distinct designs in order."""

    source: str
    text: str
    settings: SolverSettings
    points: tuple[GridPoint, ...]

    @property
    def sha256(self) -> str:
        return hashlib.sha256(self.text.encode("utf-8")).hexdigest()

    def __len__(self) -> int:
        return len(self.points)


class _Reader:
    """Validation with positions: ``fail(path, ...)`` raises GridError at ``path``'s line."""

    def __init__(self, text: str, source: str) -> None:
        self.text, self.source = text, source

    def fail(self, path: tuple, field: str, message: str, allowed: str | None = None,
             needle: str | None = None) -> GridError:
        """The error at ``path``'s line: the text's lines scanned for it only now (a
        grid read without a fault never needs them)."""
        line = line_of(self.text.splitlines(), key_lines(self.text, until=tuple(path)),
                       path, needle)
        return GridError(self.source, line, field, message, allowed)

    def check_keys(self, table: dict, where: tuple, allowed: tuple[str, ...]) -> None:
        for key in table:
            if key not in allowed:
                raise self.fail((*where, key), key, "unknown key", ", ".join(allowed))

    def number(self, value: object, path: tuple, name: str) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.fail(path, name, f"{value!r} is not a number", _limits(name))
        lo, hi = LIMITS_MM[name]
        if not lo <= value <= hi:
            raise self.fail(path, name, f"{value!r} mm is out of range", _limits(name),
                            needle=repr(value))
        return float(value)

    def values(self, value: object, path: tuple, name: str) -> list[float]:
        """A parameter's values: a number, a non-empty list, or {start, stop, num}."""
        if isinstance(value, dict):
            self.check_keys(value, path, RANGE_KEYS)
            missing = [k for k in RANGE_KEYS if k not in value]
            if missing:
                raise self.fail(path, name, f"range lacks {', '.join(missing)}",
                                "{start = ..., stop = ..., num = ...}")
            num = value["num"]
            if isinstance(num, bool) or not isinstance(num, int):
                raise self.fail(path, name, f"num = {num!r} is not an integer",
                                NUM_WORDS)
            if num < 1:
                raise self.fail(path, name, f"empty range: num = {num}",
                                NUM_WORDS)
            if num > MAX_POINTS:  # checked before expanding: a typo must not hang the job
                raise self.fail(path, name, f"num = {num} values",
                                NUM_WORDS)
            start = self.number(value["start"], path, name)
            stop = self.number(value["stop"], path, name)
            if stop < start:
                raise self.fail(path, name, f"empty range: stop {stop:g} < start {start:g}",
                                "start <= stop")
            if num == 1:
                return [start]
            step = (stop - start) / (num - 1)
            return [canonical_number(start + i * step) for i in range(num)]
        if isinstance(value, list):
            if not value:
                raise self.fail(path, name, "empty list", "one or more values")
            return [self.number(v, path, name) for v in value]
        return [self.number(value, path, name)]

    def materials(self, table: object) -> dict[str, OgdenMaterial]:
        known = dict(MATERIALS)
        if table is None:
            return known
        if not isinstance(table, dict):
            raise self.fail(("materials",), "materials", "must be a table of materials",
                            "[materials.<id>] with mu_kpa = [...] and alpha = [...]")
        for material_id, spec in table.items():
            where = ("materials", material_id)
            if material_id in MATERIALS:  # one id, one set of parameters in the database
                raise self.fail(where, f"materials.{material_id}",
                                "redefines a built-in material",
                                f"a new id (built-in: {', '.join(sorted(MATERIALS))})")
            if not re.fullmatch(MATERIAL_ID_PATTERN, material_id):  # stored as its id
                raise self.fail(where, "materials", f"{material_id!r} is not a material id",
                                MATERIAL_ID_WORDS)
            if not isinstance(spec, dict):
                raise self.fail(where, material_id, "must be a table", "mu_kpa, alpha")
            self.check_keys(spec, where, ("mu_kpa", "alpha"))
            try:
                known[material_id] = make_material(material_id, spec.get("mu_kpa", []),
                                                   spec.get("alpha", []))
            except (InputError, TypeError, ValueError) as exc:
                field = getattr(exc, "field", "mu_kpa")
                raise self.fail((*where, field), f"materials.{material_id}.{field}",
                                getattr(exc, "detail", str(exc)),
                                getattr(exc, "allowed", None)) from None
            what = reused_id(known[material_id])    # one id, one set of parameters
            if what is not None:
                raise self.fail(where, f"materials.{material_id}", f"reuses the {what} "
                                f"{material_id!r} with other parameters", REUSED_ID_ALLOWED)
        return known

    def pairs(self, value: object, path: tuple,
              known: dict[str, OgdenMaterial]) -> list[tuple[OgdenMaterial, OgdenMaterial]]:
        allowed = ", ".join(sorted(known))
        shape = '[["<body id>", "<membrane id>"], ...]'
        if not isinstance(value, list) or not value:
            raise self.fail(path, "pairs", "needs at least one [body, membrane] pair", shape)
        out = []
        for pair in value:
            if (not isinstance(pair, list) or len(pair) != 2
                    or not all(isinstance(p, str) for p in pair)):
                raise self.fail(path, "pairs", f"{pair!r} is not a [body, membrane] pair",
                                shape)
            for material_id in pair:
                if material_id not in known:
                    raise self.fail(path, "pairs", f"unknown material {material_id!r}",
                                    allowed, needle=f"{material_id}")
            out.append((known[pair[0]], known[pair[1]]))
        return out


def _limits(name: str) -> str:
    lo, hi = LIMITS_MM[name]
    return f"{lo:g} <= {name} <= {hi:g} (mm)"


# where an integer too long for Python to convert sits (only looked for once tomllib
# has refused one): its digits, underscores between them, in any of TOML's bases
_LONG_INTEGER = re.compile(f"[0-9A-Fa-f_]{{{sys.get_int_max_str_digits() + 1},}}")


def parse_grid(text: str, source: str = "<grid>") -> Grid:
    """Parse and validate a grid text; GridError on the first problem found."""
    depth, at = deepest(text)
    if depth > MAX_NESTING:  # before tomllib, which recurses once per level
        raise GridError(source, at, "toml", f"values nested {depth} levels deep",
                        f"at most {MAX_NESTING} levels of [ ] and {{ }}")
    parts, at = longest_key(text)
    if parts > MAX_KEY_PARTS:  # before tomllib, whose cost grows as its square
        raise GridError(source, at, "toml", f"a dotted key or table name of {parts} parts",
                        f"at most {MAX_KEY_PARTS} parts, as materials.soft.mu_kpa")
    reader = _Reader(text, source)
    try:
        data = tomllib.loads(text, parse_float=written_float)  # 1e-400 kept as written
    except tomllib.TOMLDecodeError as exc:
        raise GridError(source, _toml_line(str(exc), text), "toml", str(exc),
                        "valid TOML (https://toml.io)") from None
    except RecursionError:  # arrays or tables nested thousands deep
        raise GridError(source, 1, "toml", "values nested too deeply to parse",
                        f"at most {MAX_NESTING} levels of [ ] and {{ }}") from None
    except ValueError:  # an integer past Python's 4300 digits (was a traceback)
        digits = _LONG_INTEGER.search(text)
        line = text.count("\n", 0, digits.start()) + 1 if digits else 1
        raise GridError(source, line, "toml", "an integer of more than "
                        f"{sys.get_int_max_str_digits()} digits, past any value a grid "
                        "takes", f"{NUM_WORDS}; lengths in mm (solver.design.LIMITS_MM)"
                        ) from None
    reader.check_keys(data, (), TOP_KEYS)   # first: no walk of a file of unknown keys
    for path, number in unheld(data):     # a number the float does not hold, as written
        name = next((p for p in reversed(path) if p in LIMITS_MM), path[-1])
        allowed = (NUM_WORDS if path[-1] == "num" else _limits(str(name))
                   if name in LIMITS_MM else TERM_WORDS if path[0] == "materials"
                   else range_words(str(name), "a number"))
        raise reader.fail(path, ".".join(map(str, path)), unheld_words(number), allowed,
                          needle=number.text)
    for key in ("name", "description"):
        if key in data and not isinstance(data[key], str):
            raise reader.fail((key,), key, f"{data[key]!r} is not a string", "free text")
    known = reader.materials(data.get("materials"))
    settings_table = data.get("settings", {})
    if not isinstance(settings_table, dict):
        raise reader.fail(("settings",), "settings", "must be a table", "[settings]")
    _check_setting_types(reader, settings_table)
    try:
        settings = settings_from_dict(settings_table)
    except InputError as exc:
        raise reader.fail(("settings", exc.field), f"settings.{exc.field}", exc.detail,
                          exc.allowed) from None
    points: dict[str, GridPoint] = {}
    samples = data.get("sample", [])
    if not isinstance(samples, list) or not all(isinstance(t, dict) for t in samples):
        raise reader.fail(("sample",), "sample", "must be [[sample]] tables", "[[sample]]")
    tables = [_sample(reader, ("sample", index), sample, settings)
              for index, sample in enumerate(samples)]
    listed = 0
    for index, table in enumerate(tables):  # the samples together, before any is drawn
        listed += table.count
        if listed > MAX_POINTS:
            raise reader.fail(("sample", index), "sample", f"more than {MAX_POINTS} designs",
                              f"at most {MAX_POINTS} designs per grid")
    for table in tables:
        for point in table.points():
            points.setdefault(point.key, point)
    if samples and "sweep" not in data:
        return Grid(source, text, settings, tuple(points.values()))
    sweeps = data.get("sweep", [{}])
    if not isinstance(sweeps, list) or not sweeps:
        raise reader.fail(("sweep",), "sweep", "must be one or more [[sweep]] tables",
                          "[[sweep]]")
    defaults = {k: v for k, v in data.items() if k in SWEEP_KEYS}
    for index, sweep in enumerate(sweeps):
        where: tuple = ("sweep", index) if "sweep" in data else ()
        if not isinstance(sweep, dict):
            raise reader.fail(("sweep",), "sweep", f"{sweep!r} is not a table",
                              "[[sweep]] tables")
        reader.check_keys(sweep, where, SWEEP_KEYS)
        if "name" in sweep and not isinstance(sweep["name"], str):
            raise reader.fail((*where, "name"), "name", f"{sweep['name']!r} is not a string",
                              "free text")
        for point in _expand(reader, where, {**defaults, **sweep}, sweep, known, settings):
            points.setdefault(point.key, point)
        if len(points) > MAX_POINTS:
            raise reader.fail(where, "sweep", f"more than {MAX_POINTS} designs",
                              f"at most {MAX_POINTS} designs per grid")
    return Grid(source, text, settings, tuple(points.values()))


def _check_setting_types(reader: _Reader, table: dict) -> None:
    """Refuse values that settings_from_dict would silently convert (``mesh_level = 0.5``
    read as 0, ``true`` as 1)."""
    defaults = SolverSettings()
    for key, value in table.items():
        if not hasattr(defaults, key):
            continue  # unknown keys: settings_from_dict names the allowed ones
        kind = type(getattr(defaults, key))
        if kind is str:
            ok, wanted = isinstance(value, str), "a string"
        elif kind is int:
            ok, wanted = isinstance(value, int) and not isinstance(value, bool), "an integer"
        else:
            ok = isinstance(value, (int, float)) and not isinstance(value, bool)
            wanted = "a number"
        if not ok:       # with the setting's range, when it has one (SETTING_RANGES)
            raise reader.fail(("settings", key), f"settings.{key}", f"{value!r} is not {wanted}",
                              range_words(key, wanted))


def _expand(reader: _Reader, where: tuple, merged: dict, own: dict,
            known: dict[str, OgdenMaterial], settings: SolverSettings) -> list[GridPoint]:
    def path_of(key: str) -> tuple:
        return (*where, key) if key in own else (key,)

    if "pairs" not in merged:
        raise reader.fail(where, "pairs", "no material pairs given",
                          '[["pdms_1_10", "ecoflex_00_30"], ...]')
    pairs = reader.pairs(merged["pairs"], path_of("pairs"), known)
    names = [n for n in PARAMETERS if n in merged]
    axes = [reader.values(merged[n], path_of(n), n) for n in names]
    count = len(pairs) * math.prod(len(axis) for axis in axes)
    if count > MAX_POINTS:
        raise reader.fail(where, "sweep", f"{count} designs in one sweep",
                          f"at most {MAX_POINTS} designs per grid")
    out = []
    for (body, membrane), combo in itertools.product(pairs, itertools.product(*axes)):
        values = dict(zip(names, combo, strict=True))
        try:
            design = Design(body_material=body, membrane_material=membrane,
                            **values).validated()  # type: ignore[arg-type]
        except InputError as exc:
            field = exc.field if exc.field in merged else (names[0] if names else "pairs")
            raise reader.fail(path_of(field), exc.field,
                              f"design {values} does not fit: {exc.detail}",
                              exc.allowed) from None
        out.append(GridPoint(record_key(design, settings), design, settings))
    return out


@dataclass(frozen=True)
class SampleTable:
    """A checked [[sample]] table: ``n`` scrambled Sobol designs of the emulator's box
    (solver/design_space.py) per pair (``faces``: moved onto the box's faces in turn,
    ``design_space.on_faces``), each solved with every settings variant (a tip of
    ``tips``); ``count`` the designs it lists, known before they are drawn."""

    n: int
    seed: int
    skip: int
    pairs: tuple[tuple[str, str], ...]
    faces: bool
    variants: tuple[SolverSettings, ...]

    @property
    def count(self) -> int:
        return self.n * len(self.pairs) * len(self.variants)

    def points(self) -> list[GridPoint]:
        """The table's designs, point-major: an interrupted job leaves every pair even."""
        from solver.design_space import sample_designs

        per_pair = [sample_designs(self.n, pair, self.seed, self.skip, self.faces)
                    for pair in self.pairs]
        return [GridPoint(record_key(designs[i], s), designs[i], s)
                for i in range(self.n) for designs in per_pair for s in self.variants]


def _sample(reader: _Reader, where: tuple, table: dict, settings: SolverSettings
            ) -> SampleTable:
    """A [[sample]] table checked (``SampleTable``): "free" tips solved with the settings
    as given, "blocked" ones with the tip held, to ``blocked_max_pressure_pa``, for the
    force curve."""
    from solver.design_space import PAIRS

    reader.check_keys(table, where, SAMPLE_KEYS)
    ints = {}
    for key, default, lo, hi in (("n", None, 1, MAX_POINTS), ("seed", 0, 0, 2**31 - 1),
                                 ("skip", 0, 0, 2**31 - 1)):
        value = table.get(key, default)
        if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
            raise reader.fail((*where, key), key, f"{value!r} is not an integer in range",
                              f"an integer {lo} <= {key} <= {hi}")
        ints[key] = value
    pairs = table.get("pairs", [list(p) for p in PAIRS])
    if (not isinstance(pairs, list) or not pairs
            or any(not isinstance(p, list) or tuple(p) not in PAIRS for p in pairs)):
        raise reader.fail((*where, "pairs"), "pairs", f"{pairs!r} are not box pairs",
                          ", ".join(f'["{b}", "{m}"]' for b, m in PAIRS))
    tips = table.get("tips", ["free"])
    if (not isinstance(tips, list) or not tips
            or any(t not in ("free", "blocked") for t in tips)):
        raise reader.fail((*where, "tips"), "tips", f"{tips!r}", '["free"], ["free", "blocked"]')
    p_max = table.get("blocked_max_pressure_pa", BLOCKED_MAX_PRESSURE_PA)
    if isinstance(p_max, bool) or not isinstance(p_max, (int, float)) or not 1 <= p_max <= 1e6:
        raise reader.fail((*where, "blocked_max_pressure_pa"), "blocked_max_pressure_pa",
                          f"{p_max!r}", "a number 1 <= p <= 1e6 (Pa)")
    faces = table.get("faces", False)
    if not isinstance(faces, bool):
        raise reader.fail((*where, "faces"), "faces", f"{faces!r}", "true or false")
    count = ints["n"] * len(pairs) * len(tips)
    if count > MAX_POINTS:   # before drawing them: n = 100000 of 4 pairs, 2 tips was 800,000
        raise reader.fail((*where, "n"), "n", f"{count} designs (n = {ints['n']}, times "
                          f"{len(pairs)} pair(s), times {len(tips)} tip(s))",
                          f"at most {MAX_POINTS} designs per grid")
    variants = {"free": settings,
                "blocked": replace(settings, tip="blocked", max_pressure_pa=float(p_max))}
    return SampleTable(ints["n"], ints["seed"], ints["skip"],
                       tuple((pair[0], pair[1]) for pair in pairs), faces,
                       tuple(variants[tip] for tip in tips))


def _toml_line(message: str, text: str) -> int:
    if "end of document" in message:
        return max(1, len(text.splitlines()))
    marker = "at line "
    if marker in message:
        digits = message.split(marker, 1)[1].split(",")[0].split(")")[0]
        if digits.strip().isdigit():
            return int(digits)
    return 1


def load_grid(path: str | Path) -> Grid:
    """Read and validate a grid file; FileNotFoundError if it does not exist, GridError
    naming the line when it is not UTF-8 text (TOML is UTF-8; a binary file is refused)."""
    path = Path(path)
    raw = read_bounded(path, MAX_GRID_BYTES, "grid",
                       "a grid file (TOML: ranges, lists and [[sample]] tables)")
    encoding = bom_encoding(raw)    # Notepad's "UTF-8 with BOM", "Unicode" (UTF-16)
    try:
        text = raw.decode(encoding or "utf-8")
    except UnicodeDecodeError as exc:
        raise GridError(str(path), byte_line(raw, exc.start, encoding or "utf-8"), "encoding",
                        f"byte 0x{raw[exc.start]:02x} at offset {exc.start} is not "
                        + (f"{encoding} after the file's byte-order mark" if encoding
                           else "UTF-8"), "a UTF-8 text file (TOML); save it as UTF-8"
                        ) from None
    # lines ended by a CR alone (an old Mac editor's) were "line 3: Expected newline ...
    # (at line 1, column 41)": TOML holds no lone CR, so each is read as a line end
    text = text.replace("\r\n", "\n").replace("\r", "\n")
    if "\x00" in text:
        line = text[:text.index("\x00")].count("\n") + 1
        raise GridError(str(path), line, "encoding", "a NUL byte: this is a binary file",
                        "a UTF-8 text file (TOML)")
    return parse_grid(text, str(path))
