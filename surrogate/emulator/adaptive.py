"""Adaptive refinement: the next designs to solve, where the emulator is least certain.

    points = next_designs(emulator, n=16)       # GridPoints for the precompute job

Candidates are scrambled Sobol points of every group's reduced box (``CANDIDATES`` per
group, a seed different from the grid's); each is scored by ``angle_sd_deg``: the emulated
angle's standard deviation (deg) on the worse of its two axes, by pressure and by injected
volume, averaged over the angle nodes from 10 to 90 deg (below 10 deg the angle hardly
depends on the nodes' errors). The sds are the GP's times the node's band multiplier (so
that a group whose cross-validated errors exceed its GP variance is refined first). Until
2026-12-04 the score was log p's sd alone: the volume nodes, whose cross-validated error
is 3-10x log p's at 20-80 deg (benchmarks/RESULTS.md), were never the reason a design was
chosen, and the held-out curves met the accuracy target by volume less often than by
pressure. The n best are taken greedily, each at least ``MIN_SPACING`` (unit-cube
distance) from the others and from the database designs, so that one uncertain corner does
not take every slot, and none within ``FAILED_RADIUS`` of a database curve that ended
early (a Newton failure or the volume stop of a balloon that hardly bends): such a
neighbour's curve ends early too, as 27 of the 47 designs of the first ``--adaptive 48``
round on the 533-record database did, and adds no curve to interpolate; the emulator
already caps its range there. Nor any candidate whose emulated injected volume at 90 deg
reaches the FE's volume stop (``PairEmulator.fe_max_volume_ul``): its FE curve would stop
there too; nor any whose FE curve the group's range model (``PairEmulator.range_model``,
fitted to where every database curve ended) puts before 85 deg: the emulated volume learns
from complete curves only and misses the balloons near the Ecoflex/Ecoflex balance. Before
that screen, an ``--adaptive 240`` round on the 663-record database added 65 curves to
interpolate (175 ended early, most at the volume stop in Ecoflex/Ecoflex), where the
space-filling sequence, continued, gave 86 of 96.
"""

from __future__ import annotations

import numpy as np

from solver.design import Design
from solver.design_space import (
    GROUPS,
    REDUCED_RATIO_RANGE,
    contrast,
    contrast_range,
    from_unit,
    locate,
    scaled_material,
    sobol_points,
)
from solver.errors import InputError
from solver.materials import MATERIALS
from solver.precompute.grid import GridPoint
from solver.settings import SolverSettings
from solver.store.keys import record_key
from surrogate.emulator.emulator import Emulator
from surrogate.emulator.features import ANGLE_NODES_DEG, N_NODES
from surrogate.emulator.pair_emulator import FAILED_RADIUS, PairEmulator

CANDIDATES = 1024
MIN_SPACING = 0.12
SEED = 1009


def _design_for(group: str, u: np.ndarray) -> Design | None:
    """The database design (membrane at its preset) whose group coordinates are ``u``."""
    geometry, _ = from_unit(u)
    lo, hi = contrast_range(group)
    target = float(np.exp(np.log(lo) + u[-1] * (np.log(hi) - np.log(lo))))
    for pair, g in GROUPS.items():
        if g != group:
            continue
        ratio = target / contrast(pair, 1.0)
        if REDUCED_RATIO_RANGE[0] <= ratio <= REDUCED_RATIO_RANGE[1]:
            return Design(body_material=scaled_material(pair[0], round(ratio, 6)),
                          membrane_material=MATERIALS[pair[1]], **geometry).validated()
    return None


def _reaches_volume_stop(pe: PairEmulator, node_mean: np.ndarray) -> bool:
    """Whether the emulated injected volume at the last angle node (reduced design: the
    length scale is 1) reaches the FE's volume stop, so that its FE curve would end
    early."""
    if pe.fe_max_volume_ul is None:
        return False
    last = ANGLE_NODES_DEG[-1]
    return bool(last * np.exp(node_mean[2 * N_NODES - 1]) >= pe.fe_max_volume_ul)


ADAPTIVE_END_DEG = 85.0     # no candidate whose FE curve is emulated to end before this
SCORE_FROM_DEG = 10.0       # the score's angle nodes: from here to 90 deg
MIN_LOG_SLOPE = 0.1         # d log p / d log theta, d log V / d log theta: floor
_LOG_THETA = np.log(ANGLE_NODES_DEG)


def angle_sd_deg(mean: np.ndarray, sd: np.ndarray) -> np.ndarray:
    """The emulated angle's sd (deg) at each angle node, the larger of the two axes.

    ``mean`` and ``sd`` are a design's node values (log(p/theta), then log(V/theta)) and
    their sds (band multipliers included). An error d in y = log(x/theta) at a fixed
    angle moves the angle read at a given x (pressure or volume) by
    d log theta = d / (d log x / d log theta), so the angle's sd is
    theta x sd / (d log x / d log theta), the slope taken along the emulated curve
    (floored at MIN_LOG_SLOPE: past a pressure maximum the angle at a pressure is
    undefined)."""
    out = np.zeros(N_NODES)
    for axis in (slice(0, N_NODES), slice(N_NODES, 2 * N_NODES)):
        slope = np.gradient(_LOG_THETA + mean[axis], _LOG_THETA)
        out = np.maximum(out, ANGLE_NODES_DEG * sd[axis] / np.maximum(slope, MIN_LOG_SLOPE))
    return out


def _ends_early(pe: PairEmulator, u: np.ndarray) -> bool:
    """Whether the group's emulated end of the FE curve (``PairEmulator.range_model``,
    its mean) at unit coordinates ``u`` lies before ADAPTIVE_END_DEG."""
    if pe.range_model is None:
        return False
    return pe.emulated_end_deg(u)[0] < ADAPTIVE_END_DEG


MAX_ADAPTIVE = 10_000
ADAPTIVE_COUNTS = (1, MAX_ADAPTIVE)   # designs one --adaptive N asks for, lo <= N <= hi


def check_count(n: int) -> None:
    """InputError naming --adaptive unless 1 <= n <= MAX_ADAPTIVE (checked before an
    emulator is fitted for it: minutes)."""
    lo, hi = ADAPTIVE_COUNTS
    if not lo <= n <= hi:
        raise InputError("--adaptive", f"got {n}", f"{lo} <= N <= {hi}")


def next_designs(emulator: Emulator, n: int, settings: SolverSettings | None = None
                 ) -> list[GridPoint]:
    """The ``n`` most uncertain designs, as precompute grid points."""
    check_count(n)
    settings = settings or SolverSettings()
    nodes = ANGLE_NODES_DEG >= SCORE_FROM_DEG
    scored: list[tuple[float, str, np.ndarray, Design]] = []
    for group in sorted(set(GROUPS.values())):
        models = [pe for key, pe in emulator.pairs.items() if key[:-1] == group]
        if not models:
            continue
        for u in sobol_points(CANDIDATES, seed=SEED):
            design = _design_for(group, u)
            if design is None:
                continue
            point = locate(design, reduced=True)
            uu = point.coordinates()
            try:
                pe = emulator._pair(point, uu)
            except InputError:
                pe = max(models, key=lambda m: float(np.median(m.band_scale)))  # near a balance
            mean, var = pe.curves.predict(uu)
            if _reaches_volume_stop(pe, mean) or _ends_early(pe, uu):
                continue
            score = float(angle_sd_deg(mean, np.sqrt(var) * pe.band_scale)[nodes].mean())
            scored.append((score, group, uu, design))
    scored.sort(key=lambda s: -s[0])
    taken: dict[str, list[np.ndarray]] = {
        g: [pe.coordinates[i] for key, pe in emulator.pairs.items() if key[:-1] == g
            for i in range(len(pe.coordinates))] for g in set(GROUPS.values())}
    ended: dict[str, list[np.ndarray]] = {
        g: [np.asarray(fu) for key, pe in emulator.pairs.items() if key[:-1] == g
            for fu, _, _ in pe.failed] for g in set(GROUPS.values())}
    out: list[GridPoint] = []
    for _score, group, uu, design in scored:
        if any(np.linalg.norm(uu - t) < MIN_SPACING for t in taken[group]):
            continue
        if any(np.linalg.norm(uu - f) < FAILED_RADIUS for f in ended[group]):
            continue
        taken[group].append(uu)
        out.append(GridPoint(record_key(design, settings), design, settings))
        if len(out) == n:
            break
    return out
