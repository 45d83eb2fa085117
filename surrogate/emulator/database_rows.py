"""The curve database's records as the emulator's fit reads them: rows by material group.

Which records count: solved with the default FE (``SolverSettings()``: element, mesh,
control, tolerances, stop criteria) for free-tip curves, and with the blocked-tip
variant of the precompute grid's ``[[sample]]`` tables for force; designs inside the box
(``solver.design_space.locate``). Each record is reduced to the box's terms (pressure /
membrane stiffness scale, volume / length scale^3, force / (stiffness scale x length
scale^2)), so records of scaled copies of a design pool their information. A free-tip
curve that ends before LIMIT_ANGLE_DEG (the FE failed or stopped) is an early-ended one:
kept apart, it limits the range of the queries near it.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, fields, replace

import numpy as np

from solver.design_space import locate
from solver.errors import InputError
from solver.settings import SolverSettings
from surrogate.emulator.features import (
    FORCE_PRESSURE_NODES_PA,
    curve_features,
    force_features,
)
from surrogate.emulator.stretch_hazard import reached_hazard, stretch_nodes

LIMIT_ANGLE_DEG = 90.0            # the default FE's stop (SolverSettings.max_angle_deg)
MIN_DESIGNS = 10                  # the fewest designs a group's (a force model's) GPs take


@dataclass
class GroupRows:
    """One material group's free-tip rows, reduced to the box's terms: ``u`` the unit-cube
    coordinates of each complete curve, ``y`` its node outputs (log p / theta, log V /
    theta at the angle nodes), ``keys`` its record key; the early-ended curves apart
    (``failed_*``); pressures in Pa, volumes in ul, angles in deg."""

    u: list
    y: list
    keys: list
    curves: list          # (p_red, v_red, angle) per record, for cross-validation
    failed: list          # (u, end angle, reason)
    failed_end_volume: list  # the FE's last injected volume of each, reduced (ul)
    signs: list
    failed_signs: list
    failed_y: list        # node outputs of the early-ended curves (NaN past their end)
    failed_last_step: list  # the angle each one's last FE step started from (deg)
    by_volume: list       # (u, (v_red, p_red, signed angle)) of every curve (balance.py)
    stretch: list         # stretch_hazard.stretch_nodes of each complete curve (as u)
    hazard: list          # (stretch reached HAZARD_STRETCH, ended in a Newton failure)
                          # of every curve (stretch_hazard.py)


def default_free_settings() -> SolverSettings:
    """The settings of the free-tip curves the emulator is fitted to: the default FE's."""
    return SolverSettings()


def is_force_record(settings: SolverSettings) -> bool:
    """A blocked-tip curve of the default FE, solved to at least the emulator's force range
    (any ``max_pressure_pa`` >= the last force node: the grid's default or an older
    database's 6000 Pa)."""
    return (settings.tip == "blocked"
            and settings.max_pressure_pa >= FORCE_PRESSURE_NODES_PA[-1]
            and replace(settings, tip="free", max_pressure_pa=SolverSettings().max_pressure_pa)
            == default_free_settings())


def collect_rows(records: Iterable) -> tuple[dict, dict, dict]:
    """The records' rows by group: free-tip curves (``GroupRows``), blocked-tip force rows
    ((unit coordinates, F / p at the force nodes) per design) and blocked-tip ends
    ((unit coordinates, last pressure reduced Pa, stop reason) per design)."""
    free_settings = default_free_settings()
    free: dict[tuple[str, str], GroupRows] = {}
    force: dict = {}
    ends: dict = {}
    for rec in records:
        try:
            point = locate(rec.design, reduced=True)
        except InputError:
            continue
        c = rec.curve
        if rec.settings == free_settings:
            rows = free.setdefault(point.group,
                                  GroupRows(*([] for _ in fields(GroupRows))))
            f = curve_features(c.pressure_pa / point.pressure_scale,
                               c.volume_ul / point.length_scale**3, c.angle_deg)
            u = point.coordinates()
            rows.by_volume.append((u, (c.volume_ul / point.length_scale**3,
                                       c.pressure_pa / point.pressure_scale, c.angle_deg)))
            rows.hazard.append((reached_hazard(c.max_membrane_stretch),
                                c.status == "failed"))
            if f.end_angle_deg < LIMIT_ANGLE_DEG or not np.isfinite(f.log_p).all():
                rows.failed.append((u.tolist(), min(f.end_angle_deg, LIMIT_ANGLE_DEG),
                                    c.reason))
                rows.failed_end_volume.append(float(np.max(c.volume_ul))
                                              / point.length_scale**3)
                rows.failed_signs.append(f.sign)
                rows.failed_y.append(np.concatenate((f.log_p, f.log_v)))
                rows.failed_last_step.append(f.last_step_from_deg)
                continue
            rows.u.append(u)
            rows.y.append(np.concatenate((f.log_p, f.log_v)))
            rows.keys.append(rec.key)
            rows.curves.append((c.pressure_pa / point.pressure_scale,
                                c.volume_ul / point.length_scale**3, c.angle_deg))
            rows.signs.append(f.sign)
            rows.stretch.append(stretch_nodes(c.angle_deg, c.max_membrane_stretch))
        elif is_force_record(rec.settings):
            y = force_features(c.pressure_pa / point.pressure_scale,
                               c.force_mn / (point.pressure_scale * point.length_scale**2))
            if np.isfinite(y[0]):
                # one row per design: a design solved to two pressure limits (an older
                # database's 6000 Pa and today's) keeps the curve that reaches further
                rows_f = force.setdefault(point.group, {})
                key = tuple(np.round(point.coordinates(), 9))
                if key not in rows_f or np.isfinite(y).sum() > np.isfinite(rows_f[key]).sum():
                    rows_f[key] = y
                    ends.setdefault(point.group, {})[key] = (
                        float(c.pressure_pa[-1] / point.pressure_scale), c.reason)
    force = {g: ([np.array(k) for k in rows_f], list(rows_f.values()))
             for g, rows_f in force.items()}
    ends = {g: (np.array(list(e)), np.array([v[0] for v in e.values()]),
                [v[1] for v in e.values()]) for g, e in ends.items()}
    return free, force, ends
