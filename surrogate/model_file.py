"""A model's JSON file (an emulator, an exponential model) read whole, never past a bound.

``Path.read_bytes`` reads to the end: ``balloon precompute GRID --db DB --adaptive 2
--emulator /dev/zero`` grew without bound and ended in a MemoryError traceback. The
shipped emulator is 33 MB (loading it takes about 20x that in memory); a file 8x as
large is still read, anything larger is refused at ``model`` before it is parsed.
"""

from __future__ import annotations

from pathlib import Path

from solver.bounded_read import read_bounded

MAX_MODEL_FILE_BYTES = 256 * 2**20


def read_model_file(path: Path) -> bytes:
    """The bytes of the model file ``path`` (messages name the file, never its
    directory: the service sends them to clients). FileNotFoundError and
    IsADirectoryError as ``open`` raises them (the CLI names the option that gave the
    path); InputError at ``model`` past ``MAX_MODEL_FILE_BYTES``."""
    return read_bounded(path, MAX_MODEL_FILE_BYTES, "model", "a model file (JSON)",
                        shown=path.name)
