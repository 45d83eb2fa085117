"""The range by injected volume ends where nearby database curves' FE ended at a Newton
failure (``PairEmulator.end_volume_cap_ul``; emulator file format 15), and at the FE's
volume stop itself, not at the fine angle after it.

Reference numbers: the FE curves of service/data/curves.h5 (their last injected volume);
the emulators are fitted from them here or read from the shipped file.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from service.settings import DATA_DIR
from solver.design import Design
from solver.design_space import locate
from solver.settings import SolverSettings

# a PDMS-bodied database design whose default-FE curve failed (Newton) at 76.8 deg and
# 97.5 ul; fitted with its 24 nearest complete curves, its emulated volume reached 113 ul
# by the end of its range, and 102 ul (1.05x) was answered at 75.9 deg
NEWTON_FAILED = "01413e1a"
# a database design at the Ecoflex-on-PDMS 1:15 stiffness balance (the balance model
# answers it), whose FE failed at 34.6 deg and 332 ul; the balance model answered to 480 ul
AT_THE_BALANCE = "9c144205"


def _record(records, prefix: str):
    return next(r for r in records if r.key.startswith(prefix))


@pytest.fixture(scope="module")
def small_fit(shipped_records):
    """An emulator fitted on NEWTON_FAILED and the 24 complete default-FE curves of its
    group nearest to it (about 5 s)."""
    from surrogate.emulator.build import fit_emulator

    target = _record(shipped_records, NEWTON_FAILED)
    u0 = locate(target.design, reduced=True).coordinates()
    group = [r for r in shipped_records if r.settings == SolverSettings()
             and r.design.body_material.id.startswith("pdms")
             and abs(r.curve.angle_deg[-1]) >= 90.0]
    d = [np.linalg.norm(locate(r.design, reduced=True).coordinates() - u0) for r in group]
    return fit_emulator([group[i] for i in np.argsort(d)[:24]] + [target]), target


def test_the_angle_at_a_volume_is_read_as_a_query_by_volume_reads_it():
    from surrogate.emulator.emulator import (
        FINE_ANGLES_DEG,
        angle_at_volume_deg,
        ended_at_newton_failure,
    )

    v = 2.0 * FINE_ANGLES_DEG           # a V(theta) of 2 ul/deg
    assert angle_at_volume_deg(v, 101.0) == pytest.approx(50.5, abs=1e-12)
    assert angle_at_volume_deg(v, 180.0) == pytest.approx(90.0, abs=1e-12)
    assert angle_at_volume_deg(v, 180.1) is None
    assert ended_at_newton_failure("step at p = 3094.4 Pa, angle = 60.7 deg did not "
                                   "converge after cut-backs")
    for stop in ("reached max_volume_ul = 500.0", "reached max_angle_deg = 90.0",
                 "reached max_pressure_pa = 20000.0"):
        assert not ended_at_newton_failure(stop)


def test_past_a_newton_failed_database_curves_end_volume_no_angle_is_given(small_fit,
                                                                           tmp_path):
    """The fit stores each early-ended curve's last FE injected volume (reduced), the file
    keeps it, and by volume the design's range ends there: past it no number, flagged
    past_fe_range with the volume in words; the answer by pressure has the same range."""
    from surrogate.emulator.file import load_emulator, save_emulator

    fitted, target = small_fit
    end_ul = float(target.curve.volume_ul[-1])
    pe = fitted.pairs["pdms/ecoflex_00_30+"]
    u0 = locate(target.design, reduced=True).coordinates()
    own = [bool(np.allclose(u, u0)) for u, _, _ in pe.failed].index(True)
    assert len(pe.failed_end_volume_ul) == len(pe.failed)
    assert pe.failed_end_volume_ul[own] == pytest.approx(end_ul, rel=1e-12)
    e = load_emulator(save_emulator(fitted, tmp_path / "e.json"))
    np.testing.assert_array_equal(e.pairs[pe.pair].failed_end_volume_ul,
                                  pe.failed_end_volume_ul)
    r = e.predict_volume(target.design, [0.9 * end_ul, 1.01 * end_ul, 1.05 * end_ul])
    assert np.isfinite(r.angle_deg[0]) and np.isnan(r.angle_deg[1:]).all()
    assert np.isnan(r.pressure_pa[1:]).all()
    assert "past_fe_range" in r.validity["flags"]
    assert r.validity["fe_limit_volume_ul"] == pytest.approx(end_ul, rel=1e-9)
    assert f"ended at about {end_ul:.0f} ul" in r.validity["fe_stop_reason"]
    assert f"ended at about {end_ul:.0f} ul" in r.validity["messages"][0]
    assert "Newton failure" in r.validity["messages"][0]
    by_pressure = e.predict(target.design, [100.0])
    assert by_pressure.validity["fe_limit_volume_ul"] == pytest.approx(end_ul, rel=1e-9)
    assert by_pressure.validity["fe_limit_angle_deg"] == r.validity["fe_limit_angle_deg"]
    # a copy half the size holds 1/8 the volume at each angle: its range ends at 1/8
    d, k = target.design, 0.5
    small = Design(L_mm=k * d.L_mm, t_mm=k * d.t_mm, T_mm=k * d.T_mm, b_mm=k * d.b_mm,
                   h_mm=k * d.h_mm, W_mm=k * d.W_mm,
                   body_length_mm=k * d.resolved_body_length_mm,
                   body_material=d.body_material, membrane_material=d.membrane_material)
    r2 = e.predict_volume(small, [0.9 * k**3 * end_ul, 1.01 * k**3 * end_ul])
    assert np.isfinite(r2.angle_deg[0]) and np.isnan(r2.angle_deg[1])
    assert r2.validity["fe_limit_volume_ul"] == pytest.approx(k**3 * end_ul, rel=1e-9)
    assert f"ended at about {k**3 * end_ul:.0f} ul" in r2.validity["fe_stop_reason"]


def test_a_file_without_end_volumes_reads_as_before_and_damaged_ones_are_refused(small_fit):
    from surrogate.emulator.file import emulator_from_dict, emulator_to_dict
    from surrogate.errors import SurrogateFileError
    from surrogate.file_seal import KEY

    fitted, target = small_fit
    end_ul = float(target.curve.volume_ul[-1])
    d = emulator_to_dict(fitted)
    d.pop(KEY, None)
    stored = d["pairs"][0]["failed_end_volume_ul"]
    # format 14 had no such field: no cap, the range by volume as it was
    d["format_version"] = 14
    del d["pairs"][0]["failed_end_volume_ul"]
    old = emulator_from_dict(d, "old.json")
    assert all(pe.failed_end_volume_ul is None for pe in old.pairs.values())
    unchanged = replace(fitted, pairs={k: replace(pe, failed_end_volume_ul=None)
                                       for k, pe in fitted.pairs.items()})
    asks = [0.9 * end_ul, 1.05 * end_ul]
    np.testing.assert_array_equal(old.predict_volume(target.design, asks).angle_deg,
                                  unchanged.predict_volume(target.design, asks).angle_deg)
    d["format_version"] = 15
    for bad in (stored + [1.0], [-1.0] * len(stored), [float("nan")] * len(stored), "x"):
        d["pairs"][0]["failed_end_volume_ul"] = bad
        with pytest.raises(SurrogateFileError, match="failed_end_volume_ul"):
            emulator_from_dict(d, "other.json")


def _without_end_volumes(e):
    """The emulator as a file without end volumes (format 14) reads."""
    return replace(e, pairs={k: replace(pe, failed_end_volume_ul=None)
                             for k, pe in e.pairs.items()})


def test_the_balance_model_stops_where_its_newton_failed_database_curve_ended(
        shipped_records):
    """At the stiffness balance the range ended at the balance model's volume stop (480
    ul) where this database design's FE failed at 332 ul: with the group's end volumes
    (as a refit stores them, attached here to the shipped file's emulator without its
    own) it ends at
    332 ul and says why."""
    from surrogate.emulator import load_emulator
    from surrogate.emulator.database_rows import collect_rows

    shipped = _without_end_volumes(load_emulator(DATA_DIR / "emulator.json"))
    target = _record(shipped_records, AT_THE_BALANCE)
    group = locate(target.design, reduced=True).group
    rows = collect_rows(r for r in shipped_records
                    if locate(r.design, reduced=True).group == group)[0][group]
    volumes = np.array(rows.failed_end_volume, float)
    pairs = dict(shipped.pairs)
    for key in (group + "+", group + "-"):
        if key in pairs:
            pe = pairs[key]
            assert [tuple(np.round(u, 9)) for u, _, _ in pe.failed] == [
                tuple(np.round(np.asarray(u), 9)) for u, _, _ in rows.failed]
            pairs[key] = replace(pe, failed_end_volume_ul=volumes)
    e = replace(shipped, pairs=pairs)
    end_ul = float(target.curve.volume_ul[-1])
    asks = [0.9 * end_ul, 1.05 * end_ul]
    before = shipped.predict_volume(target.design, asks)
    assert "near_stiffness_balance" in before.validity["flags"]
    assert np.isfinite(before.angle_deg).all()              # the former range: 480 ul
    r = e.predict_volume(target.design, asks)
    assert "near_stiffness_balance" in r.validity["flags"]
    assert np.isfinite(r.angle_deg[0]) and np.isnan(r.angle_deg[1])
    assert "past_fe_range" in r.validity["flags"]
    assert r.validity["fe_limit_volume_ul"] == pytest.approx(end_ul, rel=1e-6)
    assert f"ended at about {end_ul:.0f} ul" in r.validity["messages"][0]


def test_the_range_by_volume_ends_at_the_fes_volume_stop_itself(shipped_records):
    """Database design da1e0959 (Ecoflex on Ecoflex; its FE failed at 50.0 deg and 499.8
    ul): its emulated volume passes the FE's 500 ul stop steeply, 7 % between two fine
    angles 0.25 deg apart. The range was read at the first fine angle past the stop, and
    by volume answered to 534.6 ul, where the FE stops at 500; it now ends at 500 ul."""
    from surrogate.emulator import load_emulator

    # the end volumes left out: da1e0959's own (499.8 ul) would end it there first
    e = _without_end_volumes(load_emulator(DATA_DIR / "emulator.json"))
    design = _record(shipped_records, "da1e0959").design
    r = e.predict_volume(design, [495.0, 510.0])
    assert np.isfinite(r.angle_deg[0]) and np.isnan(r.angle_deg[1])
    assert "past_fe_range" in r.validity["flags"]
    assert r.validity["fe_limit_volume_ul"] == pytest.approx(500.0, rel=1e-9)
    assert "max_volume_ul" in r.validity["fe_stop_reason"]
