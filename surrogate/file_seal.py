"""The content checksum of a model file (surrogate and emulator JSON): any change to a
file after it was written -- a flipped digit, a hand edit, a truncated array that still
parses -- is refused on load, never turned into a different number.

``seal(doc)`` adds ``"content_sha256"``: the sha256 of the document without it, as
canonical JSON (sorted keys; Python's float repr round-trips exactly, so reading and
re-serialising gives the same bytes). ``check_seal(doc, origin)`` verifies it; a file
of older code has none and is checked only by its structure and a trial prediction.
"""

from __future__ import annotations

import hashlib
import json

from surrogate.errors import SurrogateFileError

KEY = "content_sha256"


def _digest(doc: dict) -> str:
    body = {k: v for k, v in doc.items() if k != KEY}
    text = json.dumps(body, sort_keys=True, separators=(",", ":"), allow_nan=False)
    return hashlib.sha256(text.encode()).hexdigest()


def seal(doc: dict) -> dict:
    """``doc`` with its content checksum."""
    return {**doc, KEY: _digest(doc)}


def check_seal(doc: dict, origin: str) -> None:
    """SurrogateFileError when ``doc`` carries a checksum that does not match it."""
    stored = doc.get(KEY)
    if stored is None:
        return
    try:
        found = _digest(doc)
    except (TypeError, ValueError):
        found = None
    if stored != found:
        raise SurrogateFileError(origin, "its content changed since it was written (the "
                                 "content_sha256 checksum does not match): refit it with "
                                 "`balloon fit`, or restore it")
