"""What a saved calibrated model's name finds in the models directory, before it is read.

``load_model`` reads ``<models_dir>/<name>.json`` when it is a file and answers "no such
model" otherwise, so a named pipe (FIFO), a device or a socket put there under a model's
name, or a directory named like a model file, was answered 404 "no saved model", which
sent the user to look for a name that is there; and a symbolic link was followed
wherever it led, so a link placed in the directory made the server read (and answer
by) a JSON file from anywhere on its disk. Each is a fault of the server's directory,
said as one (503), naming the model and the kind of entry, never its path.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path


def saved_file_fault(models_dir: Path, name: str) -> str | None:
    """Why the entry for model ``name`` (a name of NAME_PATTERN's form) in ``models_dir``
    is no saved model's file, in words; None when it is a regular file -- directly, or by
    a symbolic link to one inside the directory -- or when there is no entry."""
    path = models_dir / f"{name}.json"
    try:
        mode = os.lstat(path).st_mode
    except OSError:         # no entry (or no directory): load_model's "no model"
        return None
    if stat.S_ISLNK(mode):
        try:
            target = path.resolve(strict=True)
            inside = target.is_relative_to(models_dir.resolve(strict=True))
            mode = os.stat(target).st_mode
        except (OSError, RuntimeError):     # dangling, or a loop of links
            return "a symbolic link to nothing"
        if not inside:
            return "a symbolic link out of the models directory"
    if stat.S_ISDIR(mode):
        return "a directory"
    if not stat.S_ISREG(mode):
        return "not a regular file (a device, a pipe or a socket)"
    return None
