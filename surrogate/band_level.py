"""The two-sided normal quantile of a band's level, shared by every model's bands."""

from __future__ import annotations

from functools import lru_cache

from scipy.stats import norm

from solver.errors import InputError

#: a band's level, as every refusal of one states it
LEVEL_RANGE = "0.5 <= level < 1"
#: the level an answer may be asked for (POST /v1/predict's and /v1/inverse's `level`,
#: `balloon predict --level`, `balloon inverse --level`), lo <= level <= hi: the command
#: line took 0.99999999 where a request was refused above 0.999
ASKED_LEVELS = (0.5, 0.999)
ASKED_LEVEL_WORDS = f"{ASKED_LEVELS[0]} <= level <= {ASKED_LEVELS[1]}"


def z_value(level: float) -> float:
    """Two-sided normal quantile for a band at ``level`` (e.g. 1.96 at 0.95)."""
    if not isinstance(level, (int, float)) or not 0.5 <= level < 1.0:
        raise InputError("level", f"got {level!r}", LEVEL_RANGE)
    return _z(float(level))


@lru_cache(maxsize=64)
def _z(level: float) -> float:
    return float(norm.ppf(0.5 + 0.5 * level))
