"""The baseline's answers, tabulated: angle(pressure) of every nominal design of the data
at a grid of the physical effects' values, from any ``surrogate.predictor.Predictor``.

A physical effect acts through the predictor's inputs (a stiffer membrane is a design with
the membrane's mu scaled), so the fit needs the predictor at many designs near the
nominal ones. Calling it inside the optimiser would be slow for an FE-trained emulator;
instead it is asked once per design at ``NODES`` values of each physical parameter (a
tensor grid for two) on a pressure grid, and the fit interpolates: 4-point Lagrange
(cubic) along each parameter, linear along pressure. A pressure past the end of the FE's
range (the predictor's NaN) stays NaN.

A physical effect is tabulated only over the values at which the predictor answers every
nominal design (``reach``): the emulator refuses designs outside its box
(``solver.design_space.OutOfBoxError``), so at t = 0.5 mm, the box's edge, a thinner
membrane has no answer. The reach is found by bisection of the predictor's refusals; where
it ends short of the effect's fit bounds it says why (the refused field and its allowed
range), and the fit stays inside it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from solver.errors import InputError
from surrogate.calibration.effects import Effect
from surrogate.calibration.effects._base import physical_nodes

NODES = 9
PRESSURE_POINTS = 241
BAND_LEVEL = 0.95
BAND_Z = 1.959964  # two-sided 95 %
PROBE_STEPS = 16   # bisection steps of the reach: 1/65536 of the fit range
RECENT_CURVES = 4  # interpolated curves kept (``Responses.curves``)


@dataclass(frozen=True)
class Reach:
    """The values of a physical effect's parameter at which the predictor answers every
    nominal design: [lower, upper] inside the fit bounds, and why each side ends short
    of them (empty when it does not)."""

    lower: float
    upper: float
    limits: tuple[str, ...] = ()

    @property
    def bounds(self) -> tuple[float, float]:
        return (self.lower, self.upper)

    @property
    def empty(self) -> bool:
        return not self.upper > self.lower

    def as_dict(self) -> dict[str, object]:
        return {"lower": self.lower, "upper": self.upper, "limits": list(self.limits)}


def design_key(design) -> str:
    return repr(design)


class Responses:
    """Tables of ``predictor`` at the nominal ``designs`` (one per key), pressures
    0 .. ``p_max_pa``."""

    def __init__(self, predictor, designs: dict[str, object], p_max_pa: float,
                 v_max_ul: float | None = None) -> None:
        """``v_max_ul``: also tabulate angle and chamber pressure by injected volume,
        0 .. v_max_ul (the predictor's ``predict_volume``), for the two observables of a
        syringe pump (docs/calibration.md)."""
        self.predictor = predictor
        self.keys = tuple(designs)
        self.designs = designs
        self.index = {k: i for i, k in enumerate(self.keys)}
        self.p_grid = np.linspace(0.0, p_max_pa, PRESSURE_POINTS)
        self.dp = self.p_grid[1] - self.p_grid[0]
        self._tables: dict[tuple[str, ...], tuple[list[np.ndarray], np.ndarray]] = {}
        # angle and chamber pressure by injected volume, where the predictor answers so
        self.v_grid = (np.linspace(0.0, v_max_ul, PRESSURE_POINTS)
                       if v_max_ul and callable(getattr(predictor, "predict_volume", None))
                       else None)
        self.dv = self.v_grid[1] - self.v_grid[0] if self.v_grid is not None else None
        self._volumes: dict[tuple[str, ...], dict[str, np.ndarray]] = {}
        self._sd: np.ndarray | None = None
        self._reach: dict[str, Reach] = {}
        self._recent_curves: dict[tuple, np.ndarray] = {}
        self.calls = 0

    def _refusal(self, design) -> InputError | None:
        """The predictor's refusal of ``design`` (None: it answers)."""
        self.calls += 1
        try:
            self.predictor.predict(design, np.zeros(1), level=BAND_LEVEL)
        except InputError as exc:
            return exc
        return None

    def reach(self, effect: Effect) -> Reach:
        """Where the predictor answers ``effect`` at every nominal design (see Reach)."""
        if effect.id not in self._reach:
            par = effect.parameters[0]
            bounds = {"lower": par.fit_bounds[0], "upper": par.fit_bounds[1]}
            why: dict[str, str] = {}
            for k in self.keys:
                d0 = self.designs[k]
                for side, sign in (("lower", -1.0), ("upper", 1.0)):
                    err = self._refusal(effect.design(d0, bounds[side]))
                    if err is None:
                        continue
                    good, bad = par.null, bounds[side]
                    for _ in range(PROBE_STEPS):
                        mid = 0.5 * (good + bad)
                        e2 = self._refusal(effect.design(d0, mid))
                        if e2 is None:
                            good = mid
                        else:
                            bad, err = mid, e2
                    bounds[side] = good
                    op = ">=" if sign < 0 else "<="
                    why[side] = (f"{par.name} {op} {good:.4g} {par.unit}: the baseline refuses "
                                 f"{d0.body_material.id}/{d0.membrane_material.id} L_mm = "
                                 f"{d0.L_mm:g}, t_mm = {d0.t_mm:g} changed further "
                                 f"({err.field}: {err.allowed or err.detail})")
            self._reach[effect.id] = Reach(bounds["lower"], bounds["upper"],
                                           tuple(why[s] for s in ("lower", "upper")
                                                 if s in why))
        return self._reach[effect.id]

    def _by_volume(self, design) -> tuple[np.ndarray, np.ndarray]:
        """Angle (deg) and chamber pressure (Pa) on ``v_grid`` (NaN where refused)."""
        self.calls += 1
        nan = np.full(self.v_grid.size, np.nan)
        try:
            out = self.predictor.predict_volume(design, self.v_grid, level=BAND_LEVEL,
                                                band=False)     # its band is not read
        except InputError:
            return nan, nan
        p = getattr(out, "pressure_pa", None)
        return (np.asarray(out.angle_deg, dtype=float),
                nan if p is None else np.asarray(p, dtype=float))

    def _predict(self, design, with_sd: bool = False):
        self.calls += 1
        nan = np.full(self.p_grid.size, np.nan)
        try:
            out = self.predictor.predict(design, self.p_grid, level=BAND_LEVEL)
        except InputError:
            return (nan, nan) if with_sd else nan
        angle = np.asarray(out.angle_deg, dtype=float)
        if not with_sd:
            return angle
        half = 0.5 * (np.asarray(out.upper_deg, float) - np.asarray(out.lower_deg, float))
        return angle, np.abs(half) / BAND_Z

    def sd_at(self, effects: tuple[Effect, ...], thetas: list[float]) -> np.ndarray:
        """(n_designs, pressures): the baseline's own sd at the designs changed by the
        physical ``effects`` at ``thetas`` (asked afresh, not interpolated)."""
        return np.array([self._predict(d, True)[1] for d in self._changed(effects, thetas)])

    def angle_at(self, effects: tuple[Effect, ...], thetas: list[float],
                 edit=None) -> np.ndarray:
        """(n_designs, pressures): the baseline's angle (deg) at the designs changed by
        ``edit`` (a function of a design, or None) and then by the physical ``effects`` at
        ``thetas`` (asked afresh)."""
        return np.array([self._predict(d) for d in self._changed(effects, thetas, edit)])

    def _changed(self, effects: tuple[Effect, ...], thetas: list[float], edit=None) -> list:
        out = []
        for k in self.keys:
            d = self.designs[k] if edit is None else edit(self.designs[k])
            for e, theta in zip(effects, thetas, strict=True):
                d = e.design(d, float(theta))
            out.append(d)
        return out

    def nominal_sd(self) -> np.ndarray:
        """(n_designs, pressures): the baseline's own standard deviation for an FE solve
        of each nominal design (its band at BAND_LEVEL / z)."""
        if self._sd is None:
            self._sd = np.array([self._predict(self.designs[k], True)[1] for k in self.keys])
        return self._sd

    def table(self, effects: tuple[Effect, ...]) -> tuple[list[np.ndarray], np.ndarray]:
        """(nodes per effect, values (n_designs, n_1, ..., n_k, pressures))."""
        key = tuple(e.id for e in effects)
        if key not in self._tables:
            nodes = [physical_nodes(e.parameters[0], NODES, self.reach(e).bounds)
                     for e in effects]
            shape = (len(self.keys),) + tuple(n.size for n in nodes) + (self.p_grid.size,)
            values = np.empty(shape)
            vshape = shape[:-1] + (0 if self.v_grid is None else self.v_grid.size,)
            by_v = {"angle_v": np.empty(vshape), "pressure_v": np.empty(vshape)}
            for di, k in enumerate(self.keys):
                for idx in np.ndindex(*shape[1:-1]):
                    d = self.designs[k]
                    for e, n, j in zip(effects, nodes, idx, strict=True):
                        d = e.design(d, float(n[j]))
                    # by volume first: the emulator's curve for it serves the pressures too
                    if self.v_grid is not None:
                        by_v["angle_v"][(di,) + idx], by_v["pressure_v"][(di,) + idx] = \
                            self._by_volume(d)
                    values[(di,) + idx] = self._predict(d)
            self._tables[key] = (nodes, values)
            self._volumes[key] = by_v
        return self._tables[key]

    def has_volumes(self) -> bool:
        """Does the predictor answer by injected volume, with the chamber pressure there
        (the emulator), at every nominal design?"""
        if self.v_grid is None:
            return False
        self.table(())
        p = self._volumes[()]["pressure_v"]
        return bool(np.all(np.isfinite(p[:, :2])))

    def responsive(self, effect: Effect) -> bool:
        """Does the predictor's answer change with this physical effect at all?"""
        _, values = self.table((effect,))
        mid = values.shape[1] // 2
        ref = values[:, mid]
        for j in (mid - 2, mid + 2):
            diff = np.abs(values[:, j] - ref)
            if np.nanmax(diff, initial=0.0) > 1e-6:
                return True
        return False

    def curves(self, effects: tuple[Effect, ...], thetas: list[float],
               what: str = "angle") -> np.ndarray:
        """At the effects' values ``thetas`` (interpolated): "angle" (n_designs, pressures),
        or by injected volume "angle_v" / "pressure_v" (n_designs, volumes)."""
        nodes, values = self.table(effects)
        if what != "angle":
            values = self._volumes[tuple(e.id for e in effects)][what]
        if not effects:
            return values
        # one evaluation of the augmented model asks for the same curves up to four times
        # (the gauge, the angle, the chamber's volume, a leak's pressure): the last few
        # answers are kept, read-only
        key = (tuple(e.id for e in effects), np.asarray(thetas, float).tobytes(), what)
        if key in self._recent_curves:
            return self._recent_curves[key]
        out = self._interpolated(nodes, values, thetas)
        out.flags.writeable = False
        if len(self._recent_curves) >= RECENT_CURVES:
            del self._recent_curves[next(iter(self._recent_curves))]
        self._recent_curves[key] = out
        return out

    @staticmethod
    def _interpolated(nodes: list[np.ndarray], values: np.ndarray, thetas: list[float]
                      ) -> np.ndarray:
        out = values
        for axis_nodes, theta in zip(nodes, thetas, strict=True):
            idx, w = lagrange_weights(axis_nodes, theta)
            cubic = np.tensordot(w, np.take(out, idx, axis=1), axes=([0], [1]))
            idx, w = linear_weights(axis_nodes, theta)
            linear = np.tensordot(w, np.take(out, idx, axis=1), axes=([0], [1]))
            # a node's curve that ends sooner (past the FE's range: NaN) must not void
            # the answer between two nodes that have one: linear there
            between = np.where(np.isfinite(cubic), cubic, linear)
            # nor between a node that has one and a node that does not: the predictor's
            # range ends somewhere between them, and up to there it answers
            # (the fit's hot path: worked out only where such a pair is met)
            gap = ~np.isfinite(between)
            out = (np.where(gap, _one_sided(out, axis_nodes, theta), between) if gap.any()
                   else between)
        return out

    def lookup(self, curves: np.ndarray, design_index: np.ndarray, p_pa: np.ndarray
               ) -> np.ndarray:
        """Angle at chamber pressure ``p_pa`` of each row's design (linear in p; below 0
        the angle at 0; past the grid, or at a NaN pressure, NaN)."""
        return _on_grid(curves, design_index, p_pa, self.dp)

    def lookup_volume(self, curves: np.ndarray, design_index: np.ndarray, v_ul: np.ndarray
                      ) -> np.ndarray:
        """A by-volume table's value at injected volume ``v_ul`` of each row's design."""
        return _on_grid(curves, design_index, v_ul, self.dv)


def _on_grid(curves: np.ndarray, design_index: np.ndarray, x: np.ndarray, dx: float
             ) -> np.ndarray:
    """Linear interpolation on a uniform grid from 0 in steps ``dx`` (below 0 the value at
    0; past the grid, or at NaN, NaN)."""
    n = curves.shape[1]
    known = np.isfinite(x)
    f = np.where(known, np.clip(x, 0.0, None), 0.0) / dx
    i0 = np.floor(f).astype(int)
    inside = i0 < n - 1
    i0 = np.where(inside, i0, n - 2)
    frac = f - i0
    a = curves[design_index, i0]
    b = curves[design_index, i0 + 1]
    out = a + frac * (b - a)
    return np.where((inside | (f <= n - 1)) & known, out, np.nan)


def _one_sided(values: np.ndarray, nodes: np.ndarray, x: float) -> np.ndarray:
    """Along axis 1 of ``values`` (one entry per node), the value at ``x`` carried on
    from the bracketing node that has one, by the line through it and its own outer
    neighbour (that node's value alone where the neighbour has none); NaN where neither
    bracketing node has a value.

    Between a node whose curve reaches a pressure (or volume) and one whose curve ends
    before it, the predictor's own range ends somewhere in between; interpolation
    between the two is undefined there, and a fit that read it as "no answer" met a wall
    one node short of the range: a membrane 1.2x stiff fitted as 1.189 (the node) with
    an sd of 1e-7, the readings above left to an unexplained gauge error (the
    an audit of the thirty-fifth session, syringe-pump data). The line from the reaching side
    is continuous with the interpolation at that node."""
    x = min(max(float(x), float(nodes[0])), float(nodes[-1]))
    n = nodes.size
    j = int(np.clip(np.searchsorted(nodes, x, side="right") - 1, 0, n - 2))

    def line(at: int, outer: int) -> np.ndarray:
        v = np.take(values, at, axis=1)
        if not 0 <= outer < n:
            return v
        w = np.take(values, outer, axis=1)
        slope = (v - w) / (nodes[at] - nodes[outer])
        return np.where(np.isfinite(w), v + (x - nodes[at]) * slope, v)

    low, high = line(j, j - 1), line(j + 1, j + 2)
    return np.where(np.isfinite(np.take(values, j, axis=1)), low, high)


def linear_weights(nodes: np.ndarray, x: float) -> tuple[np.ndarray, np.ndarray]:
    """Indices and weights of linear interpolation at ``x`` (clamped to the nodes); at a
    node, that node alone."""
    x = min(max(float(x), float(nodes[0])), float(nodes[-1]))
    j = int(np.clip(np.searchsorted(nodes, x, side="right") - 1, 0, nodes.size - 2))
    f = (x - nodes[j]) / (nodes[j + 1] - nodes[j])
    if f == 0.0:
        return np.array([j]), np.ones(1)
    if f == 1.0:
        return np.array([j + 1]), np.ones(1)
    return np.array([j, j + 1]), np.array([1.0 - f, f])


def lagrange_weights(nodes: np.ndarray, x: float) -> tuple[np.ndarray, np.ndarray]:
    """Indices and weights of the 4-point (cubic) Lagrange interpolant at ``x`` (clamped
    to the nodes' range)."""
    n = nodes.size
    x = min(max(float(x), float(nodes[0])), float(nodes[-1]))
    j = int(np.clip(np.searchsorted(nodes, x) - 2, 0, max(n - 4, 0)))
    idx = np.arange(j, min(j + 4, n))
    xs = nodes[idx]
    w = np.ones(idx.size)
    for a in range(idx.size):
        for b in range(idx.size):
            if a != b:
                w[a] *= (x - xs[b]) / (xs[a] - xs[b])
    if not math.isfinite(float(w.sum())):
        raise ValueError("degenerate interpolation nodes")
    return idx, w
