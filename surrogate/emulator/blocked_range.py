"""Where a design's blocked-tip FE curve ends, and so where its force is emulated to.

The blocked-tip force is emulated from the group's blocked-tip FE curves that reach its
force range (``force_fit.force_range``), but many end before it: under volume control the
chamber pressure levels off as the balloon runs away (dp/dV falls to 5-12 % of its
mid-curve value, median by group) and Newton fails just past that pressure maximum; soft
pairs also reach the FE's 500 ul volume stop. In the shipped database, 16 of 92 PDMS-bodied
blocked-tip designs end below 2500 Pa, 36 of 107 reversed-pair and 75 of 107 Ecoflex on
Ecoflex designs. Until 2026-12-06 the force was answered to the group's force range at
every design: an inverse design for 1 mN at 2000 Pa listed three designs whose blocked-tip
FE failed at 2150-2230 Pa, their FE forces 12-17 % below the answer and below its band,
and called 1.53 mN "reachable" at a design whose blocked tip failed at 1909 Pa.

``BlockedRange`` is a GP over the box of log(end / BLOCKED_MAX_PRESSURE_PA) of every
blocked-tip FE curve of the group (the end pressure reduced to the membrane at its preset,
a curve that reached the grid's stop read as ending there), the same kind of model as the
free curves' range model (``PairEmulator.range_model``). The force is given up to
BLOCKED_END_SHARE of the emulated end less BLOCKED_RANGE_Z sd: near the pressure maximum
the force falls below what the complete curves the force model learnt from say (the
answers above 0.9 of the FE end 1-43 % high, median by group, on the database's
early-ended blocked-tip curves, which the force model is not fitted on). With the cut, of the
database's 181 early-ended blocked-tip curves none is given a force past its FE end (4
before), of the held-out sets' 27 none (1); the share of their FE points given a force
fell 0.349 -> 0.330 and 0.426 -> 0.401, on the held-out complete curves 850 -> 849 of 1240
(``benchmarks/blocked_tip_ends.py``, the refit with this change alone; benchmarks/RESULTS.md,
thirty-ninth session).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from solver.precompute.grid import BLOCKED_MAX_PRESSURE_PA
from surrogate.emulator.vector_gp import VectorGP, fit_vector_gp, vector_gp_from_dict

BLOCKED_RANGE_Z = 1.0       # sd short of the emulated end
BLOCKED_END_SHARE = 0.9     # of the emulated end, less that: the force's last pressure
# The force band near the end: p / the emulated end (mean) from these on, one multiplier
# of the band's half-widths per bin (``near_end_band_scales``), 1 below the first.
NEAR_END_FROM = (0.7, 0.8)
NEAR_END_MIN_POINTS = 30    # a bin with fewer calibration points takes the next lower's


def ended_at_pressure_stop(reason: str) -> bool:
    """Whether a blocked-tip FE curve's stop reason (``solver.stepping``) is the solve's
    own pressure stop, i.e. it did not end early."""
    return reason.startswith("reached max_pressure_pa")


def _cause(reason: str) -> str:
    if reason.startswith("reached max_volume_ul"):
        return "reaches the FE's volume stop"
    return ("reaches a pressure maximum, where the balloon runs away and the FE's "
            "Newton iterations fail")


@dataclass(frozen=True)
class BlockedRange:
    """The emulated end of a group's blocked-tip FE curves over the box.

    model    GP of log(end_pa / cap_pa) over the unit box (one output)
    cap_pa   the blocked-tip solves' pressure stop (reduced Pa); a curve that reached it
             counts as ending there
    ended    (unit coordinates, end pressure reduced Pa, FE stop reason) of the group's
             blocked-tip curves that ended before cap_pa (the reason of the nearest says
             why a query's range ends)
    """

    model: VectorGP
    cap_pa: float
    ended: tuple = ()
    # multipliers of the force band's half-widths at p / emulated end >= NEAR_END_FROM[i]
    # (``near_end_band_scales``; ones: not calibrated)
    near_end_band_scale: tuple[float, ...] = (1.0,) * len(NEAR_END_FROM)

    def __post_init__(self) -> None:
        # the ended curves' unit coordinates stacked once (``reason``'s nearest)
        object.__setattr__(self, "_ended_u", np.array([np.asarray(e[0], float)
                                                      for e in self.ended]))

    def ends_pa(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The emulated end pressure (reduced Pa) of the blocked-tip FE curve at each row
        of ``u`` (m, 6), and the sd of its log."""
        u = np.asarray(u, float)
        if u.ndim == 1:         # one design: the single-row path (a query's)
            m, var = (a[None, :] for a in self.model.predict(u))
        else:
            m, var = self.model.predict_many(u)
        return self.cap_pa * np.exp(m[:, 0]), np.sqrt(np.maximum(var[:, 0], 0.0))

    def force_ends_pa(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The last reduced pressure (Pa) at which the force is given at each row of
        ``u`` (BLOCKED_END_SHARE of the emulated end less BLOCKED_RANGE_Z sd of its log),
        and the emulated end itself (reduced Pa, the mean)."""
        end, sd_log = self.ends_pa(u)
        return BLOCKED_END_SHARE * end * np.exp(-BLOCKED_RANGE_Z * sd_log), end

    def band_scales(self, pressure_red_pa: np.ndarray, end_pa: np.ndarray | float
                    ) -> np.ndarray:
        """The force band's multiplier at each reduced pressure (Pa) of a design whose
        blocked-tip curve is emulated to end at ``end_pa`` (reduced, the mean; an array
        broadcasts: one row per design)."""
        s = np.asarray(pressure_red_pa, float) / np.asarray(end_pa, float)
        which = np.searchsorted(NEAR_END_FROM, s, side="right")      # 0: below the first
        return np.concatenate(([1.0], self.near_end_band_scale))[which]

    def left_out_ends_pa(self, u: np.ndarray) -> np.ndarray:
        """The emulated end (reduced Pa, the mean) of each row of ``u`` that is one of
        the model's own designs as the model would emulate it without that design
        (leave-one-out); inf for any other row."""
        gp = self.model.gps[0]
        mean, _ = self.model.loo()
        own = {tuple(x): self.cap_pa * float(np.exp(m))
               for x, m in zip(np.round(gp.x, 9), mean[:, 0], strict=True)}
        return np.array([own.get(tuple(x), np.inf) for x in np.round(np.atleast_2d(u), 9)])

    def reason(self, u: np.ndarray, end_pa: float, force_end_pa: float,
               pressure_scale: float) -> str:
        """Why the force ends where ``force_ends_pa`` says (``force_end_pa``, with the
        emulated end ``end_pa``; both reduced Pa, as it returned them) for the design at
        unit coordinates ``u`` (its pressure scale converts to chamber Pa)."""
        end = end_pa
        sd_log = np.log(BLOCKED_END_SHARE * end_pa / force_end_pa) / BLOCKED_RANGE_Z
        cause = "reaches a pressure maximum or the FE's volume stop"
        if self.ended:
            near = int(np.argmin(np.sum((self._ended_u - u) ** 2, axis=1)))
            cause = _cause(self.ended[near][2])
        return (f"this design's blocked-tip FE curve is emulated to end at "
                f"{end * pressure_scale:.0f} Pa (+/- {100 * sd_log:.0f} %): nearby "
                f"blocked-tip FE curves end where the chamber {cause}, and near that end "
                "the force falls below what the force model learnt from curves that run on; "
                f"the force is given to {100 * BLOCKED_END_SHARE:.0f} % of that end, "
                f"{BLOCKED_RANGE_Z:g} sd short")

    def as_dict(self) -> dict:
        return {"model": self.model.as_dict(), "cap_pa": self.cap_pa,
                "ended": [[np.asarray(u).tolist(), float(p), str(r)]
                          for u, p, r in self.ended],
                "near_end_band_scale": list(self.near_end_band_scale)}


def near_end_band_scales(factors: np.ndarray, s: np.ndarray, level: float
                         ) -> tuple[float, ...]:
    """The force band's multipliers near the end of the blocked-tip curve, one per bin of
    NEAR_END_FROM: the ``level`` quantile of the calibration points' ``factors`` (by how
    much the band's half-width would have to grow to reach the FE value) at p / emulated
    end ``s`` in the bin, never below 1 nor below the bin before; a bin with fewer than
    NEAR_END_MIN_POINTS points takes the bin before's."""
    out, last = [], 1.0
    edges = (*NEAR_END_FROM, np.inf)
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        f = np.asarray(factors, float)[(s >= lo) & (s < hi)]
        if len(f) >= NEAR_END_MIN_POINTS:
            last = max(last, float(np.quantile(f, level)))
        out.append(last)
    return tuple(out)


def blocked_range_from_dict(d: dict | None) -> BlockedRange | None:
    """The blocked range stored by ``as_dict`` (None: none stored); ValueError, TypeError
    or KeyError for a damaged one."""
    if d is None:
        return None
    cap = float(d["cap_pa"])
    if not (np.isfinite(cap) and cap > 0):
        raise ValueError(f"blocked_range cap_pa {cap!r}: a positive pressure (Pa)")
    model = vector_gp_from_dict(d["model"])
    if model.center.shape != (1,):
        raise ValueError("blocked_range model: one output (the log of the end pressure)")
    ended = tuple((np.array(u, float), float(p), str(r)) for u, p, r in d["ended"])
    if any(u.shape != model.gps[0].x.shape[1:] or not 0 < p <= cap for u, p, _ in ended):
        raise ValueError("blocked_range ended: unit coordinates and an end within the cap")
    scales = tuple(float(x) for x in d.get("near_end_band_scale", (1.0,) * len(NEAR_END_FROM)))
    if len(scales) != len(NEAR_END_FROM) or not all(1.0 <= x < 1e3 for x in scales):
        raise ValueError(f"blocked_range near_end_band_scale {scales!r}: "
                         f"{len(NEAR_END_FROM)} multipliers >= 1")
    return BlockedRange(model, cap, ended, scales)


def fit_blocked_range(u: np.ndarray, end_pa: np.ndarray, reasons: list[str], seed: int = 0
                      ) -> BlockedRange | None:
    """The blocked range of a group from its blocked-tip FE curves: unit coordinates
    ``u`` (n, 6), their last pressures ``end_pa`` (reduced Pa) and stop reasons; None
    when every curve reached the pressure stop (nothing to emulate) or there are none."""
    cap = BLOCKED_MAX_PRESSURE_PA
    early = np.array([not ended_at_pressure_stop(r) for r in reasons], bool)
    if not len(u) or not early.any():
        return None
    end = np.where(early, np.minimum(np.asarray(end_pa, float), cap), cap)
    model = fit_vector_gp(np.asarray(u, float), np.log(end / cap)[:, None], seed=seed)
    ended = tuple((np.asarray(u[i], float), float(end[i]), reasons[i])
                  for i in np.flatnonzero(early & (end < cap)))
    return BlockedRange(model, cap, ended)
