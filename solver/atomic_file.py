"""Write a small text file atomically: readers see the old file or the new one, never half.

The text goes to a temporary file in the same directory, is flushed and fsynced, given
the permissions an ordinary ``open(path, "w")`` would have (0666 less the umask, not
``mkstemp``'s 0600), and ``os.replace``d over the target. If anything fails the
temporary file is removed and the old file is untouched. ``write_text_exclusive``
creates a new file the same way but hard-links it into place, which fails when the
name exists: of two concurrent creates exactly one wins (not check-then-replace).
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path


def _default_mode() -> int:
    umask = os.umask(0)
    os.umask(umask)
    return 0o666 & ~umask


def _publish(path: Path, text: str, exclusive: bool) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, _default_mode())
        if exclusive:
            os.link(tmp, path)  # FileExistsError when the name is taken
            os.unlink(tmp)
        else:
            os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def write_text_atomic(path: str | os.PathLike, text: str) -> Path:
    """Replace ``path`` with ``text`` (UTF-8) atomically, creating parent folders."""
    return _publish(Path(path), text, exclusive=False)


def write_text_exclusive(path: str | os.PathLike, text: str) -> Path:
    """Create ``path`` with ``text`` (UTF-8) atomically; FileExistsError if it exists."""
    return _publish(Path(path), text, exclusive=True)
