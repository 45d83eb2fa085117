"""Errors of the curve database (all derive from solver.errors.BalloonError)."""

from __future__ import annotations

from solver.errors import BalloonError, InputError


class SchemaVersionError(BalloonError):
    """The file was written by a newer schema than this code can read."""


class StoreBusyError(BalloonError):
    """Another process already holds the database's single writer lock."""


class NotACurveStoreError(InputError):
    """The file exists but is not a curve database (or is damaged)."""
