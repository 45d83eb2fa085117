"""A family's pressure-volume relation, from the FE curves' own injected volumes.

The exponential model gives angle(p); a syringe pump sets the injected volume V (ul,
whole actuator). Every FE curve of the family stores V at each converged step, and under
volume control the angle rises monotonically with V (also past a pressure maximum), so
the relation is kept as V(theta; L, t): for each design the curve's V against |angle| at
``N_NODES`` common angle nodes up to ``angle_max_deg`` (the smallest largest FE angle of
the family's designs; spaced as (k / N)^2, dense at small angles, where the FE's angle
starts slowly while the volume already grows, 2 deg apart at the top), and across
designs an interpolation of y = ln(V / theta) at each node in the coordinates (1 / L,
t): a cubic radial basis function with a linear tail (exact at every FE design, smooth
between them, linear outside; with too few designs for the tail, a linear kernel). Why 1
/ L: at a given angle theta = kappa L the chamber's curvature kappa = theta / L sets how
far the membrane is stretched and bulges, so V(theta) follows 1 / L rather than L
(measured leave-one-design-out on the shipped families at the FE points: volume RMS
3.6-7.8 % in 1 / L against 7.1-16.3 % in L, both with the cubic kernel; a thin-plate
spline does worse in either; benchmarks/RESULTS.md). Between nodes V is linear in theta. No
exponential-model parameter enters: at a database design the relation reproduces the
FE's own V(theta) up to the linear interpolation between nodes.

A by-volume answer reads theta at V off this V(theta), and the pressure is the
exponential model's at that angle (``Surrogate.predict_volume``). The band on theta:
V(theta) exp(+-z k s), s the leave-one-design-out RMS of y (refit without each design,
predict it), k >= 1 the factor that puts ``level`` of those held-out errors inside
(``fit_volume_relation``); the held-out error is also reported in ul and %.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import RBFInterpolator

from solver.errors import InputError

VERSION = 1
N_NODES = 90                 # angle nodes above 0: theta_k = angle_max (k / N)^2
MIN_DESIGNS = 1
KERNEL = "cubic"             # needs the linear tail; "linear" below that


@dataclass(frozen=True)
class VolumeRelation:
    """V(theta; L, t) of one family (see the module docstring). ``designs`` (L_mm, t_mm)
    and ``log_v_per_deg`` (per design, ln(V / theta) at ``angle_nodes_deg``); ``log_sd``
    and ``band_scale`` give the band; ``lodo`` the held-out errors (plain JSON)."""

    angle_nodes_deg: tuple[float, ...]
    designs: tuple[tuple[float, float], ...]
    log_v_per_deg: tuple[tuple[float, ...], ...]
    log_sd: float
    band_scale: float
    lodo: dict

    @property
    def angle_max_deg(self) -> float:
        return self.angle_nodes_deg[-1]

    def volume_curve_ul(self, L_mm: float, t_mm: float) -> np.ndarray:
        """V (ul) at ``angle_nodes_deg`` (with 0 at 0 deg prepended) for one design."""
        y = _interpolate(np.asarray(self.designs, float), np.asarray(self.log_v_per_deg, float),
                         np.array([[L_mm, t_mm]]))[0]
        nodes = np.asarray(self.angle_nodes_deg, float)
        return np.concatenate([[0.0], np.maximum.accumulate(nodes * np.exp(y))])

    def band_curves_ul(self, L_mm: float, t_mm: float, z: float
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(V, V low, V high) (ul) on the nodes with 0 deg prepended, band at quantile z."""
        v = self.volume_curve_ul(L_mm, t_mm)
        f = float(np.exp(z * self.band_scale * self.log_sd))
        return v, v / f, v * f

    def as_dict(self) -> dict[str, object]:
        return {"version": VERSION, "method": f"rbf_{KERNEL}_linear_tail_in_1/L_t",
                "quantity": "ln(volume_ul / angle_deg) at angle nodes",
                "angle_nodes_deg": list(self.angle_nodes_deg),
                "designs": [list(d) for d in self.designs],
                "log_v_per_deg": [list(r) for r in self.log_v_per_deg],
                "log_sd": self.log_sd, "band_scale": self.band_scale, "lodo": dict(self.lodo)}


def volume_relation_from_dict(d: dict) -> VolumeRelation:
    if int(d.get("version", 0)) > VERSION:
        raise ValueError(f"volume relation version {d.get('version')!r} is newer than this "
                         f"code reads ({VERSION})")
    rel = VolumeRelation(angle_nodes_deg=tuple(float(x) for x in d["angle_nodes_deg"]),
                         designs=tuple((float(a), float(b)) for a, b in d["designs"]),
                         log_v_per_deg=tuple(tuple(float(x) for x in r)
                                             for r in d["log_v_per_deg"]),
                         log_sd=float(d["log_sd"]), band_scale=float(d["band_scale"]),
                         lodo=dict(d.get("lodo", {})))
    if (len(rel.designs) != len(rel.log_v_per_deg) or not rel.designs
            or any(len(r) != len(rel.angle_nodes_deg) for r in rel.log_v_per_deg)
            or not np.isfinite(np.asarray(rel.log_v_per_deg)).all()
            or not (rel.log_sd >= 0 and rel.band_scale >= 1)):
        raise ValueError("volume relation: arrays of unequal length or values out of range")
    return rel


def _coordinates(designs: np.ndarray) -> np.ndarray:
    """(L_mm, t_mm) rows -> (1 / L_mm, t_mm) (see the module docstring)."""
    return np.column_stack([1.0 / designs[:, 0], designs[:, 1]])


def _span(designs: np.ndarray) -> np.ndarray:
    c = _coordinates(designs)
    return c.max(axis=0) - c.min(axis=0)


def _interpolate(designs: np.ndarray, values: np.ndarray, at: np.ndarray) -> np.ndarray:
    """values (n_designs, n_nodes) at the (L, t) rows of ``at``: the RBF over the axes
    with more than one value (scaled by their ranges), a constant with one design."""
    axes = _span(designs) > 0
    if len(designs) == 1 or not axes.any():
        return np.repeat(values[:1], len(at), axis=0)
    x, q = (_coordinates(d)[:, axes] / c_span[axes]
            for d, c_span in ((designs, _span(designs)), (at, _span(designs))))
    if len(designs) > x.shape[1] + 1:
        return RBFInterpolator(x, values, kernel=KERNEL, degree=1)(q)
    return RBFInterpolator(x, values, kernel="linear", degree=0)(q)


def curve_nodes(angle_deg: np.ndarray, volume_ul: np.ndarray, nodes: np.ndarray
                ) -> np.ndarray:
    """ln(V / theta) of one FE curve at the angle nodes (|angle|, the rising part)."""
    a = np.abs(np.asarray(angle_deg, float))
    v = np.asarray(volume_ul, float)
    ok = np.isfinite(a) & np.isfinite(v)
    a, v = a[ok], v[ok]
    keep = np.concatenate([[True], np.diff(np.maximum.accumulate(a)) > 0])  # rising angle
    a, v = np.concatenate([[0.0], a[keep]]), np.concatenate([[0.0], v[keep]])
    order = np.argsort(a, kind="stable")
    return np.log(np.interp(nodes, a[order], v[order]) / nodes)


@dataclass(frozen=True)
class VolumeCurve:
    """One FE curve's design (L_mm, t_mm) and its angle (deg) and volume (ul) columns."""

    L_mm: float
    t_mm: float
    angle_deg: np.ndarray
    volume_ul: np.ndarray


def fit_volume_relation(curves: list[VolumeCurve], level: float = 0.95
                        ) -> VolumeRelation | None:
    """The family's relation from its FE curves; None without a usable volume column.
    Leave-one-design-out (with >= 3 designs): each design's V(theta) predicted from the
    others and compared with its FE curve at the FE's own points up to ``angle_max_deg``
    (``_held_out_errors``)."""
    usable = [c for c in curves if c.volume_ul is not None
              and np.isfinite(c.volume_ul).sum() >= 3 and np.nanmax(c.volume_ul) > 0
              and np.nanmax(np.abs(c.angle_deg)) > 0]
    if len(usable) < MIN_DESIGNS:
        return None
    top = min(float(np.nanmax(np.abs(c.angle_deg))) for c in usable)
    nodes = top * (np.arange(1, N_NODES + 1) / N_NODES) ** 2
    designs = np.array([[c.L_mm, c.t_mm] for c in usable])
    y = np.array([curve_nodes(c.angle_deg, c.volume_ul, nodes) for c in usable])
    lodo: dict[str, object] = {"n_designs": len(usable)}
    log_sd, scale = 0.0, 1.0
    if len(usable) >= 3:
        lodo, log_sd, scale = _held_out_errors(usable, designs, y, nodes, level)
    return VolumeRelation(angle_nodes_deg=tuple(float(n) for n in nodes),
                          designs=tuple((float(a), float(b)) for a, b in designs),
                          log_v_per_deg=tuple(tuple(float(v) for v in r) for r in y),
                          log_sd=log_sd, band_scale=scale, lodo=lodo)


MIN_PERCENT_ANGLE_DEG = 5.0   # relative errors are reported from this angle on


def _held_out_errors(usable: list[VolumeCurve], designs: np.ndarray, y: np.ndarray,
                     nodes: np.ndarray, level: float) -> tuple[dict, float, float]:
    """Each design left out in turn, its V(theta) interpolated from the others and read
    at its FE points (|angle| from 0.5 deg to the top node): the volume error (ul, and %
    from ``MIN_PERCENT_ANGLE_DEG`` on) at the FE angle, the angle error (deg) at the FE
    volume; (report, RMS of the ln V error, band factor k >= 1 that puts ``level`` of
    the ln V errors inside z k s)."""
    from surrogate.band_level import z_value

    grid = np.concatenate([[0.0], nodes])
    rows, dv, dlog, da, rel = [], [], [], [], []
    for i, c in enumerate(usable):
        yi = _interpolate(np.delete(designs, i, 0), np.delete(y, i, 0), designs[i:i + 1])[0]
        v_pred = np.concatenate([[0.0], np.maximum.accumulate(nodes * np.exp(yi))])
        a = np.abs(np.asarray(c.angle_deg, float))
        v = np.asarray(c.volume_ul, float)
        keep = np.isfinite(a) & np.isfinite(v) & (a >= 0.5) & (a <= nodes[-1]) & (v > 0)
        keep &= np.interp(a, grid, v_pred) > 0
        a, v = a[keep], v[keep]
        if not a.size:   # nothing of this curve to compare in the relation's range
            continue
        e_v = np.interp(a, grid, v_pred) - v
        e_a = np.interp(v, v_pred, grid) - a
        big = a >= MIN_PERCENT_ANGLE_DEG
        dv.append(e_v)
        da.append(e_a)
        dlog.append(np.log(np.interp(a, grid, v_pred) / v))
        rel.append(100 * e_v[big] / v[big])
        rows.append({"L_mm": float(c.L_mm), "t_mm": float(c.t_mm),
                     "rmse_ul": float(np.sqrt(np.mean(e_v**2))),
                     "max_error_ul": float(np.max(np.abs(e_v))),
                     "max_error_percent": float(np.max(np.abs(rel[-1]), initial=0.0)),
                     "max_angle_error_deg": float(np.max(np.abs(e_a)))})
    if not rows:
        return {"n_designs": len(usable), "available": False,
                "note": "no held-out FE point inside the relation's angle range"}, 0.0, 1.0
    ev, ea, el, er = (np.concatenate(x) for x in (dv, da, dlog, rel))
    log_sd = float(np.sqrt(np.mean(el**2)))
    z = z_value(level)
    scale = max(1.0, float(np.quantile(np.abs(el), level)) / (z * log_sd)) if log_sd else 1.0
    report = {
        "n_designs": len(usable), "n_points": int(ev.size),
        "rmse_ul": float(np.sqrt(np.mean(ev**2))), "max_error_ul": float(np.max(np.abs(ev))),
        "rmse_percent": float(np.sqrt(np.mean(er**2))) if er.size else None,
        "max_error_percent": float(np.max(np.abs(er), initial=0.0)),
        "percent_from_angle_deg": MIN_PERCENT_ANGLE_DEG,
        "rmse_angle_deg": float(np.sqrt(np.mean(ea**2))),
        "max_angle_error_deg": float(np.max(np.abs(ea))),
        "rmse_log": log_sd, "level": level, "band_scale": scale, "per_design": rows,
        "note": "each design predicted from the family's other designs and compared with "
                "its FE curve at the FE's points (outside the others' (L, t) hull the "
                "linear tail extrapolates)"}
    return report, log_sd, scale


def check_volumes(v: np.ndarray) -> None:
    if (v < 0).any():
        raise InputError("volumes_ul", f"negative volume {v.min():g} ul", "volumes >= 0 ul")
