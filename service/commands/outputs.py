"""Output paths checked before a command spends minutes on its work: one rule for
every file a command writes (``balloon solve``, ``fit``, ``calibrate``, ``db export``).

A path is refused, naming its option, when it is a directory, names something that is
not a regular file (a device, a pipe: the atomic write would replace it -- `fit -o
/dev/full` did), lies in a directory that does not exist or cannot be written (tried
with a temporary file there, which root's permissions do not fake), or has a suffix the
writer cannot produce; and when it is the file the command reads (by any name: a
symlink or a hard link too) or an existing HDF5 file, which no command writes by these
options (`db export C.h5 -o C.h5` replaced the curve database with its CSV and said
"exported 2404 records"; `-o other.h5` did the same to another database, whose sealed
header hid its HDF5 signature from a check at byte 0), or a curve database's lock file
(replaced, it lets a second writer in beside the one that holds the old one); and when
two outputs of one command name one file (``distinct_outputs``: `fit -o m.json
--emulator-output m.json` wrote the exponential model, then the emulator over it)."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from solver.errors import InputError
from solver.store.integrity import HDF5_HEAD_BYTES, looks_like_hdf5
from solver.store.locking import JOB_SUFFIX, WRITER_SUFFIX

# what matplotlib writes (Figure.savefig by suffix) and meshio writes for --vtk
PLOT_SUFFIXES = (".png", ".pdf", ".svg", ".jpg", ".jpeg", ".eps", ".ps", ".tif", ".tiff",
                 ".webp")
VTK_SUFFIXES = (".vtu", ".vtk")


def is_hdf5(path: Path) -> bool:
    """Whether the regular file ``path`` is an HDF5 file (a curve database, sealed or
    not: solver/store/integrity.py)."""
    with open(path, "rb") as f:
        return looks_like_hdf5(f.read(HDF5_HEAD_BYTES))


def locked_database(path: Path) -> str | None:
    """The name of the HDF5 file whose writer or job lock ``path`` is (``<db>.lock``,
    ``<db>.job.lock``: solver/store/locking.py), else None."""
    for suffix in (JOB_SUFFIX, WRITER_SUFFIX):
        if path.name.endswith(suffix):
            database = path.with_name(path.name[:-len(suffix)])
            if database.is_file() and is_hdf5(database):
                return database.name
    return None


def check_output(path: str | os.PathLike | None, option: str,
                 suffixes: tuple[str, ...] | None = None,
                 inputs: tuple[tuple[str, str | os.PathLike | None], ...] = ()) -> None:
    """InputError naming ``option`` unless ``path`` (None: not asked) can be written as a
    new or replaced regular file with one of ``suffixes`` (any when None) without
    destroying what the command reads: ``inputs`` are (name, path) of its input files."""
    if path is None or str(path) == "-":
        return
    target = Path(path)
    if target.is_dir():
        raise InputError(option, f"{path} is a directory", "a file path")
    if target.exists() and not target.is_file():
        raise InputError(option, f"{path} is not a regular file (a device or a pipe): it "
                         "would be replaced", "a path to a regular file")
    if target.exists():
        for name, source in inputs:
            if source is not None and Path(source).exists() and os.path.samefile(target,
                                                                                   source):
                raise InputError(option, f"{path} is the file this command reads ({name}): "
                                 "writing it would destroy it",
                                 f"a path other than {name}'s")
        if is_hdf5(target):
            raise InputError(option, f"{path} is an HDF5 file (a curve database?): "
                             "this would replace it", "a path that is not an HDF5 file")
    database = locked_database(target)
    if database is not None:
        raise InputError(option, f"{path} is the lock file of the curve database "
                         f"{database}: replacing it would let two writers in at once",
                         "a path that is not a database's lock file")
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


def distinct_outputs(outputs: tuple[tuple[str, str | os.PathLike | None], ...]) -> None:
    """InputError naming the later option unless the (option, path) ``outputs`` of one
    command name different files (by any name: a symlink, ``./``, a hard link): the
    second write would replace the first, after the work, without a word."""
    seen: list[tuple[str, Path]] = []
    for option, path in outputs:
        if path is None or str(path) == "-":
            continue
        target = Path(path)
        for earlier, other in seen:
            if (target.resolve() == other.resolve()
                    or (target.exists() and other.exists() and os.path.samefile(target, other))):
                raise InputError(option, f"{path} is also {earlier}'s file: the second "
                                 "write would replace the first", f"a path other than {earlier}'s")
        seen.append((option, target))


def check_output_dir(path: str | os.PathLike | None, option: str) -> None:
    """As ``check_output`` for a directory a command creates or fills (``--report-dir``)."""
    if path is None:
        return
    target = Path(path)
    if target.exists() and not target.is_dir():
        raise InputError(option, f"{path} is a file", "a directory path")
    base = target if target.is_dir() else target.parent
    check_output(base / "report.json", option)
