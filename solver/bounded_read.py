"""An input file the user names, read whole but never past a bound.

``Path.read_bytes`` reads to the end: /dev/zero, a pipe that does not end, or a stray
10 GB file fills the memory before any check of its content can speak (``balloon
precompute /dev/zero`` grew to 2.7 GB and ended in a MemoryError traceback; ``balloon
calibrate /dev/zero`` likewise). An input file that is read whole is read here: at most
``max_bytes`` and one byte more, which tells that it is larger.

Only a regular file is read: a named pipe (FIFO) with no writer blocked ``balloon
calibrate FIFO`` and ``balloon precompute FIFO`` in ``open`` for ever, and a device is no
data file (``/dev/zero`` was read to the bound first). The file is opened without
waiting for a writer and what was opened is checked, so no swap of the name between a
check and the open can hang the command either.
"""

from __future__ import annotations

import errno
import os
import stat
from pathlib import Path

from solver.errors import InputError

NOT_REGULAR = "not a regular file (a device or a pipe)"


def read_bounded(path: Path, max_bytes: int, field: str, what: str,
                 shown: str | None = None) -> bytes:
    """The bytes of ``path``; an InputError at ``field`` when it holds more than
    ``max_bytes`` (``what`` names the file's kind in the allowed range: "a grid file";
    ``shown``, how the message names the file: by default the path as given)."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)   # a FIFO opens without a writer
    except OSError as exc:
        if exc.errno == errno.ENXIO:    # a socket: nothing to open
            raise _not_regular(field, what, shown or path) from None
        raise
    kind = os.fstat(fd).st_mode
    if not stat.S_ISREG(kind):
        os.close(fd)
        if stat.S_ISDIR(kind):   # as open() says it: the CLI names the file's argument
            raise IsADirectoryError(errno.EISDIR, os.strerror(errno.EISDIR), str(path))
        raise _not_regular(field, what, shown or path)
    os.set_blocking(fd, True)
    with os.fdopen(fd, "rb") as file:
        data = file.read(max_bytes + 1)
    if len(data) > max_bytes:
        size = f"{max_bytes / 2**20:g} MiB"
        raise InputError(field, f"{shown or path}: larger than {size}", f"{what} of at most {size}")
    return data


def _not_regular(field: str, what: str, shown: object) -> InputError:
    return InputError(field, f"{shown}: {NOT_REGULAR}", f"{what}, a regular file")
