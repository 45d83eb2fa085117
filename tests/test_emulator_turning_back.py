"""Near the stiffness balance an FE curve can turn back: its |angle| peaks and falls as the
membrane's balloon grows (surrogate/emulator/balance.py, "Curves that turn back"). The
emulator's answer there is flagged and its band is the turning curves' own calibration,
checked on FE curves of three random box designs it never saw (tests/data, source named
in the file)."""

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from solver import Design
from solver.design_space import locate, scaled_material
from solver.settings import SolverSettings
from solver.store import CurveStore
from surrogate.emulator import load_emulator
from surrogate.emulator.balance import (
    TURN_BACK_DEG,
    VOLUME_NODES_UL,
    balance_model_from_dict,
    loo_band_scales,
    turn_back_deg,
    turns_back,
)
from surrogate.emulator.balance_answer import TURN_FLAG

EMULATOR = "service/data/emulator.json"
RANDOM_DESIGNS = "service/data/band-calibration.h5"
CURVES = Path(__file__).parent / "data" / "fe_curves_turning_back.json"


@pytest.fixture(scope="module")
def emulator():
    return load_emulator(EMULATOR)


def _design(c: dict) -> Design:
    return Design(body_material=scaled_material(c["body"]["preset"],
                                                c["body"]["stiffness_scale"]),
                  membrane_material=scaled_material(c["membrane"]["preset"],
                                                    c["membrane"]["stiffness_scale"]),
                  **c["geometry_mm"]).validated()


FE = json.loads(CURVES.read_text())["curves"]


def test_the_stored_fe_curves_turn_back():
    """The data: each FE curve's |angle| falls by 7-14 deg after its peak."""
    for c in FE:
        a = np.abs(np.array(c["angle_deg"]))
        assert a.max() - a[-1] > 5.0
        assert c["volume_ul"][-1] == pytest.approx(500.0, abs=1.0)   # the volume stop


def test_a_fall_after_the_peak():
    assert turn_back_deg(np.array([0.0, -3.0, -8.0, -6.5])) == pytest.approx(1.5)
    assert turn_back_deg(np.array([0.0, 2.0, 5.0, 5.0])) == 0.0
    assert turns_back(np.array([0.0, 5.0, 5.0 - 1.01 * TURN_BACK_DEG]))
    assert not turns_back(np.array([0.0, 5.0, 5.0 - 0.99 * TURN_BACK_DEG]))


@pytest.mark.parametrize("k", range(len(FE)))
def test_a_turning_answer_is_flagged_with_the_turning_band(emulator, k):
    """Each design's answer by volume and by pressure says its curve turns back, and the
    band is the turning curves' (wider than the plain one by their ratio)."""
    c = FE[k]
    d = _design(c)
    v = np.array(c["volume_ul"][1:])
    by_volume = emulator.predict_volume(d, v)
    assert TURN_FLAG in by_volume.validity["flags"]
    assert "turns back" in " ".join(by_volume.validity["messages"])
    by_pressure = emulator.predict(d, np.array(c["pressure_pa"][1:]))
    assert TURN_FLAG in by_pressure.validity["flags"]
    model = emulator.balance_models[locate(d, reduced=True).group]
    assert model.turn_scales is not None
    plain = replace(model, turn_scales=None)
    nodes = model.nodes(locate(d, reduced=True).coordinates())
    wide = model.by_volume(nodes, v / locate(d, reduced=True).length_scale**3, 1.96)
    narrow = plain.by_volume(nodes, v / locate(d, reduced=True).length_scale**3, 1.96)
    ratio = (wide[2] - wide[1]) / (narrow[2] - narrow[1])
    assert np.allclose(ratio[np.isfinite(ratio)],
                       model.turn_scales[0] / model.band_scale_volume)
    assert model.turn_scales[0] > model.band_scale_volume


def test_the_turning_band_covers_the_fe_curve_the_plain_band_missed(emulator):
    """The Ecoflex/Ecoflex design whose turning curve the emulator reads worst (its peak
    -10 deg against the FE's -26): the plain band covered 0.29 of the FE points by
    volume, the turning band covers them."""
    c = FE[0]
    d = _design(c)
    v, a = np.array(c["volume_ul"][1:]), np.array(c["angle_deg"][1:])
    ans = emulator.predict_volume(d, v)
    ok = np.isfinite(np.asarray(ans.angle_deg, float))
    inside = (a[ok] >= np.asarray(ans.lower_deg)[ok]) & (a[ok] <= np.asarray(ans.upper_deg)[ok])
    assert ok.mean() > 0.9
    assert inside.mean() >= 0.9


def test_the_inverse_is_flagged_too(emulator):
    c = FE[0]
    inv = emulator.inverse(_design(c), np.array([-5.0, -8.0]))
    assert TURN_FLAG in inv.validity["flags"]


def test_the_flag_marks_the_least_reliable_balance_answers(emulator):
    """The balance-answered random designs of the band calibration set (none of their FE
    curves falls by more than 0.3 deg): the three whose emulated curve turns back are
    the worst answered (per-curve RMSE 1.6-11 deg against a median of 0.5), and the
    turning band covers at least 0.85 of each one's FE points (the plain band covered
    0.57 of the worst)."""
    flagged, plain = [], []
    with CurveStore(RANDOM_DESIGNS) as db:
        for rec in db.records():
            cv = rec.curve
            if rec.settings != SolverSettings() or cv is None or len(cv.pressure_pa) < 3:
                continue
            v, a = np.asarray(cv.volume_ul[1:]), np.asarray(cv.angle_deg[1:])
            keep = np.abs(a) <= 90.0
            ans = emulator.predict_volume(rec.design, v[keep])
            if "near_stiffness_balance" not in ans.validity["flags"]:
                continue
            m = np.asarray(ans.angle_deg, float)
            ok = np.isfinite(m)
            rmse = float(np.sqrt(np.mean((m[ok] - a[keep][ok]) ** 2)))
            cover = float(np.mean((a[keep][ok] >= np.asarray(ans.lower_deg)[ok])
                                  & (a[keep][ok] <= np.asarray(ans.upper_deg)[ok])))
            (flagged if TURN_FLAG in ans.validity["flags"] else plain).append((rmse, cover))
    assert len(plain) >= 20 and 1 <= len(flagged) <= 0.1 * len(plain)
    assert min(r for r, _ in flagged) > 2 * np.median([r for r, _ in plain])
    assert min(c for _, c in flagged) >= 0.85


def test_the_turning_multipliers_are_stored_and_checked():
    model_dict = json.loads(Path(EMULATOR).read_text())["balance_models"]
    for group, d in model_dict.items():
        assert len(d["turn_band_scales"]) == 2, group
        model = balance_model_from_dict(d)
        assert model.turn_scales == tuple(d["turn_band_scales"])
        for bad in ([0.5, 2.0], [1.5], "wide"):
            with pytest.raises(ValueError, match="turn_band_scales|band scales"):
                balance_model_from_dict({**d, "turn_band_scales": bad})
        old = {k: v for k, v in d.items() if k != "turn_band_scales"}
        assert balance_model_from_dict(old).turn_scales is None      # files before 18


def test_fewer_turning_curves_keep_the_plain_multipliers():
    """loo_band_scales on a model whose curves do not turn: no turning pair."""
    rng = np.random.default_rng(0)
    from surrogate.emulator.balance import N_VOLUME_NODES, fit_balance_model
    u = rng.random((40, 2))
    curves = []
    for x in u:
        v = np.concatenate(([0.0], np.geomspace(0.5, 520.0, 40)))
        a = (5 + 10 * x[0]) * np.log1p(v / 20.0)          # rising: never turns back
        p = 1000.0 * (1 + x[1]) * np.log1p(v)
        curves.append((v, p, a))
    model, report = fit_balance_model(u, curves)
    assert model is not None and model.turn_scales is None
    assert report["turning_curves"] == 0
    scales, turn, _ = loo_band_scales(model.gp, curves)
    assert turn is None and scales == (model.band_scale_volume, model.band_scale_pressure)
    assert len(VOLUME_NODES_UL) == N_VOLUME_NODES
