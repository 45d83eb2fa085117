"""Output paths checked before a command spends minutes on its work: one rule for
every file a command writes (``balloon solve``, ``fit``, ``calibrate``, ``db export``).

A path is refused, naming its option, when it is a directory, names something that is
not a regular file (a device, a pipe: the atomic write would replace it -- `fit -o
/dev/full` did), lies in a directory that does not exist or cannot be written (tried
with a temporary file there, which root's permissions do not fake), or has a suffix the
writer cannot produce."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from solver.errors import InputError

# what matplotlib writes (Figure.savefig by suffix) and meshio writes for --vtk
PLOT_SUFFIXES = (".png", ".pdf", ".svg", ".jpg", ".jpeg", ".eps", ".ps", ".tif", ".tiff",
                 ".webp")
VTK_SUFFIXES = (".vtu", ".vtk")


def check_output(path: str | os.PathLike | None, option: str,
                 suffixes: tuple[str, ...] | None = None) -> None:
    """InputError naming ``option`` unless ``path`` (None: not asked) can be written as a
    new or replaced regular file with one of ``suffixes`` (any when None)."""
    if path is None or str(path) == "-":
        return
    target = Path(path)
    if target.is_dir():
        raise InputError(option, f"{path} is a directory", "a file path")
    if target.exists() and not target.is_file():
        raise InputError(option, f"{path} is not a regular file (a device or a pipe): it "
                         "would be replaced", "a path to a regular file")
    parent = target.parent
    if not parent.is_dir():
        raise InputError(option, f"directory {parent} does not exist",
                         "a path in an existing directory")
    try:
        with tempfile.NamedTemporaryFile(dir=parent, prefix=".balloon-check-"):
            pass
    except OSError as exc:
        raise InputError(option, f"directory {parent} cannot be written "
                         f"({exc.strerror or type(exc).__name__})",
                         "a path in a writable directory") from None
    if suffixes is not None and target.suffix.lower() not in suffixes:
        raise InputError(option, f"{path}: cannot write a {target.suffix or 'suffix-less'} "
                         "file", "a path ending in " + ", ".join(suffixes))


def check_output_dir(path: str | os.PathLike | None, option: str) -> None:
    """As ``check_output`` for a directory a command creates or fills (``--report-dir``)."""
    if path is None:
        return
    target = Path(path)
    if target.exists() and not target.is_dir():
        raise InputError(option, f"{path} is a file", "a directory path")
    base = target if target.is_dir() else target.parent
    check_output(base / "report.json", option)
