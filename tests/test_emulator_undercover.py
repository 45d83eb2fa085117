"""A design whose group covered too little of random designs' FE points is flagged.

The bands' second calibration (``random_calibration``) measures, per group, axis and side
(near or far from curves that ended early), how much of the FE points of random designs
the calibrated band covers. Where that is below UNDERCOVER_LEVEL on enough points the
answer says so (``band_undercovers_random_designs``) instead of passing a too-narrow band
off as 95 %. The fit calibrated on 192 random designs flagged Ecoflex on Ecoflex bending
towards the membrane (0.19 of 78 far points, 0.88 of 165 near, by pressure) and the
reversed pair near curves that ended early (0.88 of 89 points by pressure;
benchmarks/RESULTS.md, eighteenth session); the shipped fit, on 384, flags nothing.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from service.settings import DATA_DIR
from solver.design import Design
from solver.design_space import locate
from surrogate.emulator import load_emulator
from surrogate.emulator.emulator import (
    NEAR_FAILED_RADIUS,
    UNDERCOVER_LEVEL,
    UNDERCOVER_MIN_POINTS,
)
from surrogate.emulator.random_calibration import GROUP_MIN_POINTS, PointFactors, group_coverage

FLAG = "band_undercovers_random_designs"


@pytest.fixture(scope="module")
def emulator():
    return load_emulator(DATA_DIR / "emulator.json")


def _with_cell(e, pair: str, axis: str, side: str, cell: dict):
    report = dict(e.report)
    cal = dict(report["random_design_calibration"])
    cov = {p: {a: dict(c) for a, c in v.items()}
           for p, v in (cal.get("group_coverage_after") or {}).items()}
    cov.setdefault(pair, {}).setdefault(axis, {})[side] = cell
    cal["group_coverage_after"] = cov
    report["random_design_calibration"] = cal
    return replace(e, report=report)


def test_group_coverage_counts_points_and_curves():
    pf = PointFactors(angle_deg=np.array([5.0, 10, 20, 30, 40, 50]),
                      factor=np.array([0.5, 2.0, 0.1, 0.9, 1.5, 0.2]),
                      near=np.array([False, False, False, True, True, True]),
                      axis=np.array(["pressure"] * 3 + ["volume"] * 3),
                      pair=np.array(["g+"] * 6), curve=np.array([0, 0, 1, 2, 2, 3]))
    g = group_coverage(pf)["g+"]
    assert g["pressure"]["far"] == {"coverage": pytest.approx(2 / 3), "points": 3, "curves": 2}
    assert g["pressure"]["near"] == {"coverage": None, "points": 0, "curves": 0}
    assert g["volume"]["near"] == {"coverage": pytest.approx(2 / 3), "points": 3, "curves": 2}


def test_the_flag_follows_the_groups_measured_coverage(emulator):
    d = Design().validated()
    point = locate(d, reduced=True)
    pe, cb = emulator.curve_band(point, 1.96, volume_band=False)
    side = "near" if cb.failed_distance < NEAR_FAILED_RADIUS else "far"
    p = np.linspace(100, 1500, 8)
    assert FLAG not in emulator.predict(d, p).validity["flags"]     # shipped: covered
    bad = _with_cell(emulator, pe.pair, "pressure", side,
                     {"coverage": 0.5, "points": 200, "curves": 7})
    r = bad.predict(d, p)
    assert FLAG in r.validity["flags"]
    message = r.validity["messages"][r.validity["flags"].index(FLAG)]
    assert "50 %" in message and "7 curves" in message and "POST /v1/solve" in message
    # the volume axis reads its own cell
    assert FLAG not in bad.predict_volume(d, [5.0, 10.0]).validity["flags"]
    # too few points: no claim either way
    thin = _with_cell(emulator, pe.pair, "pressure", side,
                      {"coverage": 0.5, "points": UNDERCOVER_MIN_POINTS - 1, "curves": 1})
    assert FLAG not in thin.predict(d, p).validity["flags"]


def test_the_shipped_fit_covers_every_group_and_widens_ecoflex_bending_towards_it(emulator):
    """Calibrated on 384 random designs, every group and side with enough points covers at
    least UNDERCOVER_LEVEL of them, so nothing is flagged; Ecoflex on Ecoflex bending
    towards the membrane (flagged on the fit of 192 designs: 0.19 of 78 far points) got
    its own factors instead, and its band is wide where its answers are poor."""
    cal = emulator.report["random_design_calibration"]
    assert cal["curves"] >= 384
    cells = cal["group_coverage_after"]
    low = {(pair, axis, side): c for pair, axes in cells.items()
           for axis, sides in axes.items() for side, c in sides.items()
           if c["coverage"] is not None and c["points"] >= UNDERCOVER_MIN_POINTS
           and c["coverage"] < UNDERCOVER_LEVEL}
    # a cell with its own factors (GROUP_MIN_POINTS points) is covered; one that took the
    # pooled factors may not be, and its designs are flagged. Since the volume GPs
    # (2026-12-05, twenty-sixth session): the reversed pair near early-ended curves by
    # volume, 107 points of 3 curves, 0.81 (1.0 before; benchmarks/RESULTS.md)
    assert all(c["points"] < GROUP_MIN_POINTS for c in low.values()), low
    assert len(low) <= 1, low
    towards = cal["group_factors"]["ecoflex_00_30/ecoflex_00_30-"]
    # its own factors widen both axes (by volume 5-8x until 2026-12-05; since, the
    # variance carries the early-ended curves' spread for its many designs that end
    # early, and the factor left is 1.5-1.7; by pressure > 2 until the balance model took
    # the designs that end at the volume stop out of the curve GPs' answers, 1.1-2.1 since;
    # by volume none since the volume GPs read the pressure curve's shape: its GP bands
    # cover its random designs as they are, 1.0 in every bin, twenty-sixth session; by
    # pressure at 60-90 deg 1.0 since the thirty-sixth: with the range no longer cut at
    # ~84 deg those bins hold points enough of their own, and cover them unwidened; at
    # 0-20 deg 1.0-1.02 since the designs on the box's faces, forty-fourth session)
    assert min(towards["pressure"]["far"][2:4]) > 1.05 and min(towards["pressure"]["far"]) >= 1.0
    assert min(towards["volume"]["far"]) >= 1.0
    # a soft body on Ecoflex bends towards the membrane: not flagged, a wide band
    d = Design(body_material="ecoflex_00_30*0.5", membrane_material="ecoflex_00_30*2",
               L_mm=12.0).validated()
    p = np.linspace(100, 1500, 8)
    r = emulator.predict(d, p)
    assert r.angle_deg[np.isfinite(r.angle_deg)].max() < 0
    assert FLAG not in r.validity["flags"]
    assert FLAG not in emulator.predict_volume(d, [2.0, 5.0]).validity["flags"]
    standard = emulator.predict(Design(), p)
    relative = [(x.upper_deg - x.lower_deg) / np.abs(x.angle_deg) for x in (r, standard)]
    # (> 2x until 2026-12-05, when the designs of this group that end at the volume stop,
    # its worst answered, went to the balance model and out of this calibration: 1.7x)
    assert np.nanmin(relative[0][2:]) > 1.5 * np.nanmax(relative[1][2:])
