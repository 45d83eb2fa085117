"""Many designs from a CSV file, answered by one loaded model:
``balloon inverse --designs designs.csv --angles-deg 45 -o ranked.csv``.

A lab's batch: one row per design, its columns the design's fields as ``POST /v1/predict``
names them (``L_mm`` and ``t_mm`` required; ``T_mm``, ``b_mm``, ``h_mm``, ``W_mm``,
``body_length_mm``, ``chamber_offset_mm``, ``body_material``, ``membrane_material``,
``body_stiffness_scale``, ``membrane_stiffness_scale`` optional, an empty cell is the
default), any other column (a name, a note) carried to the output as written. Lengths mm,
stiffness scales x the preset's moduli. The model is loaded once (seconds; a loop over
``balloon inverse`` loaded it for every design, 11-20 s each on the shared 2-core VM) and
each row is answered in milliseconds: 200 designs in 21 s.

A row the model refuses (outside the box, a cell that is no number, more or fewer cells
than the header: never read by position) keeps its place, its
error in the ``error`` column naming the column and the allowed range, and the batch goes
on (the exit status is 0 when any row is answered, 2 when none is). Progress goes to
stderr. The output is a plain CSV (',' separators, '.' decimals, one
header line: what a spreadsheet reads) with the model's identity on every row: ``model``,
``model_file``, ``model_sha256`` (of the file's bytes; empty for the built-in ``paper``)
and ``balloon_version``, so that a ranking can be made again and told apart from one of
another model file. A file separated by ';' with decimal commas (a German Excel's) is read
as the measured-data reader reads one (``surrogate.calibration._csv_dialect``).
"""

from __future__ import annotations

import csv
import difflib
import io
import sys
from collections.abc import Callable, Iterator
from pathlib import Path

from solver.errors import BalloonError, InputError
from solver.number_text import NUMBER_FORM, is_number_text

MAX_BYTES = 64 * 2**20      # a designs file read whole, never past this
MAX_DESIGNS = 100_000       # rows of one batch
NUMBER_COLUMNS = ("L_mm", "t_mm", "T_mm", "b_mm", "h_mm", "W_mm", "body_length_mm",
                  "chamber_offset_mm", "body_stiffness_scale", "membrane_stiffness_scale")
TEXT_COLUMNS = ("body_material", "membrane_material")
REQUIRED = ("L_mm", "t_mm")
#: a row's key (no header's: a header cell is text) saying its cells do not match the
#: header: "7,1" in a comma-separated file is two cells, read as L 7 and t 1 by position
CELLS = 0
#: the columns the output adds after the input's own and the answer's
IDENTITY = ("error", "model", "model_file", "model_sha256", "balloon_version")


def read_designs(path: Path, option: str = "--designs") -> tuple[list[str], list[dict]]:
    """(header, rows) of a designs file: every cell as text. InputError naming ``option``
    for a file that is no designs table (no header, a column given twice, L_mm or t_mm
    missing, a column that reads as a misspelt length), saying what it allows."""
    from solver.bounded_read import read_bounded
    from surrogate.calibration._csv_dialect import decimal_commas, is_blank, separator
    from surrogate.calibration._errors import DataError

    raw = read_bounded(path, MAX_BYTES, option, "a designs CSV file")
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise InputError(option, f"{path}: not UTF-8 text", "a CSV file (UTF-8)") from None
    lines = [line for line in text.splitlines() if not is_blank(line)]
    if not lines:
        raise InputError(option, f"{path}: empty", "a header line and one row per design")
    sep = separator(lines[0])
    reader = csv.reader(io.StringIO("\n".join(lines)), delimiter=sep)
    header = [h.strip() for h in next(reader)]
    known = (*NUMBER_COLUMNS, *TEXT_COLUMNS)
    allowed = f"columns {', '.join(known)} (L_mm, t_mm required) and any of your own"
    twice = sorted({h for h in header if header.count(h) > 1})
    if twice:
        raise InputError(option, f"{path}: column {twice[0]!r} given twice", allowed)
    missing = [c for c in REQUIRED if c not in header]
    if missing:
        raise InputError(option, f"{path}: no column {missing[0]!r} (header: "
                         f"{', '.join(header)[:200]})", allowed)
    # a column named as a design's field but none of them (T_mn, l_mm): it would be
    # carried and its design get the default, never the value the user meant
    for h in header:
        near = difflib.get_close_matches(h, known, n=1, cutoff=0.75)
        if h not in known and (near or h.endswith("_mm") or "material" in h or "scale" in h):
            hint = f" (did you mean {near[0]!r}?)" if near else ""
            raise InputError(option, f"{path}: column {h!r} is none of the design's{hint}",
                             allowed)
    rows = []
    for cells in reader:
        row = dict(zip(header, (c.strip() for c in cells), strict=False))
        if len(cells) != len(header):   # its own error: the batch goes on
            row[CELLS] = f"{len(cells)} cells where the header has {len(header)}"
        rows.append(row)
    if len(rows) > MAX_DESIGNS:
        raise InputError(option, f"{path}: {len(rows)} designs", f"at most {MAX_DESIGNS}")
    if not rows:
        raise InputError(option, f"{path}: a header and no design", "one row per design")
    try:
        rows = decimal_commas(rows, NUMBER_COLUMNS, sep)   # type: ignore[arg-type]
    except DataError as exc:
        raise InputError(option, f"{path}: {exc}") from None
    return header, rows


def row_design(row: dict) -> object:
    """The design of one row (solver.design.Design), as ``balloon predict``'s flags make
    it; InputError naming the row's column and its allowed range."""
    from argparse import Namespace

    from service.commands.predict import design_from_args

    if CELLS in row:
        raise InputError("row", f"{row[CELLS]} (a decimal comma in a ',' file?): not read "
                         "by position", "one cell per header column; '.' decimals, or a "
                         "';'-separated file for decimal commas")
    values: dict[str, object] = {}
    for name in NUMBER_COLUMNS:
        cell = row.get(name) or ""
        if cell == "":
            if name in REQUIRED:
                raise InputError(name, "empty", "a number (mm)")
            continue
        if not is_number_text(cell):
            raise InputError(name, f"{cell[:40]!r} is not a number", NUMBER_FORM)
        values[name] = float(cell)
    for name in TEXT_COLUMNS:
        values[name] = row.get(name) or None
    try:
        return design_from_args(Namespace(**values))
    except InputError as exc:   # "--body-stiffness-scale" is the column here
        field = exc.field.lstrip("-").replace("-", "_")
        raise InputError(field, exc.detail, exc.allowed, allowed_said=exc.allowed_said) from None


def model_identity(spec: str | None, models_dir: Path | None) -> dict[str, str]:
    """The model's name, its file's name and the SHA-256 of its bytes (empty for the
    built-in ``paper``), and the package's version: the columns that make a batch's
    output reproducible."""
    from service.cli import package_version
    from service.settings import get_settings
    from surrogate.fit_provenance import file_sha256

    name = spec or "emulator"
    settings = get_settings()
    path: Path | None
    if name == "paper":
        path = None
    elif name == "emulator":
        path = settings.emulator_path
    elif name in ("exponential", "fitted"):
        path = settings.surrogate_path
    elif Path(name).suffix == ".json" or "/" in name:
        path = Path(name)
    else:       # a saved calibrated model
        path = (models_dir or settings.models_dir) / f"{name}.json"
    sha = file_sha256(path) if path and path.is_file() else ""
    return {"model": name, "model_file": path.name if path else "",
            "model_sha256": sha, "balloon_version": package_version()}


def progress(done: int, total: int, refused: int) -> None:
    """``designs 37/200 (1 refused)`` on stderr: on one line rewritten on a terminal, every
    tenth of the batch (and the last) otherwise."""
    text = f"balloon: designs {done}/{total}" + (f" ({refused} refused)" if refused else "")
    if sys.stderr.isatty():
        print("\r" + text, end="\n" if done == total else "", file=sys.stderr, flush=True)
    elif done == total or done % max(1, total // 10) == 0:
        print(text, file=sys.stderr, flush=True)


def run_batch(header: list[str], rows: list[dict], columns: tuple[str, ...],
              answer: Callable[[object], Iterator[dict[str, object]]],
              identity: dict[str, str], out: io.TextIOBase) -> int:
    """Each row's design answered (``answer(design)``: its output rows, each with
    ``columns``), written as CSV to ``out`` after the row's own cells; a refused row
    once, its ``error`` said. Returns how many rows were refused."""
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow([*header, *columns, *IDENTITY])
    refused = 0
    for k, row in enumerate(rows, start=1):
        own = [row.get(h, "") for h in header]
        try:
            answers = list(answer(row_design(row)))
        except (BalloonError, ValueError) as exc:
            refused += 1
            writer.writerow([*own, *("" for _ in columns), _one_line(exc),
                             *list(identity.values())])
        else:
            for a in answers:
                writer.writerow([*own, *(_cell(a.get(c)) for c in columns), "",
                                 *list(identity.values())])
        progress(k, len(rows), refused)
    return refused


def _cell(value: object) -> object:
    """A CSV cell: an empty one for no number (past the FE range); a float to 6
    significant digits (a spreadsheet's reading, and the same text on every machine)."""
    if value is None:
        return ""
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, (list, tuple)):
        return " ".join(str(v) for v in value)
    return value


def _one_line(exc: BaseException) -> str:
    from service.cli import shown

    return shown(exc).replace("\n", " ")
