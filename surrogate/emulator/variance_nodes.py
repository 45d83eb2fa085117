"""Which pressure nodes a query computes the exact variance at, chosen per fit.

A query's costly part is the exact GP variance, one O(n^2) triangular product per node.
The other pressure nodes' variance is read off the natural cubic spline of log variance
in log angle (``spread_variance``). Each node's GP has its own hyperparameters, so the sd
along a curve is not smooth everywhere and which nodes the spline needs depends on the
fit: on the 2155-record fit of the former mesh the 6.5-deg node's sd sat above its
neighbours' and an evenly spread set read the 4-10 deg nodes up to 13 % off; the set
chosen for that fit read a 1356-record fit of the balanced mesh up to 11.8 % off. So the
fit chooses its own (``choose``, stored in the emulator file since format 8): COUNT nodes
by greedy removal from all 32 (always the one whose removal raises the largest + 2 x the
median relative sd error least; the first and last stay), on PER_GROUP random designs of
the box per group, with the two seeds of SEEDS. The band's calibration (band_scale) is
itself some 10 % uncertain.

Since 2026-12-04 the fit gives the pressure nodes one kernel per group
(``build.fit_curve_gps``), since 2026-12-05 one below 45 deg and one for the top pressure
GPs above (``shape_gps``): their variances are then one product per kernel, and ``choose``
returns every node (nothing is read off the spline). The choice stays for files whose
pressure nodes have a kernel each.
"""

from __future__ import annotations

import numpy as np

from surrogate.emulator.features import ANGLE_NODES_DEG, N_NODES, spline_matrix

# 12 of 32: the O(n^2) part of a query is memory-bound (the nodes' packed L^-1, 4.8 MB for
# 12 on a 447-design group), and 17 took a query to 1.03-1.9 ms on the shared 2-core
# machine; 12 read the sd within 3.8 % (largest) and 1.6 % (median) of the exact one on
# 100 designs not used to choose them, 17 within 1.5 % and 0.7 %, while the band's
# calibration is itself some 10 % uncertain (benchmarks/RESULTS.md, eighteenth session)
COUNT = 12
# at most this many kernels among a pair's pressure nodes: every node's variance is exact
# (one kernel below 45 deg, the top pressure GPs' one above: ``shape_gps``)
SHARED_KERNELS = 2
PER_GROUP = 25
SEEDS = (7, 99)
VARIANCE_FLOOR = 1e-14     # (log units)^2: a node's variance at a database design
# Files before format 8: the set chosen for the 2155-record fit of the former mesh (within
# 2.9 % largest and 1.0 % median of the exact sd on 100 designs not used to choose it).
FORMAT_7_NODES = np.array([0, 1, 2, 3, 6, 9, 10, 11, 12, 14, 15, 17, 21, 25, 28, 30, 31])


def spline(nodes: np.ndarray) -> np.ndarray:
    """(N_NODES, len(nodes)): every pressure node's log variance from those at ``nodes``."""
    return spline_matrix(ANGLE_NODES_DEG[np.asarray(nodes)], ANGLE_NODES_DEG)


def spread_variance(var: np.ndarray, nodes: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``var`` (2 N_NODES: pressure then volume nodes) with every pressure node's variance
    read off the spline ``b`` = ``spline(nodes)`` of those at ``nodes`` (the volume nodes,
    whose sd bends more along the curve, up to 9 % off so read, keep theirs)."""
    out = var.copy()
    known = np.maximum(var[nodes], VARIANCE_FLOOR)
    out[:N_NODES] = np.exp(b @ np.log(known))
    return out


def exact_variances(pairs, seed: int, per_group: int = PER_GROUP) -> np.ndarray:
    """(designs, N_NODES): the exact variance of log p at random unit coordinates, per_group
    designs for each of ``pairs`` (PairEmulator objects with one GP per output)."""
    rng = np.random.default_rng(seed)
    out = []
    for pe in pairs:
        u = rng.uniform(0, 1, (per_group, pe.coordinates.shape[1]))
        out.append(pe.curves.predict_many(u, variance_of=np.arange(N_NODES))[1][:, :N_NODES])
    return np.vstack(out)


def errors(nodes, exact: np.ndarray) -> tuple[float, float]:
    """Largest and median (over designs) of each design's largest relative sd error when
    the pressure nodes' variance is read off ``nodes``."""
    nodes = np.asarray(nodes)
    read = np.exp(np.log(np.maximum(exact[:, nodes], VARIANCE_FLOOR)) @ spline(nodes).T)
    worst = np.abs(np.sqrt(read / np.maximum(exact, VARIANCE_FLOOR)) - 1).max(axis=1)
    return float(worst.max()), float(np.median(worst))


def greedy(exact: np.ndarray, count: int = COUNT) -> np.ndarray:
    """Remove nodes one by one (never the first or last) down to ``count``, each time
    the one whose removal raises largest + 2 x median error least."""
    nodes = list(range(N_NODES))
    while len(nodes) > count:
        def cost(n: int) -> float:
            big, med = errors([m for m in nodes if m != n], exact)
            return big + 2 * med
        nodes.remove(min(nodes[1:-1], key=cost))
    return np.array(nodes)


def choose(pairs, count: int = COUNT) -> tuple[np.ndarray, dict]:
    """The fit's variance nodes (``greedy`` on random designs of its groups, SEEDS) and a
    report: their errors there and on PER_GROUP other designs per group (seed 123)."""
    pairs = [pe for pe in pairs if pe.curves.per_output]
    if not pairs:
        return FORMAT_7_NODES.copy(), {"nodes": FORMAT_7_NODES.tolist(),
                                       "chosen": False}
    if all(pe.curves.kernels(slice(0, N_NODES)) <= SHARED_KERNELS for pe in pairs):
        # the pressure nodes share one kernel, or one below 45 deg and the top pressure
        # GPs' one above (build.fit_curve_gps): their variances are one product per kernel,
        # so every node's is exact and none is read off the spline
        nodes = np.arange(N_NODES)
        return nodes, {"nodes": nodes.tolist(), "chosen": False, "shared_kernel": True}
    fit = np.vstack([exact_variances(pairs, s) for s in SEEDS])
    nodes = greedy(fit, count)
    check = exact_variances(pairs, 123)
    big, med = errors(nodes, check)
    return nodes, {"nodes": nodes.tolist(), "chosen": True, "designs": len(fit),
                   "check_designs": len(check), "check_largest_rel_sd_error": big,
                   "check_median_rel_sd_error": med}
