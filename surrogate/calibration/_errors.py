"""Errors of the calibration package (all derive from the project tree in solver.errors).

    InputError
    └── DataError        a measured-data file or row is invalid; names the row and column
    NotFoundError
    └── ModelNotFoundError  no saved calibrated model of that name
"""

from __future__ import annotations

from solver.errors import InputError, NotFoundError


class DataError(InputError):
    """Invalid measured data. ``row`` is the 1-based data row (the CSV header is row 0),
    ``column`` the column name; nothing of the file is used when this is raised."""

    def __init__(self, column: str, message: str, row: int | None = None,
                 allowed: str | None = None) -> None:
        self.row = row
        self.column = column
        where = f"row {row}: " if row is not None else ""
        super().__init__(column, where + message, allowed)


class ModelNotFoundError(NotFoundError):
    """No saved calibrated model of that name in the models directory."""
