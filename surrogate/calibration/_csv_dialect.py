"""A spreadsheet's CSV dialect: the field separator and the decimal mark of a lab's file.

Excel writes "CSV" with the list separator and the decimal mark of its locale: in a
German (French, Italian, ...) locale that is ``;`` between fields and ``,`` as the
decimal mark (``0,75``), and its "CSV UTF-8" adds a byte-order mark. The locale cannot
be changed from the save dialog, so such a file is read as it is, not refused:

* the separator is the header's: ``,`` when the header has one, else ``;`` or a tab
  when the header splits on it;
* with ``;`` or a tab, the decimal mark of the numeric columns is ``,`` when any of
  their cells has one (otherwise ``.``, as a LabVIEW or pandas export writes). A cell
  that then also holds a ``.`` (``1.234,5``: a thousands separator) or holds only a
  ``.`` beside cells with ``,`` is ambiguous and is an error naming its row and column,
  never guessed.

A comma-separated file keeps ``.`` as its only decimal mark where a quoted ``"1,5"``
may be a thousands separator: beside a cell with ``.``, or where every comma in the
numeric columns stands before exactly three digits after a whole number (``"1,500"``),
it is the usual "not a number" error. A spreadsheet in a decimal-comma locale set to
separate fields by ``,`` quotes every number (``"8,60","0,030"``): where no numeric cell
has a ``.`` and some comma cannot be a thousands separator (not three digits after it,
or a whole part of 0: ``"8,60"``, ``"0,030"``), the commas are decimal marks (until
2026-12-08 refused as "not a number: '8,60'", benchmarks/lab_rig_sets.py N55).

A first line ``sep=;`` (``sep=,``, ``sep=`` and a tab), which Excel reads and some
exports write above the header, names the separator: the file is read with it, the line
is not data. A ``sep=`` naming any other character is an error saying which it may name.
"""

from __future__ import annotations

import re

from solver.number_text import is_number_text
from surrogate.calibration._errors import DataError

# the separators a file may use, as an error says them
SEPARATORS = {",": "','", ";": "';'", "\t": "a tab"}
_SEP_LINE = re.compile(r'"?sep=(.?)"?[,;\t]*', re.IGNORECASE)


def named_separator(first_line: str) -> str | None:
    """The separator a file's first line ``sep=X`` names (Excel's hint), or None when
    the line is no such hint. Raises DataError when X is not one of ``SEPARATORS``."""
    match = _SEP_LINE.fullmatch(first_line.lstrip("\ufeff").rstrip("\r\n"))
    if match is None:
        return None
    sep = match.group(1)
    if sep not in SEPARATORS:
        raise DataError("header", f"the first line {first_line.strip()[:40]!r} names "
                        f"{sep!r} as the field separator", None,
                        "sep=, sep=; or sep= and a tab (" + ", ".join(SEPARATORS.values())
                        + "), or no sep= line")
    return sep


def separator(header_line: str) -> str:
    """The field separator of a CSV file, from its header line."""
    if "," in header_line:
        return ","
    for sep in (";", "\t"):
        if sep in header_line:
            return sep
    return ","


def is_blank(line: str) -> bool:
    """A line of separators and spaces only: a spreadsheet's empty row (Excel exports a
    row it once formatted as ``;;;;;;``), skipped as a blank line is."""
    return not line.strip(" \t\r\n,;")


def decimal_commas(rows: list[dict[str, object]], numeric: tuple[str, ...], sep: str
                   ) -> list[dict[str, object]]:
    """``rows`` with the decimal commas of their numeric columns read as points, when the
    file is separated by ``sep`` other than ',' and writes its decimals with ','.
    Raises DataError (row 1-based, the column) on a cell whose mark is ambiguous."""
    def cells():
        for i, row in enumerate(rows, start=1):
            for name in numeric:
                value = row.get(name)
                if isinstance(value, str):
                    yield i, name, value

    if not any("," in value for _, _, value in cells()):
        return rows
    if sep == "," and (any("." in value for _, _, value in cells()) or not any(
            _only_decimal(value) for _, _, value in cells() if "," in value)):
        return rows
    for i, name, value in cells():
        if "." in value:
            raise DataError(name, f"{value!r} has a '.' while the file's numbers use ',' "
                            "as the decimal mark (a thousands separator?)", i,
                            "numbers written as the rest of the file writes them, "
                            "'0,75', without thousands separators")
    return [{k: (_point(v) if k in numeric and isinstance(v, str) else v)
             for k, v in row.items()} for row in rows]


def _only_decimal(cell: str) -> bool:
    """A number with one comma that no thousands separator writes: not three digits
    after it, or a whole part of 0 (``8,60``, ``0,030``, ``-1,5``; not ``1,500``)."""
    whole, comma, frac = cell.strip().lstrip("+-").partition(",")
    return (bool(comma) and "," not in frac and whole.isascii() and whole.isdigit()
            and frac.isascii() and frac.isdigit() and (len(frac) != 3 or int(whole) == 0))


def _point(cell: str) -> str:
    """A cell's decimal comma read as a point where that makes it a number; any other
    cell as written (``٨,40`` was refused as ``'٨.40'``, a text the user never wrote)."""
    pointed = cell.replace(",", ".")
    return pointed if is_number_text(pointed) else cell
