"""Write a file atomically: readers see the old file or the new one, never half.

The content goes to a temporary file in the same directory (its name keeps the target's
suffix, by which matplotlib and meshio choose a format), is flushed and fsynced, given
the permissions an ordinary ``open(path, "w")`` would have (0666 less the umask, not
``mkstemp``'s 0600), and ``os.replace``d over the target. If anything fails -- a full
disk, a file-size limit, Ctrl-C -- the temporary file is removed and the old file is
untouched (`balloon db export` and `balloon solve --csv` had left a truncated file in
place of the former one). ``atomic_output`` does this for any writer given a path;
``write_text_exclusive`` creates a new file the same way but hard-links it into place,
which fails when the name exists: of two concurrent creates exactly one wins (not
check-then-replace). An OSError of the write names the target, not the temporary file.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path


def _default_mode() -> int:
    umask = os.umask(0)
    os.umask(umask)
    return 0o666 & ~umask


@contextmanager
def atomic_output(path: str | os.PathLike, exclusive: bool = False,
                  keep_suffix: bool = False) -> Iterator[Path]:
    """A temporary path beside ``path`` to write to (``.<name>.<8 characters>.tmp``, the
    form a saved model's cleanup knows; with ``keep_suffix``, ``path``'s suffix after
    it, for writers that choose a format by it); when the block ends normally it is
    fsynced and renamed over ``path`` (with ``exclusive``, linked to it: FileExistsError
    when the name is taken), else removed."""
    path = Path(path)
    fd, name = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent,
                                suffix=".tmp" + (path.suffix if keep_suffix else ""))
    os.close(fd)
    tmp = Path(name)
    try:
        yield tmp
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        os.chmod(tmp, _default_mode())
        if exclusive:
            os.link(tmp, path)
            tmp.unlink()
        else:
            os.replace(tmp, path)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        if exc.filename is None or str(exc.filename) == str(tmp):  # the target, by name
            raise type(exc)(exc.errno, exc.strerror, str(path)) from None
        raise
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def _publish(path: Path, text: str, exclusive: bool) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_output(path, exclusive) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return path


def write_text_atomic(path: str | os.PathLike, text: str) -> Path:
    """Replace ``path`` with ``text`` (UTF-8) atomically, creating parent folders."""
    return _publish(Path(path), text, exclusive=False)


def write_text_exclusive(path: str | os.PathLike, text: str) -> Path:
    """Create ``path`` with ``text`` (UTF-8) atomically; FileExistsError if it exists."""
    return _publish(Path(path), text, exclusive=True)
