"""A text file's byte-order mark: the Unicode encoding its first bytes name.

Windows tools write one: Notepad's "UTF-8 with BOM", Excel's "CSV UTF-8", "Unicode text"
(UTF-16 little-endian). A file the user names (measured data, a grid) that starts with
one is read in the encoding it names, the mark dropped; without one a file is UTF-8.
"""

from __future__ import annotations

# the marks, longest first where one begins another (UTF-32 LE's begins with UTF-16 LE's)
BOMS = ((b"\xef\xbb\xbf", "utf-8-sig"), (b"\xff\xfe\x00\x00", "utf-32"),
        (b"\x00\x00\xfe\xff", "utf-32"), (b"\xff\xfe", "utf-16"), (b"\xfe\xff", "utf-16"))


def bom_encoding(data: bytes) -> str | None:
    """The codec of the byte-order mark ``data`` starts with (which drops the mark when
    decoding), or None when it starts with none."""
    return next((encoding for bom, encoding in BOMS if data.startswith(bom)), None)


def byte_line(data: bytes, offset: int, encoding: str) -> int:
    """The 1-based line of byte ``offset`` of ``data``, text in ``encoding`` (where a
    decoding error is: UnicodeDecodeError.start)."""
    return data[:offset].decode(encoding, errors="replace").count("\n") + 1
