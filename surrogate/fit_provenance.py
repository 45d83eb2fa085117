"""What a fitted model file says about how it was made, so that it can be made again.

A model file (the emulator, the exponential surrogate) records the code that fitted it
(package version and git commit, marked ``+dirty`` when the code differed from that
commit: ``solver.store.record.git_commit``), the command that reproduces the fit, and
each input database by name, record count and SHA-256 of its bytes -- the name, never
the path on the machine that made it. The shipped emulator of 2026-12-05 recorded a
commit whose code writes an older file format, and no checksum of the data it came from.
"""

from __future__ import annotations

import hashlib
import time
from pathlib import Path


def file_sha256(path: str | Path) -> str:
    """SHA-256 (hex) of the file's bytes (0.2 s for the shipped 30 MB database)."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def database_entry(path: str | Path, records: int) -> dict[str, object]:
    """An input database as a model file records it: name, records, checksum."""
    return {"name": Path(path).name, "records": int(records), "sha256": file_sha256(path)}


def refit_step(command: str) -> dict[str, str]:
    """A last step of the fit run alone on a model file (a band recalibration without a
    refit), as its provenance records it: the code's commit, when (UTC), the command."""
    from solver.store.record import git_commit

    return {"git_commit": git_commit(),
            "created_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
            "command": command}
