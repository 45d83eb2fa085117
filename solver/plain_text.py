"""Text a user wrote, as the service shows it and as a label may hold it.

A terminal obeys a control character (ESC [ 2 J clears the screen; the C1 CSI, U+009B,
does in some terminals too) and a page or a terminal obeys a bidi override (U+202E shows
"1.0 ni" for "in 1.0") or hides a zero-width character: text from a request or a file
never reaches either unescaped. ``escaped`` is how every error line and problem document
shows such text; ``hidden_character`` is what a free-text label (a curve's id, a run's
label) may not hold, refused naming the character.
"""

from __future__ import annotations

import unicodedata

# Unicode categories that are not text to show: controls (Cc: C0, DEL, C1), formats (Cf:
# bidi overrides and isolates, zero-width characters, the BOM, the soft hyphen),
# surrogates (Cs), line and paragraph separators (Zl, Zp)
HIDDEN_CATEGORIES = frozenset({"Cc", "Cf", "Cs", "Zl", "Zp"})
PRINTABLE_WORDS = "printable text (no control, bidi-override or zero-width characters)"


def escaped(text: object) -> str:
    """``text`` with every character Python does not print (the categories above, other
    spaces than ' ', unassigned ones) written as its escape: ESC as \\x1b, U+202E as
    \\u202e."""
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in str(text))


def hidden_character(text: str) -> str | None:
    """The first character of ``text`` in HIDDEN_CATEGORIES, named: "U+202E
    (RIGHT-TO-LEFT OVERRIDE)"; None when there is none."""
    for c in text:
        if unicodedata.category(c) in HIDDEN_CATEGORIES:
            name = unicodedata.name(c, "a control character")
            return f"U+{ord(c):04X} ({name})"
    return None
