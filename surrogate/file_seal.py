"""The content checksum of a model file (surrogate, emulator and saved calibrated-model
JSON): any change to a file after it was written -- a flipped digit, a hand edit, a
truncated array that still parses -- is refused on load, never turned into a different
number.

``seal(doc)`` adds ``"content_sha256"``: the sha256 of the document without it, as
canonical JSON (sorted keys; Python's float repr round-trips exactly, so reading and
re-serialising gives the same bytes). ``check_seal(doc, origin)`` verifies it
(``seal_broken``: whether it fails, for a caller with its own words: the saved calibrated
models, surrogate/calibration/_saved.py); a file of older code has none and is checked
only by its structure (and a trial prediction, or a flag on every answer of a saved
model).
``canonical_text(doc)`` is that canonical JSON: a file written as it (the emulator's) is
verified from its bytes (``check_seal(..., raw=...)``: the checksum's member cut out and
the rest hashed, no re-serialisation of a 30 MB document; any other text falls back to
the canonical form of what was parsed).
``check_header`` checks the format name and version every model file starts with.
"""

from __future__ import annotations

import hashlib
import json

from surrogate.errors import SurrogateFileError

KEY = "content_sha256"


def canonical_text(doc: dict) -> str:
    """``doc`` as canonical JSON: sorted keys, no spaces, no NaN."""
    return json.dumps(doc, sort_keys=True, separators=(",", ":"), allow_nan=False)


def _digest(doc: dict) -> str:
    body = {k: v for k, v in doc.items() if k != KEY}
    return hashlib.sha256(canonical_text(body).encode()).hexdigest()


def _raw_matches(raw: bytes, stored: str) -> bool:
    """Whether ``raw`` is a canonical text whose body (the checksum's member cut out)
    hashes to ``stored``: then, sha256 being collision resistant, the body is the very
    canonical JSON that was sealed, and what was parsed from ``raw`` is what was written."""
    member = f'"{KEY}":"{stored}"'.encode()
    for cut in (b"," + member, member + b","):
        at = raw.find(cut)
        if at >= 0:
            body = raw[:at] + raw[at + len(cut):]
            return hashlib.sha256(body).hexdigest() == stored
    return False


def seal(doc: dict) -> dict:
    """``doc`` with its content checksum."""
    return {**doc, KEY: _digest(doc)}


def seal_broken(doc: dict, raw: bytes | None = None) -> bool:
    """Whether ``doc`` carries a checksum that does not match it (False without one);
    ``raw``, the bytes ``doc`` was parsed from, when at hand (a canonical file is checked
    on them)."""
    stored = doc.get(KEY)
    if stored is None:
        return False
    if raw is not None and isinstance(stored, str) and _raw_matches(raw, stored):
        return False
    try:
        found = _digest(doc)
    except (TypeError, ValueError):
        found = None
    return stored != found


def check_seal(doc: dict, origin: str, raw: bytes | None = None) -> None:
    """SurrogateFileError when ``doc`` carries a checksum that does not match it
    (``seal_broken``)."""
    if seal_broken(doc, raw):
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
