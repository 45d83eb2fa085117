"""The curve GPs of a pair: its 32 pressure nodes and 32 volume nodes over the box.

The outputs a query reads are log(p / theta) and log(V / theta) at the angle nodes
(``features.curve_features``). The volume nodes above an anchor angle are interpolated as
the log of their rise in log V above the anchor node,

    z_j = log(log V_j - log V_a),      log V_j = log V_a + exp(z_j),

and turned back into log(V / theta) for the query (``node_outputs``). Why: between 60 and
90 deg the injected volume of one design grows 1.3x to 6.4x (Ecoflex/Ecoflex's database;
log V90 / V60 0.28 / 0.42 / 0.92 at its 10th / 50th / 90th percentiles), most where the membrane
balloons near its pressure maximum, so log V at the top nodes is a heavy-tailed function
of the design that the GPs interpolated 0.2-0.66 off (in log V) on the designs they
missed by volume, while the pressure at the same nodes was within 0.02. The log of the
rise takes that tail out. On the FE curves of random designs outside the database
(band calibration set and the five held-out sets), complete curves within the per-curve
target by volume, GP means: Ecoflex/Ecoflex bending away 35 -> 49 of 61, the reversed
pair 90 -> 102 of 115, PDMS on Ecoflex 185 -> 193 of 221 with the anchor at 30 deg
(benchmarks/RESULTS.md, twenty-third session; anchors of 1-60 deg measured).

Variance: log V_j = log V_a + exp(z_j) to first order, the anchor node and the rise taken
as independent: var(log V_j) = var(log V_a) + exp(2 z_j) var(z_j); the rise and its sd
are capped at MAX_LOG_RISE (a GP extrapolating to a corner of the box). The band multipliers
(cross-validation, then FE curves of random designs) are calibrated on these variances,
so a first-order error here is calibrated away with the rest.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from surrogate.emulator.early_ended_nodes import ConditionedMeans, EarlyEndedRows
from surrogate.emulator.features import ANGLE_NODES_DEG, N_NODES
from surrogate.emulator.shape_gps import TOP_PRESSURE_FROM, ShapeGPs
from surrogate.emulator.vector_gp import VectorGP

VOLUME_RISE_ANCHOR_DEG = 30.0
# the smallest rise in log V a training curve is given (V grows with theta on the rising
# branch; the shipped database's smallest rise above 30 deg is far above this)
MIN_LOG_RISE = 1e-6
# the largest rise in log V above the anchor a query is given, and the largest sd of it:
# twice the shipped database's largest (3.1, a 22x volume from 30 to 90 deg), so only a
# GP extrapolating far from its designs reaches it (its linear mean made the rise e^4000 at
# corners of the unit cube, and the volume an overflow); the FE's volume stop ends any
# such curve long before
MAX_LOG_RISE = 6.0
_LOG_THETA = np.log(ANGLE_NODES_DEG)
_LOG_MAX_RISE = np.log(MAX_LOG_RISE)


def anchor_index(anchor_deg: float = VOLUME_RISE_ANCHOR_DEG) -> int:
    """The angle node at ``anchor_deg`` (ValueError if it is not a node)."""
    hit = np.flatnonzero(np.isclose(ANGLE_NODES_DEG, anchor_deg))
    if hit.size != 1:
        raise ValueError(f"volume rise anchor {anchor_deg} deg is not an angle node")
    return int(hit[0])


def rise_outputs(y: np.ndarray, anchor: int | None) -> np.ndarray:
    """The GPs' outputs from node outputs ``y`` (..., 64: log p/theta, log V/theta): the
    volume nodes above ``anchor`` as the log of their rise in log V (none: unchanged)."""
    y = np.array(y, float)
    if anchor is None:
        return y
    lv = y[..., N_NODES:] + _LOG_THETA
    top = np.arange(anchor + 1, N_NODES)
    rise = lv[..., top] - lv[..., anchor:anchor + 1]
    y[..., N_NODES + top] = np.log(np.maximum(rise, MIN_LOG_RISE))
    return y


def node_outputs(mean: np.ndarray, var: np.ndarray, anchor: int | None
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Node outputs (log p/theta, log V/theta) and their variances from the GPs' (the
    inverse of ``rise_outputs``, variance to first order; NaN where the GP's or the
    anchor's variance was not asked)."""
    if anchor is None:
        return mean, var
    mean, var = np.array(mean, float), np.array(var, float)
    a, cols = N_NODES + anchor, slice(N_NODES + anchor + 1, 2 * N_NODES)
    rise = np.exp(np.minimum(mean[..., cols], _LOG_MAX_RISE))
    var[..., cols] = var[..., a:a + 1] + np.minimum(rise**2 * var[..., cols], MAX_LOG_RISE**2)
    mean[..., cols] = (mean[..., a:a + 1] + _LOG_THETA[anchor]) + rise - _LOG_THETA[anchor + 1:]
    return mean, var


@dataclass(frozen=True)
class CurveGPs:
    """A pair's curve GPs (``gp``, on ``rise_outputs``) read as node outputs; with
    ``early_ended`` (its early-ended database curves' outputs, ``early_ended_nodes``) a
    query's ``early_weight`` > 0 blends in the means conditioned on them too and adds the
    two means' spread to the variance (``_blend``). With ``volume`` and ``top_pressure``
    (``shape_gps``) the volume outputs and the pressure outputs from
    ``TOP_PRESSURE_FROM_DEG`` up are theirs, read with the shape of ``gp``'s pressure means
    (before any blend); the blend's shift of the volume outputs is still ``gp``'s
    conditioned minus its own, of the pressure outputs conditioned minus the answer's."""
    gp: VectorGP
    volume_rise_anchor: int | None = None
    early_ended: EarlyEndedRows | None = None
    volume: ShapeGPs | None = None
    top_pressure: ShapeGPs | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "_conditioned", None if self.early_ended is None
                           else ConditionedMeans(self.gp, self.early_ended))
        # with volume GPs a query needs ``gp``'s pressure outputs alone (its volume
        # outputs' means only for a blend's shift): the same GPs, the pressure nodes' kernel
        object.__setattr__(self, "_pressure_gp", None if self.volume is None else VectorGP(
            self.gp.center[:N_NODES], self.gp.scale[:N_NODES], np.eye(N_NODES),
            self.gp.gps[:N_NODES], self.gp.residual_var[:N_NODES]))
        # a one-row query's shape correction is the pressure GPs' kernel row times the
        # shape GPs' weights when both were fitted on the same designs with that kernel
        # (every shipped group): one kernel row for the three, not three
        object.__setattr__(self, "_shares_row", self.volume is not None and all(
            _same_kernel(self.gp, g) for g in (self.volume, self.top_pressure)
            if g is not None))
        object.__setattr__(self, "_selections", {})     # ``_selection``'s, per index array

    def _blend(self, u: np.ndarray, mean: np.ndarray, weight: np.ndarray | float | None
               ) -> tuple[np.ndarray, np.ndarray] | None:
        """What blending the conditioned means in at ``weight`` adds to ``gp``'s means
        ``mean`` (rows of ``u``) and to their variances: w (m_conditioned - m_complete) and
        the blend's spread w (m_conditioned - m_complete)^2 (the two means disagree where
        the early-ended curves pull; the answer is not surer than that). None where
        nothing is blended (no conditioned means, every weight 0)."""
        cond: ConditionedMeans | None = self._conditioned  # type: ignore[attr-defined]
        if cond is None or weight is None:
            return None
        w = np.asarray(weight, float)
        if not (w > 0).any():
            return None
        if mean.ndim == 1:
            d = cond.predict(u) - mean
            return w * d, w * d * d
        shift, spread = np.zeros_like(mean), np.zeros_like(mean)
        on = np.flatnonzero(w > 0)
        d = cond.predict_many(u[on]) - mean[on]
        shift[on] = w[on, None] * d
        spread[on] = w[on, None] * d * d
        return shift, spread

    @property
    def per_output(self) -> bool:
        return self.gp.per_output

    def kernels(self, sel: slice | np.ndarray) -> int:
        """How many distinct kernels the node outputs ``sel`` have (``VectorGP.kernels``)."""
        if self.volume is None:
            return self.gp.kernels(sel)
        on_p, on_top, on_v = _split(np.arange(2 * N_NODES)[sel],
                                    self.top_pressure is not None)
        return (self.gp.kernels(on_p) + self.volume.gp.kernels(on_v)
                + (0 if on_top is None else self.top_pressure.gp.kernels(on_top)))

    def _asked(self, variance_of: slice | np.ndarray | None
               ) -> tuple[slice | np.ndarray | None, bool]:
        """The GP outputs whose variance the asked node outputs' need (the anchor with any
        top volume node), and whether the anchor was added (its variance then not
        returned)."""
        if variance_of is None or self.volume_rise_anchor is None:
            return variance_of, False
        idx = np.arange(2 * N_NODES)[variance_of]
        anchor = N_NODES + self.volume_rise_anchor
        if idx.size and (idx > anchor).any() and anchor not in idx:
            return np.sort(np.append(idx, anchor)), True
        return variance_of, False

    def _selection(self, variance_of: slice | np.ndarray | None) -> tuple:
        """``_asked`` of ``variance_of`` and, with volume GPs, ``_split`` of what it asks
        (None without): worked out once per index array (a query asks for the same few;
        5-8 us of each first query otherwise), read-only."""
        key = ((variance_of.dtype.str, variance_of.shape, variance_of.tobytes())
               if isinstance(variance_of, np.ndarray) and variance_of.dtype != bool else None)
        found = self._selections.get(key) if key is not None else None  # type: ignore[attr-defined]
        if found is None:
            asked, added = self._asked(variance_of)
            if asked is variance_of and key is not None:
                asked = variance_of.copy()          # kept: not the caller's array
            split = (None if self.volume is None
                     else _split(asked, self.top_pressure is not None))
            found = (asked, added, split)
            if key is not None and len(self._selections) < 8:  # type: ignore[attr-defined]
                for a in (asked, *(split or ())):
                    if isinstance(a, np.ndarray):
                        a.flags.writeable = False
                self._selections[key] = found  # type: ignore[attr-defined]
        return found

    def _answer(self, mean: np.ndarray, var: np.ndarray, added: bool
                ) -> tuple[np.ndarray, np.ndarray]:
        mean, var = node_outputs(mean, var, self.volume_rise_anchor)
        if added:
            var[..., N_NODES + self.volume_rise_anchor] = np.nan
        return mean, var

    def predict(self, u: np.ndarray, variance_of: slice | np.ndarray | None = None,
                early_weight: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """Node outputs and variances at one input row (``VectorGP.predict``); the means
        blended with the early-ended-conditioned ones at ``early_weight``."""
        return self.predict_with_plain(u, variance_of, early_weight)[:2]

    def predict_with_plain(self, u: np.ndarray, variance_of: slice | np.ndarray | None = None,
                           early_weight: float = 0.0
                           ) -> tuple[np.ndarray, np.ndarray,
                                      tuple[np.ndarray, np.ndarray] | None]:
        """``predict``, and the pressure nodes' means and variances of the complete-curve
        GPs alone where the blend changed them (what the force model's angle reads:
        ``force_fit.force_angle_rows``; None where nothing was blended)."""
        return self._nodes(np.asarray(u, float).ravel(), variance_of, early_weight)

    def _nodes(self, u: np.ndarray, variance_of: slice | np.ndarray | None,
               early_weight: np.ndarray | float | None
               ) -> tuple[np.ndarray, np.ndarray, tuple[np.ndarray, np.ndarray] | None]:
        """``predict_with_plain`` at one row ``u`` (d,) or at rows (N, d)."""
        asked, added, split = self._selection(variance_of)
        many = u.ndim == 2
        if self.volume is None:
            mean, var = (self.gp.predict_many if many else self.gp.predict)(u, asked)
            out, out_var = mean, var
        else:
            on_p, on_top, on_v = split
            pressure_gp: VectorGP = self._pressure_gp  # type: ignore[attr-defined]
            if many:
                p_mean, p_var = pressure_gp.predict_many(u, on_p)
                v_mean, v_var = self.volume.predict_many(u, p_mean, on_v)
            else:
                rows = pressure_gp.kernel_rows(u)
                shared = rows if self._shares_row else None  # type: ignore[attr-defined]
                p_mean, p_var = pressure_gp.predict(u, on_p, rows)
                v_mean, v_var = self.volume.predict(u, p_mean, on_v, shared)
            if self.top_pressure is not None:
                t_mean, t_var = (self.top_pressure.predict_many(u, p_mean, on_top) if many
                                 else self.top_pressure.predict(u, p_mean, on_top, shared))
                p_mean = np.concatenate((p_mean[..., :TOP_PRESSURE_FROM], t_mean), axis=-1)
                p_var = np.concatenate((p_var[..., :TOP_PRESSURE_FROM], t_var), axis=-1)
            out = np.concatenate((p_mean, v_mean), axis=-1)
            out_var = np.concatenate((p_var, v_var), axis=-1)
            # the blend's shift is the conditioned means minus the answer's own (the volume
            # GPs' and the top pressure GPs' above 45 deg), so that at weight 1 the node
            # outputs are the conditioned means: an early-ended database curve is
            # reproduced on both axes (by volume 406 -> 470 of 565 within 0.2 deg, where
            # the volume outputs' shift had been gp's conditioned minus its own;
            # thirty-eighth session)
            mean, var = out, out_var
        blend = self._blend(u, mean, early_weight)
        plain = None
        if blend is not None:
            plain = (out[..., :N_NODES], out_var[..., :N_NODES])
            out, out_var = out + blend[0], out_var + blend[1]
        return (*self._answer(out, out_var, added), plain)

    def predict_many(self, u: np.ndarray, variance_of: slice | np.ndarray | None = None,
                     early_weight: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Node outputs and variances at input rows ``u`` (``VectorGP.predict_many``);
        row i's means blended at ``early_weight[i]`` (None: all 0)."""
        return self.predict_many_with_plain(u, variance_of, early_weight)[:2]

    def predict_many_with_plain(self, u: np.ndarray,
                                variance_of: slice | np.ndarray | None = None,
                                early_weight: np.ndarray | None = None
                                ) -> tuple[np.ndarray, np.ndarray,
                                           tuple[np.ndarray, np.ndarray] | None]:
        """``predict_many``, and the rows' pressure-node means and variances of the
        complete-curve GPs alone where the blend changed any row (``predict_with_plain``;
        None otherwise)."""
        return self._nodes(np.atleast_2d(np.asarray(u, float)), variance_of, early_weight)


def _same_kernel(gp: VectorGP, shape: ShapeGPs) -> bool:
    """Whether ``shape``'s correction kernel is ``gp``'s pressure nodes' one kernel on the
    same designs (so that its kernel row at a query is theirs)."""
    first = gp.gps[0]
    return (gp.kernels(slice(0, N_NODES)) == 1
            and np.array_equal(first.lengths, shape.pressure_lengths)
            and np.array_equal(first.x, shape.design_inputs))


def _split(asked: slice | np.ndarray | None, top: bool
           ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
    """The node outputs whose variance is asked (None: all) as the pressure GPs' (indices;
    with ``top`` those below ``TOP_PRESSURE_FROM`` only), the top pressure GPs' and the
    volume GPs' (indices from 0 each, None: all; the top's None without ``top``)."""
    if asked is None:
        return np.arange(TOP_PRESSURE_FROM if top else N_NODES), None, None
    idx = np.arange(2 * N_NODES)[asked]
    on_p = idx[idx < N_NODES]
    on_v = idx[idx >= N_NODES] - N_NODES
    if not top:
        return on_p, None, on_v
    return (on_p[on_p < TOP_PRESSURE_FROM], on_p[on_p >= TOP_PRESSURE_FROM] - TOP_PRESSURE_FROM,
            on_v)
