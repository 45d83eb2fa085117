"""Surrogate files: versioned JSON.

    {"format": "balloon-surrogate", "format_version": 2, "name", "form", "provenance"
     (database path and metadata, record keys, package version, git commit, date),
     "families": [Family.as_dict()...], "report": {...the fit report...}}

Format versions: 2 stores each parameter covariance in the fit coordinates
(``covariance_names``: log10 b_t in place of b_t); 1 stored it in b_t (1/mm) and is
still read (converted on load, same bands). Writes are atomic (temporary file +
rename): a failed save leaves the old file intact. A file of a newer format version
than this code reads is refused with SurrogateFileError.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from solver.atomic_file import write_text_atomic
from solver.errors import NotFoundError
from surrogate.core import Surrogate
from surrogate.errors import SurrogateFileError
from surrogate.family import family_from_dict
from surrogate.fit import FORMAT_VERSION, _plain

FORMAT_NAME = "balloon-surrogate"


def surrogate_to_dict(s: Surrogate) -> dict:
    return {"format": FORMAT_NAME, "format_version": FORMAT_VERSION, "name": s.name,
            "form": s.form, "provenance": _plain(s.provenance),
            "families": [_plain(f.as_dict()) for f in s.family_fits],
            "report": _plain(s.report)}


def surrogate_from_dict(d: dict, origin: str = "<dict>") -> Surrogate:
    if not isinstance(d, dict) or d.get("format") != FORMAT_NAME:
        raise SurrogateFileError(origin, f"not a surrogate file (no \"format\": "
                                 f"\"{FORMAT_NAME}\")")
    version = d.get("format_version")
    if not isinstance(version, int) or version > FORMAT_VERSION:
        raise SurrogateFileError(origin, f"format version {version!r} is newer than this "
                                 f"code reads ({FORMAT_VERSION}); upgrade balloon-actuator")
    try:
        families = tuple(family_from_dict(f, version) for f in d["families"])
        return Surrogate(name=str(d["name"]), family_fits=families,
                         provenance=dict(d.get("provenance", {})), form=d.get("form"),
                         report=dict(d.get("report", {})))
    except (KeyError, TypeError, ValueError) as exc:
        raise SurrogateFileError(origin, f"malformed surrogate file ({exc!r})") from None


def save_surrogate(s: Surrogate, path: str | os.PathLike) -> Path:
    """Write ``s`` as JSON to ``path`` atomically; returns the path."""
    text = json.dumps(surrogate_to_dict(s), indent=1, allow_nan=False)
    return write_text_atomic(path, text)


def load_surrogate(path: str | os.PathLike) -> Surrogate:
    """Read a surrogate file; NotFoundError when missing, SurrogateFileError when unusable."""
    path = Path(path)
    if not path.is_file():
        raise NotFoundError(f"surrogate file {path} does not exist (make one with "
                            "`balloon fit --db DB -o FILE`, or use the model `paper`)")
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise SurrogateFileError(str(path), f"not valid JSON ({exc})") from None
    return surrogate_from_dict(data, str(path))


def open_surrogate(spec: str | os.PathLike) -> Surrogate:
    """``"paper"`` for the paper preset, else a surrogate file path."""
    if str(spec) == "paper":
        from surrogate.paper import paper_surrogate

        return paper_surrogate()
    return load_surrogate(spec)
