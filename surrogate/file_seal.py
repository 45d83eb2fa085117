"""The content checksum of a model file (surrogate and emulator JSON): any change to a
file after it was written -- a flipped digit, a hand edit, a truncated array that still
parses -- is refused on load, never turned into a different number.

``seal(doc)`` adds ``"content_sha256"``: the sha256 of the document without it, as
canonical JSON (sorted keys; Python's float repr round-trips exactly, so reading and
re-serialising gives the same bytes). ``check_seal(doc, origin)`` verifies it; a file
of older code has none and is checked only by its structure and a trial prediction.
``check_header`` checks the format name and version every model file starts with.
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


def check_header(doc: object, format_name: str, reads_up_to: int, kind: str,
                 origin: str) -> int:
    """The file's format version, after checking that ``doc`` is a ``format_name`` file
    (``kind``: "a surrogate", "an emulator", for the message) of a version this code
    reads (at most ``reads_up_to``); SurrogateFileError otherwise."""
    if not isinstance(doc, dict) or doc.get("format") != format_name:
        raise SurrogateFileError(origin, f"not {kind} file (no \"format\": "
                                 f"\"{format_name}\")")
    version = doc.get("format_version")
    if not isinstance(version, int) or version > reads_up_to:
        raise SurrogateFileError(origin, f"format version {version!r} is newer than this "
                                 f"code reads ({reads_up_to}); upgrade balloon-actuator")
    return version
