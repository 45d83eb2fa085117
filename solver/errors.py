"""The exception tree of the whole project (every package derives from it).

    BalloonError                  anything this project raises on purpose
    ├── InputError (ValueError)   a user-supplied value is out of range or unknown;
    │                             carries the field name and the allowed range
    ├── NotFoundError (KeyError)  a named thing (record, material, model) does not exist
    ├── ExistsError               a named thing to be created already exists
    └── SolverError               the finite-element solve could not proceed
        └── ConvergenceError      Newton failed even after the step was cut back

Messages say what was wrong and what to do; the CLI prints them on one line and
the HTTP layer maps each class to one status code.
"""

from __future__ import annotations


class BalloonError(Exception):
    """Base class of every deliberate error in this project."""


class InputError(BalloonError, ValueError):
    """A user-supplied value is invalid.

    ``field`` names the offending input (e.g. ``"t_mm"``), ``allowed`` states the
    allowed range or values in words (e.g. ``"0.05 <= t_mm <= 5"``), said after the
    message unless ``allowed_said``: the message says it already, in its place.
    """

    def __init__(self, field: str, message: str, allowed: str | None = None, *,
                 allowed_said: bool = False) -> None:
        self.field = field
        self.allowed = allowed
        self.detail = message
        self.allowed_said = allowed_said
        text = f"{field}: {message}"
        if allowed and not allowed_said:
            text += f" (allowed: {allowed})"
        super().__init__(text)


class NotFoundError(BalloonError, KeyError):
    """A named object (record, material, saved model, job) does not exist."""

    def __str__(self) -> str:  # KeyError would add quotes around the message
        return str(self.args[0]) if self.args else "not found"


class ExistsError(BalloonError):
    """A named object (a saved model) cannot be created: one of that name already exists."""


class SolverError(BalloonError):
    """The finite-element solve could not proceed."""


class ConvergenceError(SolverError):
    """Newton's method failed to converge even after cutting the step back."""
