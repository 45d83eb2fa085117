"""Errors of the surrogate layer (all derive from ``solver.errors``):

    InputError
    ├── OutOfFamilyError       the design's family (material pair, T, b, h) is not fitted;
    │                          the message says which precompute to run
    └── SurrogateFileError     a surrogate file is unreadable or of a newer format version
    BalloonError
    └── Cancelled              long work stopped because its caller no longer wants it
"""

from __future__ import annotations

import threading

from solver.errors import BalloonError, InputError


class OutOfFamilyError(InputError):
    """The surrogate has no fitted family for this design; ``family`` is the design's
    family tuple (body id, membrane id, T_mm, b_mm, h_mm); ``allowed`` the fitted families
    (the message says them in its place)."""

    def __init__(self, message: str, family: tuple = (), allowed: str | None = None) -> None:
        super().__init__("design", message, allowed, allowed_said=True)
        self.family = family


class SurrogateFileError(InputError):
    """A surrogate JSON file cannot be used (corrupt, not a surrogate, newer format)."""

    def __init__(self, path: str, message: str) -> None:
        super().__init__("model", f"{path}: {message}")
        self.path = path


class Cancelled(BalloonError):
    """Long work (a calibration, a design search) stopped at a loop boundary because its
    caller set the ``cancel`` event it was given (the service: its HTTP client
    disconnected). Nothing is answered or saved."""


def stop_if_cancelled(cancel: threading.Event | None) -> None:
    """Raise Cancelled when ``cancel`` is set; the long loops call it at their natural
    boundaries (a fit, a cross-validation, a batch of designs screened), so the work
    stops within one of them. ``None``: never cancelled (the CLI, scripts)."""
    if cancel is not None and cancel.is_set():
        raise Cancelled("stopped: the caller no longer wants the answer")
