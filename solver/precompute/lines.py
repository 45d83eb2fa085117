"""Where a key sits in a TOML text (tomllib parses without positions).

``key_lines(text)`` scans the text once and maps every key path to the span of lines
(1-based, inclusive) of its assignment: ``("L_mm",)``, ``("settings", "mesh_level")``,
``("sweep", 1, "pairs")`` (the second ``[[sweep]]``), ``("materials", "soft", "mu_kpa")``.
Table headers map to their own line (``("sweep", 1)``). It understands comments,
quoted strings and values spread over several lines; that is all a grid file needs.
"""

from __future__ import annotations

import re

HEADER = re.compile(r"^\s*(\[\[?)\s*([A-Za-z0-9_.\-]+)\s*\]\]?\s*$")
ASSIGNMENT = re.compile(r"""^\s*([A-Za-z0-9_\-]+|"[^"]*"|'[^']*')\s*=""")

Path_ = tuple[object, ...]


#: a string (to its closing quote or the line's end) or a comment, as _code finds them
_STRING_OR_COMMENT = re.compile(r"\"[^\"]*\"?|'[^']*'?|#.*")
_BRACKET = re.compile(r"[\[\]{}]")


def _blanked(match: re.Match) -> str:
    found = match[0]
    if found[0] == "#":
        return ""
    closed = len(found) > 1 and found[-1] == found[0]
    return found[0] + " " * (len(found) - 1 - closed) + found[0] * closed


def _code(line: str) -> str:
    """The line without its comment and with string contents blanked (brackets in
    strings do not count). Regular expressions, not a loop over the characters: a
    16 MiB grid is read three times (deepest, longest_key, key_lines)."""
    if '"' not in line and "'" not in line and "#" not in line:
        return line
    return _STRING_OR_COMMENT.sub(_blanked, line)


def key_lines(text: str, until: Path_ | None = None) -> dict[Path_, tuple[int, int]]:
    """Every key path's span of lines; with ``until``, the scan stops once that path's
    span is complete (the lines of a refused key, without the rest of the file)."""
    spans: dict[Path_, tuple[int, int]] = {}
    table: Path_ = ()
    counts: dict[str, int] = {}
    depth = 0
    open_key: Path_ | None = None
    for number, raw in enumerate(text.splitlines(), start=1):
        code = _code(raw)
        if depth == 0:
            header = HEADER.match(code)
            if header:
                name = header.group(2)
                parts: list[object] = list(name.split("."))
                if header.group(1) == "[[":
                    counts[name] = counts.get(name, -1) + 1
                    parts.append(counts[name])
                table = tuple(parts)
                spans[table] = (number, number)
                continue
            assignment = ASSIGNMENT.match(code)
            if assignment:
                open_key = (*table, assignment.group(1).strip("\"'"))
                spans[open_key] = (number, number)
                code = code[assignment.end():]
        depth += code.count("[") + code.count("{") - code.count("]") - code.count("}")
        depth = max(depth, 0)
        if open_key is not None:
            spans[open_key] = (spans[open_key][0], number)
            if depth == 0:
                open_key = None
        if until is not None and open_key is None and until in spans:
            break
    return spans


def line_of(text_lines: list[str], spans: dict[Path_, tuple[int, int]], path: Path_,
            needle: str | None = None) -> int:
    """The line of ``path`` (or of its nearest enclosing table); with ``needle``, the first
    line of the key's span that contains it."""
    probe = tuple(path)
    while probe and probe not in spans:
        probe = probe[:-1]
    if not probe:
        return 1
    first, last = spans[probe]
    if needle is not None:
        for number in range(first, last + 1):
            if needle in text_lines[number - 1]:
                return number
    return first


def deepest(text: str) -> tuple[int, int]:
    """(depth, line) of the deepest nesting of [ ] and { } in the values (table headers
    such as ``[[sweep]]`` do not count)."""
    best, at, depth = 0, 1, 0
    for number, raw in enumerate(text.splitlines(), start=1):
        if not _BRACKET.search(raw):
            continue      # the depth is unchanged
        code = _code(raw)
        if depth == 0 and HEADER.match(code):
            continue
        for ch in code:
            if ch in "[{":
                depth += 1
                if depth > best:
                    best, at = depth, number
            elif ch in "]}":
                depth = max(depth - 1, 0)
    return best, at


def longest_key(text: str) -> tuple[int, int]:
    """(parts, line) of the longest dotted name -- a key (``a.b.c = 1``) or a table header
    (``[a.b.c]``) -- counted per line, strings as one part each. tomllib keeps every
    prefix of a dotted key, so a key of n parts costs it n^2: one of 50,000 parts (a
    100 kB line) took 88 s and 9.9 GB before any check."""
    best, at = 1, 1
    for number, raw in enumerate(text.splitlines(), start=1):
        if "." not in raw:
            continue      # one part at most
        code = re.sub(r"\s*\.\s*", ".", re.sub(r"\"[^\"]*\"|'[^']*'", "q", _code(raw)))
        parts = max((t.count(".") + 1 for t in re.split(r"[\s=,\[\]{}]+", code) if t),
                    default=0)
        if parts > best:
            best, at = parts, number
    return best, at
