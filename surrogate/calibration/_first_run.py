"""A specimen's first run against its later runs: the gauge at the same injected volume.

The runs of one specimen share its stiffness and geometry, so at one injected volume of
one pump program their gauges differ by the gauge's reading noise alone, as often up as
down. A silicone membrane that softens after its first stretch (the Mullins effect:
the first loading of a fresh specimen is its stiffest; labs precondition each specimen
by loading it once before measuring) reads the first run's gauge higher at every
loading reading, on every specimen; so does a rig that warms up over the session. The
bend at a volume is not moved (both layers soften alike), so the calibration, which reads
the specimen's stiffness as scatter between specimens, fits nothing and had called what
remains replicate scatter (benchmarks/lab_rig_sets.py N44: m 0.25, the second loading
4-20 % below the first).

Test: per specimen with two or more runs and loading reading (injected volume above 0,
the pump loading) that its runs share (the same volume), the first run's gauge against
the mean of its later runs'; a sign test over those pairs (binomial, two-sided). Only the
loading is compared: an unloading follows the loading's softening in every run alike.
"""

from __future__ import annotations

import math

import numpy as np

#: the sign test's two-sided level: a paired count this lopsided is not reading noise
LEVEL = 1e-3
#: pairs needed before a count is read (with fewer the test cannot reach ``LEVEL``)
MIN_PAIRS = 11


def _sign_test(up: int, n: int) -> float:
    """Two-sided binomial p of ``up`` of ``n`` signs at one half."""
    tail = sum(math.comb(n, k) for k in range(max(up, n - up), n + 1)) / 2.0 ** n
    return min(1.0, 2.0 * tail)


def first_run_against_later(curve: np.ndarray, specimen: np.ndarray, volume_ul: np.ndarray,
                            direction: np.ndarray, gauge_pa: np.ndarray) -> dict | None:
    """The first run's gauge (the specimen's first curve in the data) against its later
    runs' at the loading readings they share: None without ``MIN_PAIRS`` such pairs;
    else the pairs, how many read higher in the first run, the median relative
    difference (first / later - 1), the sign test's p and ``differs``."""
    rel = []
    for s in np.unique(specimen):
        runs = list(dict.fromkeys(curve[specimen == s]))    # curve order: the data's
        if len(runs) < 2:
            continue
        first = {}
        for i in np.flatnonzero((curve == runs[0]) & (direction > 0) & (volume_ul > 0)):
            first.setdefault(round(float(volume_ul[i]), 6), float(gauge_pa[i]))
        later: dict[float, list[float]] = {}
        for c in runs[1:]:
            for i in np.flatnonzero((curve == c) & (direction > 0) & (volume_ul > 0)):
                later.setdefault(round(float(volume_ul[i]), 6), []).append(float(gauge_pa[i]))
        rel += [first[v] / np.mean(later[v]) - 1.0 for v in first
                if v in later and np.mean(later[v]) > 0]
    rel = [r for r in rel if np.isfinite(r)]
    if len(rel) < MIN_PAIRS:
        return None
    up = sum(r > 0 for r in rel)
    p = _sign_test(up, len(rel))
    return {"pairs": len(rel), "first_higher": int(up),
            "median_relative": float(np.median(rel)), "p": p, "differs": bool(p < LEVEL)}


def first_run_sentence(result: dict | None) -> str | None:
    """The report's sentence when the first runs differ from the later ones."""
    if not result or not result["differs"]:
        return None
    way = "higher" if result["median_relative"] > 0 else "lower"
    return (f"Each specimen's first run reads the gauge {way} than its later runs at the "
            f"same injected volume ({result['first_higher']} of {result['pairs']} loading "
            f"readings higher, median {100 * result['median_relative']:+.0f} %; not reading "
            "noise): the specimens "
            + ("softened after their first loading (the Mullins effect: precondition each "
               "specimen by loading it once before measuring, and leave that run out)"
               if way == "higher" else "stiffened between runs")
            + " or the rig changed over the session (its temperature); the calibration "
            "reads one stiffness per specimen, so this is not among what it fits.")
