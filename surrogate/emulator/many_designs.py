"""Many designs at once, for the inverse design's search (``surrogate.search.design_search``).

The same answers as a query of one design at a time (the angle with its band at one
pressure, the pressure needed for one angle, the force; or, for a syringe pump's target,
the angle with its band at one injected volume and the volume needed for one angle), each
group's designs in one batch of GP predictions.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import TYPE_CHECKING

import numpy as np

from solver.design import Design
from solver.design_space import locate
from surrogate.band_level import z_value
from surrogate.emulator.curve_band import volume_band_ul
from surrogate.emulator.fe_range import fe_range, pressure_stop_angle
from surrogate.emulator.features import N_NODES
from surrogate.emulator.force_answer import force_backed
from surrogate.emulator.node_curves import ANGLES0, _with_origin, node_curves
from surrogate.emulator.vector_gp import MEANS_ONLY
from surrogate.emulator.volume_answer import at_volumes, volumes_at_angles
from surrogate.emulator.volume_curve import emulated_volume_ul
from surrogate.predictor import one_signed

if TYPE_CHECKING:
    from surrogate.emulator.emulator import Emulator


def _pair_batches(emulator: Emulator, designs: list[Design], z: float,
                  volume_band: bool = False, means_only: bool = False) -> Iterator[tuple]:
    """Per pair emulator: (pe, idx, points, u, mean, var, ends, plain, scales, curves,
    p_raw) of its designs (``idx``: their places in ``designs``), the variance as a
    single query reads it (exact at the variance nodes, spread; with ``volume_band`` at
    the volume nodes too; with ``means_only`` none: ``var`` and the band's curves NaN);
    ``curves``: p(theta) mean, lower and upper made monotone, ``p_raw`` the mean
    before."""
    points = [locate(d, reduced=True) for d in designs]
    coords = np.array([pt.coordinates() for pt in points])
    for key, idx in emulator._signed_groups(points, coords).items():
        if key not in emulator.pairs:
            continue
        pe = emulator.pairs[key]
        u = coords[idx]
        which = emulator.variance_nodes
        if volume_band:
            which = np.concatenate((np.arange(N_NODES)[which], np.arange(N_NODES, 2 * N_NODES)))
        if means_only:
            mean, _, ends, plain = pe.curve_nodes_many(u, variance_of=MEANS_ONLY)
            var = np.full_like(mean, np.nan)
        else:
            mean, var, ends, plain = (
                pe.curve_nodes_many(u, variance_of=which)
                if pe.curves.per_output else pe.curve_nodes_many(u))
            if pe.curves.per_output:
                var = np.array([emulator.spread_variance(row) for row in var])
        scales = pe.band_scales(pe.nearest_failed(u))
        y, sd = mean[:, :N_NODES], np.sqrt(var[:, :N_NODES]) * scales[:, :N_NODES]
        raw = node_curves(y, sd, z)
        curves = [np.maximum.accumulate(c, axis=1) for c in raw]
        yield pe, idx, points, u, mean, var, ends, plain, scales, curves, raw[0]


def _row_limit(pe: object, pt: object, u_row: np.ndarray, volume_row: np.ndarray,
               end_row: object, pm: np.ndarray) -> float:
    """The FE range's end (deg, unsigned) of one design of a batch: where its emulated
    curve ends, or the FE's pressure stop where that comes first."""
    limit = fe_range(pe, u_row, volume_row, pt.length_scale, end_row)[0]  # type: ignore
    at_stop = pressure_stop_angle(limit, ANGLES0, pm, pt.pressure_scale)  # type: ignore
    return limit if at_stop is None else at_stop


def evaluate_designs(emulator: Emulator, designs: list[Design], pressure_pa: float,
                     angle_deg: float | None, level: float = 0.95) -> dict[str, np.ndarray]:
    """Many designs at once (inverse design): |angle| (deg) with its band at
    ``pressure_pa``, and the pressure needed for |``angle_deg``| with its band (NaN
    past the FE's range), and which way each bends (``sign``: +1 away from the
    membrane, -1 towards it, 0 near a balance, where no answer is given); arrays in
    the order of ``designs``. Raises InputError for a design outside the box."""
    z = z_value(level)
    out = {k: np.full(len(designs), np.nan) for k in (
        "angle", "angle_lo", "angle_hi", "needed", "needed_lo", "needed_hi", "force",
        "force_lo", "force_hi")}
    out["sign"] = np.zeros(len(designs))
    for pe, idx, points, u, mean, var, ends, plain, scales, curves, _ in _pair_batches(
            emulator, designs, z):
        out["sign"][idx] = pe.sign
        fmean = fsd = None
        force_curves = curves
        if pe.force is not None:
            fmean, fvar = pe.force.predict_many(u)
            blocked_ends, blocked_means = pe.blocked_ends_pa(u)
            fsd = np.sqrt(fvar) * pe.force_sd_scales(blocked_means)
            if plain is not None:
                # the force model's angle and band: the complete-curve GPs' (as
                # curve_band)
                p_mean, p_var = plain
                if pe.curves.per_output:
                    p_var = np.array([emulator.spread_variance(np.concatenate((r, v)))
                                      for r, v in zip(p_var, var[:, N_NODES:],
                                                      strict=True)])
                p_sd = np.sqrt(p_var[:, :N_NODES]) * scales[:, :N_NODES]
                force_curves = [np.maximum.accumulate(c, axis=1)
                                for c in node_curves(p_mean, p_sd, z)]
        volumes = emulated_volume_ul(mean[:, N_NODES:])
        for row, i in enumerate(idx):
            pt = points[i]
            pm, pl, pu = (_with_origin(c[row]) for c in curves)
            limit = _row_limit(pe, pt, u[row], volumes[row], ends[row], pm)
            p_lim = float(np.interp(limit, ANGLES0, pm))
            q = pressure_pa / pt.pressure_scale
            if q <= p_lim:
                out["angle"][i] = np.interp(q, pm, ANGLES0)
                out["angle_lo"][i] = np.interp(q, pu, ANGLES0)
                out["angle_hi"][i] = np.interp(q, pl, ANGLES0)
            if angle_deg is not None and abs(angle_deg) <= limit:
                a = abs(angle_deg)
                s = pt.pressure_scale
                out["needed"][i] = np.interp(a, ANGLES0, pm) * s
                out["needed_lo"][i] = np.interp(a, ANGLES0, pl) * s
                out["needed_hi"][i] = np.interp(a, ANGLES0, pu) * s
            if fmean is not None and q <= pe.force_end_pa(p_lim, blocked_ends[row]):
                scale = pt.pressure_scale * pt.length_scale**2
                qa = np.array([q])
                fm, fl, fu = (_with_origin(c[row]) for c in force_curves)
                a, a_lo, a_hi = (np.interp(qa, c, ANGLES0) for c in (fm, fu, fl))
                vals = [scale * float(v[0]) for v in one_signed(*pe.force_reduced(
                    fmean[row], fsd[row], mean[row], qa, a, a_lo, a_hi, z), pe.sign)]
                lo_f, hi_f = vals[1], vals[2]
                if force_backed(vals[0], lo_f, hi_f):
                    out["force"][i] = vals[0]
                    out["force_lo"][i], out["force_hi"][i] = lo_f, hi_f
    return out


def evaluate_designs_by_volume(emulator: Emulator, designs: list[Design], volume_ul: float,
                               angle_deg: float, level: float = 0.95, band: bool = True
                               ) -> dict[str, np.ndarray]:
    """Many designs at once, for a syringe pump's target: |angle| (deg) with its band and
    the chamber pressure (Pa) at the injected volume ``volume_ul`` (ul, whole actuator),
    the volume needed for |``angle_deg``| with its band (ul) and the chamber pressure
    there (Pa), NaN past each design's FE range; ``sign`` as ``evaluate_designs``. The
    same readings as ``Emulator.predict_volume`` and ``Emulator.inverse``
    (``volume_answer``), for each pair's designs in one batch of GP predictions with the
    volume nodes' variance; ``band=False``: the means alone (the bands NaN), half the cost
    or less (the search's bisection steps)."""
    z = z_value(level)
    out = {k: np.full(len(designs), np.nan) for k in (
        "angle", "angle_lo", "angle_hi", "pressure", "needed", "needed_lo", "needed_hi",
        "needed_pressure")}
    out["sign"] = np.zeros(len(designs))
    a = abs(float(angle_deg))
    for pe, idx, points, u, mean, var, ends, _, scales, curves, p_raw in _pair_batches(
            emulator, designs, z, volume_band=True, means_only=not band):
        out["sign"][idx] = pe.sign
        v_sd = np.sqrt(var[:, N_NODES:]) * scales[:, N_NODES:]
        volumes = emulated_volume_ul(mean[:, N_NODES:])
        for row, i in enumerate(idx):
            pt = points[i]
            pm = _with_origin(curves[0][row])
            limit = _row_limit(pe, pt, u[row], volumes[row], ends[row], pm)
            curves_v = volume_band_ul(mean[row, N_NODES:], v_sd[row], z)
            ls3 = pt.length_scale**3
            read = at_volumes(np.array([volume_ul / ls3]), curves_v,
                              _with_origin(p_raw[row]), limit, band)
            out["angle"][i] = read.angle_deg[0]
            out["angle_lo"][i], out["angle_hi"][i] = read.lower_deg[0], read.upper_deg[0]
            out["pressure"][i] = read.pressure_red_pa[0] * pt.pressure_scale
            need = volumes_at_angles(np.array([a]), curves_v, limit)
            out["needed"][i], out["needed_lo"][i], out["needed_hi"][i] = (
                float(c[0]) * ls3 for c in need)
            if a <= limit:
                out["needed_pressure"][i] = float(np.interp(a, ANGLES0, pm)) * pt.pressure_scale
    return out
