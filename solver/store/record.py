"""One database record: a design, its solver settings, the curve and where it came from.

Provenance keys (all plain JSON values):

    package_version   version of the ``balloon-actuator`` distribution that solved it
    git_commit        commit of the source tree when run from a git checkout, else ""
    created_utc       ISO 8601 UTC time the record was made
    wall_time_s       wall-clock seconds the solve took, s
    status, reason    the curve's status ("complete" | "stopped" | "failed") and why
    host              host name of the machine (or cluster worker) that solved it
"""

from __future__ import annotations

import socket
import subprocess
from dataclasses import dataclass, field
from datetime import UTC, datetime
from functools import lru_cache
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

import numpy as np

from solver.curve import Curve
from solver.design import Design
from solver.settings import SolverSettings
from solver.store.keys import record_key

PROVENANCE_KEYS = ("package_version", "git_commit", "created_utc", "wall_time_s", "status",
                   "reason", "host")


@dataclass(frozen=True)
class Record:
    """A stored solve. ``key`` is ``record_key(design, settings)``."""

    key: str
    design: Design
    settings: SolverSettings
    curve: Curve
    provenance: dict = field(default_factory=dict)

    @property
    def status(self) -> str:
        return self.curve.status

    def as_dict(self) -> dict[str, object]:
        """Plain-JSON view: key, design, settings, curve (lists) and provenance."""
        return {"key": self.key, "design": self.design.as_dict(),
                "settings": self.settings.as_dict(), "curve": self.curve.as_dict(),
                "provenance": dict(self.provenance)}


@lru_cache(maxsize=1)
def package_version() -> str:
    try:
        return version("balloon-actuator")
    except PackageNotFoundError:
        return "0+unknown"


# The code a result depends on, relative to the checkout's root: what ``git_commit``
# checks for changes against HEAD (the shipped data files the fit writes are not code).
CODE_PATHS = ("solver", "surrogate", "service", "pyproject.toml", ":(exclude)service/data")


@lru_cache(maxsize=1)
def git_commit() -> str:
    """HEAD of the checkout this code runs from, with ``+dirty`` when a tracked file of
    the code (CODE_PATHS) differs from it: a result made by uncommitted code names the
    commit it started from and says that it is not that commit's ("" outside git or
    without git)."""
    here = Path(__file__).resolve().parent
    try:
        out = subprocess.run(["git", "rev-parse", "HEAD"], cwd=here, capture_output=True,
                             text=True, timeout=5, check=False)
        if out.returncode != 0:
            return ""
        top = subprocess.run(["git", "rev-parse", "--show-toplevel"], cwd=here,
                             capture_output=True, text=True, timeout=5, check=False)
        changed = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no", "--", *CODE_PATHS],
            cwd=top.stdout.strip() or here, capture_output=True, text=True, timeout=10,
            check=False)
    except (OSError, subprocess.SubprocessError):
        return ""
    dirty = changed.returncode == 0 and bool(changed.stdout.strip())
    return out.stdout.strip() + ("+dirty" if dirty else "")


def utc_now() -> str:
    return datetime.now(UTC).isoformat(timespec="seconds")


def make_provenance(curve: Curve, wall_time_s: float | None = None) -> dict[str, object]:
    """Provenance of a solve finished just now on this host."""
    return {"package_version": package_version(), "git_commit": git_commit(),
            "created_utc": utc_now(),
            "wall_time_s": float(curve.wall_time_s if wall_time_s is None else wall_time_s),
            "status": curve.status, "reason": curve.reason, "host": socket.gethostname()}


def make_record(design: Design, settings: SolverSettings, curve: Curve,
                wall_time_s: float | None = None) -> Record:
    """A Record with its key and this host's provenance."""
    design = design.validated()
    settings = settings.validated()
    return Record(record_key(design, settings), design, settings, curve,
                  make_provenance(curve, wall_time_s))


def failed_curve(reason: str, wall_time_s: float = 0.0) -> Curve:
    """An empty curve with status "failed": used when a solve raised instead of returning."""
    empty = np.zeros(0)
    return Curve(pressure_pa=empty, volume_ul=empty, time_s=empty, angle_deg=empty,
                 tip_displacement_mm=np.zeros((0, 2)), max_membrane_stretch=empty,
                 force_mn=empty, newton_iterations=np.zeros(0, dtype=np.int64),
                 residual_norm=empty, negative_eigenvalues=np.zeros(0, dtype=np.int64),
                 status="failed", reason=reason, wall_time_s=float(wall_time_s))
