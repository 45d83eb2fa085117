"""Errors of the surrogate layer (all derive from ``solver.errors``):

    InputError
    ├── OutOfFamilyError       the design's family (material pair, T, b, h) is not fitted;
    │                          the message says which precompute to run
    └── SurrogateFileError     a surrogate file is unreadable or of a newer format version
"""

from __future__ import annotations

from solver.errors import InputError


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
