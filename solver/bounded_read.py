"""An input file the user names, read whole but never past a bound.

``Path.read_bytes`` reads to the end: /dev/zero, a pipe that does not end, or a stray
10 GB file fills the memory before any check of its content can speak (``balloon
precompute /dev/zero`` grew to 2.7 GB and ended in a MemoryError traceback; ``balloon
calibrate /dev/zero`` likewise). An input file that is read whole is read here: at most
``max_bytes`` and one byte more, which tells that it is larger.
"""

from __future__ import annotations

from pathlib import Path

from solver.errors import InputError


def read_bounded(path: Path, max_bytes: int, field: str, what: str,
                 shown: str | None = None) -> bytes:
    """The bytes of ``path``; an InputError at ``field`` when it holds more than
    ``max_bytes`` (``what`` names the file's kind in the allowed range: "a grid file";
    ``shown``, how the message names the file: by default the path as given)."""
    with path.open("rb") as file:
        data = file.read(max_bytes + 1)
    if len(data) > max_bytes:
        size = f"{max_bytes / 2**20:g} MiB"
        raise InputError(field, f"{shown or path}: larger than {size}", f"{what} of at most {size}")
    return data
