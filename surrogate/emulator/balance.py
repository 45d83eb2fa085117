"""The emulator at a soft pair's stiffness balance: the signed angle by injected volume.

    model, report = fit_balance_model(u, curves)    # the group's FE curves, reduced
    nodes = model.nodes(u)                          # one GP evaluation
    angle, lower, upper, p_red = model.by_volume(nodes, v_red, z)
    angle, lower, upper, v_red = model.by_pressure(nodes, p_red, z)

Physics. Where the body and the membrane are alike in stiffness (Ecoflex on Ecoflex, the
contrast s_body / s_membrane near the balance), both balloon and the actuator bends little,
either way: the FE curve runs to its volume stop (500 ul, ``SolverSettings.max_volume_ul``)
at a few degrees or a few tens of degrees, not to 90 deg. The per-direction curve GPs
(log pressure at fixed |angle|, ``curve_gps``) need the direction first and have no node
for a curve that turns at 3 deg; the group's sign model cannot tell the direction within
``emulator.SIGN_MARGIN`` of the balance, and those designs were refused (13 of the 492
random box designs of the band calibration and held-out sets, 2026-12-05).

The signed angle at a fixed injected volume passes through zero continuously as the
contrast crosses the balance, so it is interpolated across it: outputs are the signed
angle (deg) at VOLUME_NODES_UL (reduced design, W = 3 mm; one kernel) and the log of the
chamber pressure (Pa, reduced) at the same volumes (one GP each), fitted on every database
curve of the group that reaches the last node before 90 deg: the curves that end at the
volume stop. By pressure, p(V) (made non-decreasing) is inverted first. The bands are the
GPs' sd times a multiplier per axis, from the leave-one-out predictions of the fitted
curves read at their own FE points (the 95 % quantile of |error| / sd over 1.96; a
point within the answer's 0.05 deg floor is inside at any multiplier).

Range: up to the last node (480 ul, short of the volume stop) or the FE's volume stop for
the design's size, whichever is smaller; no force is emulated here (no blocked-tip model
near the balance). Answers are flagged ``near_stiffness_balance`` (``Emulator``).

Curves that turn back. Near the balance the FE's |angle| can pass a peak and fall as the
injected volume grows (the membrane's balloon takes over the body's bending): 52 of the
shipped database's 2283 default free-tip curves fall by more than 0.5 deg, 13 by 3.5-11
deg, all with a soft (Ecoflex) body. Few curves are like that, and the model's error there
is larger: where its leave-one-out mean turns back by more than TURN_BACK_DEG, 95 % of the
fitted curves' own points need 1.2-1.8 x the band the rest need (the fiftieth session,
benchmarks/RESULTS.md). So the band multipliers are fitted twice, on the curves whose
leave-one-out mean turns back and on the rest, and a design whose emulated curve turns back
(``turn_back_deg``) gets the first pair and the flag ``curve_turns_back``; the rest the
second (one pair over every curve, as before, made the others' band too wide: it covered
0.995 of the FE points of the random designs whose emulated curve does not turn back).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from surrogate.band_level import z_value
from surrogate.emulator.features import ANGLE_BAND_FLOOR_DEG
from surrogate.emulator.vector_gp import VectorGP, fit_output_gps, vector_gp_from_dict

VOLUME_NODES_UL = np.geomspace(2.0, 480.0, 24)   # reduced design (W = 3 mm), ul
N_VOLUME_NODES = len(VOLUME_NODES_UL)
MIN_CURVES = 30             # fewer curves at the volume stop: no balance model
CALIBRATION_LEVEL = 0.95    # the multipliers are fitted at this level
# A curve whose |angle| at the volume nodes falls by more than this after its peak turns
# back (deg): its band multipliers are those fitted on such curves, and its answers are
# flagged curve_turns_back. It marks 15 of the Ecoflex/Ecoflex group's 324 fitted curves
# and 13 of the reversed pair's 56, by their leave-one-out means.
TURN_BACK_DEG = 1.0
MIN_TURNING_CURVES = 5      # fewer turning curves: they keep the plain multipliers


def on_nodes(v_red: np.ndarray, p_red: np.ndarray, angle_deg: np.ndarray
             ) -> np.ndarray | None:
    """(signed angle at VOLUME_NODES_UL, log p there) of one FE curve (reduced injected
    volume in ul, reduced pressure in Pa, signed angle in deg), read on its rising-volume
    part; None when the curve does not reach the last node."""
    v, p, a = (np.asarray(x, float) for x in (v_red, p_red, angle_deg))
    falls = np.flatnonzero(np.diff(v) <= 0)
    if falls.size:
        k = falls[0] + 1
        v, p, a = v[:k], p[:k], a[:k]
    if len(v) < 3 or v[-1] < VOLUME_NODES_UL[-1] or (p[1:] <= 0).any():
        return None
    log_p = np.interp(VOLUME_NODES_UL, v[1:], np.log(p[1:]))
    return np.concatenate((np.interp(VOLUME_NODES_UL, v, a), log_p))


def _angle_at(v_red: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    """Values given at VOLUME_NODES_UL read at ``v_red``: linear in log V between nodes,
    linear from (0, 0) below the first."""
    v = np.asarray(v_red, float)
    inside = np.interp(np.log(np.maximum(v, VOLUME_NODES_UL[0])), np.log(VOLUME_NODES_UL),
                       nodes)
    return np.where(v < VOLUME_NODES_UL[0], nodes[0] * v / VOLUME_NODES_UL[0], inside)


def _volume_at(p_red: np.ndarray, p_nodes: np.ndarray) -> np.ndarray:
    """The reduced volume at reduced pressures ``p_red`` off p(V) at the nodes (strictly
    increasing): linear in log-log between nodes, linear from (0, 0) below the first,
    infinite above the last (past the range)."""
    p = np.asarray(p_red, float)
    log_v = np.interp(np.log(np.maximum(p, p_nodes[0])), np.log(p_nodes),
                      np.log(VOLUME_NODES_UL), right=np.inf)
    return np.where(p < p_nodes[0], VOLUME_NODES_UL[0] * p / p_nodes[0], np.exp(log_v))


def _pressure_at(v_red: np.ndarray, p_nodes: np.ndarray) -> np.ndarray:
    """The inverse of ``_volume_at``: the reduced pressure at reduced volumes."""
    v = np.asarray(v_red, float)
    log_p = np.interp(np.log(np.maximum(v, VOLUME_NODES_UL[0])), np.log(VOLUME_NODES_UL),
                      np.log(p_nodes))
    return np.where(v < VOLUME_NODES_UL[0], p_nodes[0] * v / VOLUME_NODES_UL[0],
                    np.exp(log_p))


def first_reach(v_red: np.ndarray, angle_deg: np.ndarray, target_deg: np.ndarray
                ) -> np.ndarray:
    """For each signed target angle, the first volume of the rising grid ``v_red`` at which
    the signed ``angle_deg`` on it reaches the target (as far from zero, the same sign),
    linear between grid points; 0 for a target of 0, NaN where it is never reached."""
    out = np.full(np.shape(target_deg), np.nan)
    for i, t in enumerate(np.asarray(target_deg, float)):
        if t == 0.0:
            out[i] = 0.0
            continue
        signed = np.sign(t) * angle_deg
        hit = np.flatnonzero(signed >= abs(t))
        if not hit.size:
            continue
        k = int(hit[0])
        out[i] = v_red[0] if k == 0 else float(np.interp(
            abs(t), signed[k - 1:k + 1], v_red[k - 1:k + 1]))
    return out


def turn_back_deg(angle_nodes: np.ndarray) -> float:
    """How far (deg, >= 0) the |signed angle| at the volume nodes falls after its peak
    before the last node: 0 for a curve that never turns back."""
    a = np.abs(np.asarray(angle_nodes, float))
    return float(a.max() - a[-1]) if a.size else 0.0


def turns_back(angle_nodes: np.ndarray) -> bool:
    """Whether a curve's |angle| at the volume nodes falls by more than TURN_BACK_DEG."""
    return turn_back_deg(angle_nodes) > TURN_BACK_DEG


def _increasing(p: np.ndarray) -> np.ndarray:
    """``p`` made strictly increasing (a flat stretch rises by 1e-9 relative a node)."""
    p = np.maximum.accumulate(p)
    return p * (1.0 + 1e-9 * np.arange(len(p)))


@dataclass(frozen=True)
class BalanceModel:
    """The signed angle and log pressure at VOLUME_NODES_UL over the group's unit cube.

    gp                   outputs: signed angle (deg) at the nodes, then log p (Pa)
    band_scale_volume    sd multiplier of the angle read by injected volume
    band_scale_pressure  sd multiplier of the angle read by pressure
    turn_scales          the two multipliers (volume, pressure) of a curve that turns
                         back (``turn_back_deg`` above TURN_BACK_DEG); files made before
                         the fiftieth session have none: the plain ones apply
    """

    gp: VectorGP
    band_scale_volume: float
    band_scale_pressure: float
    turn_scales: tuple[float, float] | None = None

    def scales(self, nodes: tuple) -> tuple[float, float]:
        """The (volume, pressure) band multipliers of an answer from ``nodes``
        (``self.nodes(u)``): the turning curves' where its curve turns back."""
        if self.turn_scales is not None and turns_back(nodes[0]):
            return self.turn_scales
        return self.band_scale_volume, self.band_scale_pressure

    @property
    def designs(self) -> int:
        return len(self.gp.gps[0].y)

    def nodes(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(signed angle, its sd, strictly increasing reduced pressure) at the nodes."""
        mean, var = self.gp.predict(u, variance_of=slice(0, N_VOLUME_NODES))
        angle = mean[:N_VOLUME_NODES]
        sd = np.sqrt(np.maximum(var[:N_VOLUME_NODES], 0.0))
        return angle, sd, _increasing(np.exp(mean[N_VOLUME_NODES:]))

    def top_deg(self, u: np.ndarray, z: float) -> float:
        """|angle| at the last volume node plus ``z`` of its sd (band multiplier by
        volume included), deg: below 90 the design's FE curve ends at the volume stop."""
        last = N_VOLUME_NODES - 1
        mean, var = self.gp.predict(u, variance_of=np.array([last]))
        return float(abs(mean[last]) + z * self.band_scale_volume * np.sqrt(max(var[last], 0.0)))

    def by_volume(self, nodes: tuple, v_red: np.ndarray, z: float
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(angle, lower, upper in deg; reduced pressure in Pa) at reduced volumes, from
        ``nodes`` (``self.nodes(u)``: one GP evaluation serves every reading)."""
        angle, sd, p_nodes = nodes
        return (*self._band(v_red, angle, sd, z, self.scales(nodes)[0]),
                _pressure_at(v_red, p_nodes))

    def by_pressure(self, nodes: tuple, p_red: np.ndarray, z: float
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(angle, lower, upper in deg; reduced volume in ul) at reduced pressures, from
        ``nodes`` (``self.nodes(u)``)."""
        angle, sd, p_nodes = nodes
        v_red = _volume_at(p_red, p_nodes)
        return (*self._band(v_red, angle, sd, z, self.scales(nodes)[1]), v_red)


    def volumes_for(self, nodes: tuple, angle_deg: np.ndarray, v_end: float, z: float
                    ) -> tuple[tuple[np.ndarray, ...], tuple[np.ndarray, ...]]:
        """The answer by volume read backwards: for each signed target angle (deg), the
        first reduced injected volume (ul) up to ``v_end`` at which the model's angle
        reaches it -- a syringe pump reaches it there first --, and the reduced chamber
        pressure (Pa) at that volume; each as (value, lower, upper), NaN where the angle
        is not reached by ``v_end``. The volume band is where the angle band by volume
        reaches the target, the pressure band where the angle band by pressure does (the
        bands ``by_volume`` and ``by_pressure`` give), so that each forward answer at the
        value returned gives the target."""
        angle, sd, p_nodes = nodes
        grid = np.concatenate(([0.0], np.geomspace(VOLUME_NODES_UL[0] * 1e-3, v_end, 4000)))
        mean = _angle_at(grid, angle)
        target = np.asarray(angle_deg, float)
        volume = first_reach(grid, mean, target)
        edges = []
        for scale in self.scales(nodes):
            half = z * scale * _angle_at(grid, sd)
            a, b = first_reach(grid, mean - half, target), first_reach(grid, mean + half, target)
            edges.append((np.fmin(a, b), np.where(np.isnan(a) | np.isnan(b), np.nan,
                                                  np.fmax(a, b))))
        (v_lo, v_hi), (pv_lo, pv_hi) = edges
        pressure = tuple(np.where(np.isnan(v), np.nan, _pressure_at(np.nan_to_num(v), p_nodes))
                         for v in (volume, pv_lo, pv_hi))
        return (volume, v_lo, v_hi), pressure

    @staticmethod
    def _band(v_red: np.ndarray, angle: np.ndarray, sd: np.ndarray, z: float, scale: float
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        mean = _angle_at(v_red, angle)
        half = z * scale * _angle_at(v_red, sd)
        return mean, mean - half, mean + half

    def as_dict(self) -> dict[str, object]:
        out = {"volume_nodes_ul": VOLUME_NODES_UL.tolist(), "gp": self.gp.as_dict(),
               "band_scale_volume": self.band_scale_volume,
               "band_scale_pressure": self.band_scale_pressure}
        if self.turn_scales is not None:
            out["turn_band_scales"] = list(self.turn_scales)
        return out


def balance_model_from_dict(d: object) -> BalanceModel:
    """The stored model; ValueError (naming the field) when it is damaged or was made with
    other volume nodes."""
    if not isinstance(d, dict):
        raise ValueError("balance_models: each must be an object")
    if d.get("volume_nodes_ul") != VOLUME_NODES_UL.tolist():
        raise ValueError("balance_models volume_nodes_ul: made with other volume nodes "
                         "than this code uses")
    gp = vector_gp_from_dict(d["gp"])
    if len(gp.gps) != 2 * N_VOLUME_NODES:
        raise ValueError(f"balance_models gp must have {2 * N_VOLUME_NODES} outputs")
    scales = [float(d["band_scale_volume"]), float(d["band_scale_pressure"])]
    turn = d.get("turn_band_scales")
    if turn is not None:
        if not isinstance(turn, list) or len(turn) != 2:
            raise ValueError("balance_models turn_band_scales must be two numbers")
        turn = [float(x) for x in turn]
    if not all(np.isfinite(s) and s >= 1.0 for s in scales + (turn or [])):
        raise ValueError("balance_models band scales must be finite and >= 1")
    return BalanceModel(gp, *scales, turn_scales=None if turn is None else tuple(turn))


def fit_balance_model(u: np.ndarray, curves: list[tuple[np.ndarray, np.ndarray, np.ndarray]],
                      seed: int = 0) -> tuple[BalanceModel | None, dict[str, object]]:
    """The model from a group's database curves: unit coordinates ``u`` (n, d) and each
    curve's (reduced volume ul, reduced pressure Pa, signed angle deg); those that reach
    the last volume node are used. None (and why, in the report) with fewer than
    MIN_CURVES of them."""
    rows = [(x, y) for x, c in zip(u, curves, strict=True)
            if (y := on_nodes(*c)) is not None]
    report: dict[str, object] = {"curves": len(rows)}
    if len(rows) < MIN_CURVES:
        report["fitted"] = False
        return None, report
    x = np.array([r[0] for r in rows])
    y = np.array([r[1] for r in rows])
    gp = fit_output_gps(x, y, seed=seed, shared=slice(0, N_VOLUME_NODES))
    used = [c for c in curves if on_nodes(*c) is not None]
    scales, turn, calibration = loo_band_scales(gp, used)
    report.update({"fitted": True, "band_scale_volume": scales[0],
                   "band_scale_pressure": scales[1], **calibration})
    return BalanceModel(gp, *scales, turn_scales=turn), report


def loo_band_scales(gp: VectorGP, curves: list
                    ) -> tuple[tuple[float, float], tuple[float, float] | None, dict]:
    """The sd multipliers per axis (volume, pressure; >= 1) that make the leave-one-out
    bands of the fitted curves ``curves`` (each (reduced volume ul, reduced pressure Pa,
    signed angle deg), in ``gp``'s row order) cover CALIBRATION_LEVEL of their own FE
    points up to the last node: over the curves whose leave-one-out mean does not turn
    back, and over those whose mean does (``turns_back``; never narrower than the
    others'). With fewer than MIN_TURNING_CURVES turning curves: one pair over every
    curve, and None. Also a report (curves, coverage, and the one pair over every curve,
    which files before format 18 have as their only pair)."""
    mean, var = gp.loo()
    ratios: dict[str, list[np.ndarray]] = {"volume": [], "pressure": []}
    turning = []
    for m, s2, (v, p, a) in zip(mean, var, curves, strict=True):
        angle, sd = m[:N_VOLUME_NODES], np.sqrt(np.maximum(s2[:N_VOLUME_NODES], 0.0))
        turning.append(turns_back(angle))
        p_nodes = _increasing(np.exp(m[N_VOLUME_NODES:]))
        keep = (v > 0) & (v <= VOLUME_NODES_UL[-1])
        for axis, v_read in (("volume", v[keep]), ("pressure", _volume_at(p[keep], p_nodes))):
            err = np.abs(_angle_at(v_read, angle) - a[keep])
            # inside the answer's floor (emulator.floored_band) at any multiplier
            ratios[axis].append(np.where(err <= ANGLE_BAND_FLOOR_DEG, 0.0,
                                         err / np.maximum(_angle_at(v_read, sd), 1e-12)))
    z = z_value(CALIBRATION_LEVEL)

    def multipliers(which: list[bool], floor: tuple[float, float] = (1.0, 1.0)
                    ) -> tuple[tuple[float, float], dict[str, float]]:
        pooled = {axis: np.concatenate([r for r, w in zip(ratios[axis], which, strict=True)
                                        if w]) for axis in ("volume", "pressure")}
        scales = tuple(max(f, float(np.quantile(pooled[axis], CALIBRATION_LEVEL)) / z)
                       for axis, f in zip(("volume", "pressure"), floor, strict=True))
        coverage = {axis: float(np.mean(pooled[axis] <= z * s))
                    for axis, s in zip(("volume", "pressure"), scales, strict=True)}
        return scales, coverage  # type: ignore[return-value]

    every, every_coverage = multipliers([True] * len(turning))
    report: dict[str, object] = {"turning_curves": sum(turning),
                                 "every_curve_band_scales": list(every),
                                 "every_curve_loo_coverage": every_coverage}
    if sum(turning) < MIN_TURNING_CURVES:
        report["loo_coverage"] = every_coverage
        return every, None, report
    scales, coverage = multipliers([not t for t in turning])
    turn, turn_coverage = multipliers(turning, floor=scales)        # never narrower
    report.update({"loo_coverage": coverage, "turn_band_scales": list(turn),
                   "turn_loo_coverage": turn_coverage})
    return scales, turn, report
