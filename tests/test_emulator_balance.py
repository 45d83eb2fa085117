"""The emulator at the Ecoflex/Ecoflex stiffness balance: the signed angle by injected volume
(surrogate/emulator/balance.py), checked on FE curves of random box designs it never saw."""


import numpy as np
import pytest

from solver.design_space import locate
from solver.errors import InputError
from solver.settings import SolverSettings
from solver.store import CurveStore
from surrogate.emulator import load_emulator
from surrogate.emulator.balance import VOLUME_NODES_UL, on_nodes
from surrogate.emulator.file import emulator_from_dict
from surrogate.errors import SurrogateFileError
from surrogate.file_seal import KEY

EMULATOR = "service/data/emulator.json"
# FE curves of 384 random box designs (benchmarks/heldout_designs.py, seed 2027), none in
# the database; the band calibration widened the per-direction bands only
RANDOM_DESIGNS = "service/data/band-calibration.h5"
FLAG = "near_stiffness_balance"


@pytest.fixture(scope="module")
def emulator():
    return load_emulator(EMULATOR)


@pytest.fixture(scope="module")
def balance_curves(emulator):
    """The default-FE free-tip curves of the random designs the emulator answers by its
    balance model (before 2026-12-05 each was refused: 13 of the 384)."""
    out = []
    with CurveStore(RANDOM_DESIGNS) as db:
        for rec in db.records():
            c = rec.curve
            if rec.settings != SolverSettings() or c is None or len(c.pressure_pa) < 3:
                continue
            if FLAG in emulator.predict(rec.design, c.pressure_pa[1:2]).validity["flags"]:
                out.append((rec.design, c))
    return out


def _undecided(emulator, design) -> bool:
    """At the balance itself: the sign model gives no direction."""
    try:
        emulator._sign(locate(design, reduced=True))
    except InputError:
        return True
    return False


def test_a_curve_on_the_volume_nodes():
    """Read on its rising-volume part; a curve that stops short of the last node has none."""
    v = np.array([0.0, 1.0, 10.0, 100.0, 490.0, 485.0, 600.0])
    p = np.array([0.0, 100.0, 400.0, 900.0, 1500.0, 1400.0, 1800.0])
    a = np.array([0.0, -0.1, -0.5, -2.0, -6.0, -5.0, -9.0])
    y = on_nodes(v, p, a)
    n = len(VOLUME_NODES_UL)
    assert y.shape == (2 * n,)
    assert y[n - 1] == pytest.approx(np.interp(480.0, v[:5], a[:5]))
    assert y[2 * n - 1] == pytest.approx(np.interp(480.0, v[1:5], np.log(p[1:5])))
    assert on_nodes(v[:4], p[:4], a[:4]) is None


def test_designs_at_the_balance_are_answered_within_the_target_and_their_band(
        emulator, balance_curves):
    """Every random design the sign model cannot give a direction to (13, refused until
    2026-12-05) and those whose FE curve the balance model says ends at the volume stop
    are answered by it, both ways round, by pressure and by injected volume. Measured on
    the refit of 2026-12-05: 35 of the 384 designs (13 undecided), 23 within RMSE <= 1 and
    max <= 3 deg by pressure and 22 by volume, the band covering 0.971 / 0.965 of their
    points. The checks leave room for a refit, not for a model that misses most curves or
    states a band it does not keep."""
    assert len(balance_curves) >= 25
    assert sum(_undecided(emulator, d) for d, _ in balance_curves) >= 10
    ends = [c.angle_deg[-1] for _, c in balance_curves]
    assert min(ends) < -10 and max(ends) > 10          # both directions
    for axis in ("pressure", "volume"):
        hits = inside = points = 0
        for design, c in balance_curves:
            x = c.pressure_pa if axis == "pressure" else c.volume_ul
            keep = x > 0
            ask = emulator.predict if axis == "pressure" else emulator.predict_volume
            r = ask(design, x[keep])
            assert FLAG in r.validity["flags"]
            # no force model at the balance itself; elsewhere the direction's force model
            assert (r.force_mn is None) == _undecided(emulator, design)
            ok = np.isfinite(r.angle_deg)
            assert ok.mean() > 0.9
            fe = c.angle_deg[keep][ok]
            err = r.angle_deg[ok] - fe
            hits += bool(np.sqrt(np.mean(err**2)) <= 1.0 and np.abs(err).max() <= 3.0)
            assert (r.lower_deg[ok] <= r.angle_deg[ok] - 0.05 + 1e-9).all()
            assert (r.angle_deg[ok] + 0.05 <= r.upper_deg[ok] + 1e-9).all()
            if "curve_turns_back" in r.validity["flags"]:
                continue    # their own band's calibration: test_emulator_turning_back.py
            inside += int(((r.lower_deg[ok] <= fe) & (fe <= r.upper_deg[ok])).sum())
            points += int(ok.sum())
        assert hits >= len(balance_curves) // 2, axis
        # 0.993 / 0.990 (pressure / volume) since the fiftieth session, the curves that
        # turn back apart (their band: test_emulator_turning_back.py); one pair of
        # multipliers over every curve had covered these 0.995 / 0.992, and the total
        # 0.981 / 0.978 only because the worst turning curve was covered 0.6
        # (benchmarks/RESULTS.md)
        assert 0.85 <= inside / points <= 0.995, axis


def test_the_answer_stops_at_the_volume_stop_and_says_so(emulator, balance_curves):
    """Past the last volume node (480 ul, short of the FE's 500 ul stop) no angle; the
    pressure axis stops at the pressure there."""
    design, _ = balance_curves[0]
    r = emulator.predict_volume(design, [100.0, 470.0, 495.0, 700.0])
    assert np.isfinite(r.angle_deg[:2]).all() and np.isnan(r.angle_deg[2:]).all()
    assert np.isnan(r.pressure_pa[2:]).all()
    assert r.validity["flags"][:2] == ["past_fe_range", FLAG]
    assert r.validity["fe_limit_volume_ul"] == pytest.approx(VOLUME_NODES_UL[-1])
    limit_pa = r.validity["fe_limit_pa"]
    rp = emulator.predict(design, [0.5 * limit_pa, 0.99 * limit_pa, 1.01 * limit_pa])
    assert np.isfinite(rp.angle_deg[:2]).all() and np.isnan(rp.angle_deg[2])
    assert "past_fe_range" in rp.validity["flags"]
    # the two axes agree: the angle at a pressure is the angle at the volume it gives
    back = emulator.predict_volume(design, rp.volume_ul[:2])
    np.testing.assert_allclose(back.angle_deg, rp.angle_deg[:2], atol=1e-6)
    np.testing.assert_allclose(back.pressure_pa, rp.pressure_pa[:2], rtol=1e-6)


def test_the_inverse_reads_the_balance_model_and_round_trips(emulator, balance_curves):
    """Where the balance model answers, the inverse reads it too: for half of each FE
    curve's largest angle, the injected volume and chamber pressure the answers by volume
    and by pressure give that angle back, flagged. Until 2026-12-06 the per-direction GPs
    answered instead: 13 of these 35 designs refused (no direction), the others' volumes
    read back up to 12.7 deg off."""
    answered = 0
    for design, c in balance_curves:
        k = int(np.argmax(np.abs(c.angle_deg)))
        target = 0.5 * c.angle_deg[k]
        inv = emulator.inverse(design, [target])
        assert FLAG in inv.validity["flags"]
        if not np.isfinite(inv.volume_ul[0]):
            assert "past_fe_range" in inv.validity["flags"]
            continue
        answered += 1
        by_v = emulator.predict_volume(design, inv.volume_ul)
        by_p = emulator.predict(design, inv.pressure_pa)
        np.testing.assert_allclose(by_v.angle_deg, [target], atol=0.01)
        np.testing.assert_allclose(by_p.angle_deg, [target], atol=0.05)
    assert answered >= 0.9 * len(balance_curves)


@pytest.mark.parametrize(("body", "membrane"), [
    ("ecoflex_00_30*2", "pdms_1_15*0.5"),        # bends towards the membrane, past -90
    ("ecoflex_00_30*0.5", "ecoflex_00_30*2"),
])
def test_no_angle_past_the_fes_angle_stop_near_the_balance(emulator, body, membrane):
    """The FE stops at 90 deg or at the volume stop, whichever comes first: the balance
    model answered a stiff-bodied design 122 and 135 deg at 200 and 480 ul with its band
    cut to [90, 90] (an audit of the thirty-fifth session)."""
    from solver.design import Design
    from solver.design_space import scaled_material

    def material(text: str):
        preset, scale = text.split("*")
        return scaled_material(preset, float(scale))

    design = Design(L_mm=18, t_mm=0.5, T_mm=2, b_mm=2.4, h_mm=0.229415,
                    body_material=material(body), membrane_material=material(membrane))
    volumes = np.linspace(5.0, 480.0, 96)
    answer = emulator.predict_volume(design, volumes)
    angle = np.asarray(answer.angle_deg, float)
    given = np.isfinite(angle)
    assert np.all(np.abs(angle[given]) <= 90.0 + 1e-9)
    for side in (answer.lower_deg, answer.upper_deg):
        assert np.all(np.abs(np.asarray(side, float)[given]) <= 90.0 + 1e-9)
    if not given.all():
        assert "past_fe_range" in answer.validity["flags"]
        assert abs(answer.validity["fe_limit_angle_deg"]) <= 90.0 + 1e-9
    by_pressure = emulator.predict(design, np.linspace(100.0, 20000.0, 60))
    p_angle = np.asarray(by_pressure.angle_deg, float)
    assert np.all(np.abs(p_angle[np.isfinite(p_angle)]) <= 90.0 + 1e-9)


def test_a_scaled_copy_gives_the_same_angles_at_the_scaled_volumes(emulator, balance_curves):
    """The invariances: every length x k scales the volumes by k^3, both layers' mu x s
    the pressures by s; the angles stay (the FE's volume stop, 500 ul, does not scale)."""
    from dataclasses import replace

    from solver.design_space import scaled_material

    design, _ = balance_curves[1]
    r = emulator.predict_volume(design, [20.0, 100.0])
    k = 1.5
    s_b = design.body_material.mu_kpa[0] / scaled_material("ecoflex_00_30", 1.0).mu_kpa[0]
    s_m = design.membrane_material.mu_kpa[0] / scaled_material("ecoflex_00_30", 1.0).mu_kpa[0]
    f = 1.2 if max(s_b, s_m) <= 2.0 / 1.2 else 0.85       # both scales stay in 0.5-2
    big = replace(design, L_mm=k * design.L_mm, t_mm=k * design.t_mm, T_mm=k * design.T_mm,
                  b_mm=k * design.b_mm, h_mm=k * design.h_mm, W_mm=k * design.W_mm,
                  body_length_mm=None, chamber_offset_mm=None,
                  body_material=scaled_material("ecoflex_00_30", f * s_b),
                  membrane_material=scaled_material("ecoflex_00_30", f * s_m))
    rb = emulator.predict_volume(big, [20.0 * k**3, 100.0 * k**3])  # below its 480 ul
    assert FLAG in rb.validity["flags"]
    np.testing.assert_allclose(rb.angle_deg, r.angle_deg, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(rb.pressure_pa, f * r.pressure_pa, rtol=1e-6)


def test_over_http_the_answer_is_a_200_with_its_flag_and_no_force_at_the_balance(
        shipped_client, emulator, balance_curves):
    design = next(d for d, _ in balance_curves if _undecided(emulator, d))
    body = {"design": design.as_dict(), "pressures_pa": [200.0, 600.0]}
    r = shipped_client.post("/v1/predict", json=body)
    assert r.status_code == 200, r.text
    out = r.json()
    assert FLAG in out["validity"]["flags"]
    assert all(a is not None for a in out["angle_deg"])
    assert out["force_mn"] is None


def _loaded(d: dict):
    """The file loader's validation of ``d``, in memory (writing and reading 30 MB per
    variant cost ~10 s each), without its checksum."""
    d.pop(KEY, None)
    return emulator_from_dict(d, "e.json")


def test_the_file_keeps_the_model_reads_format_11_and_refuses_damage(
        shipped_emulator_saved_and_loaded, emulator, balance_curves):
    from surrogate.emulator.file import emulator_to_dict

    design = next(d for d, _ in balance_curves if _undecided(emulator, d))
    shipped, back = shipped_emulator_saved_and_loaded
    assert shipped is emulator
    np.testing.assert_array_equal(back.predict_volume(design, [50.0]).angle_deg,
                                  emulator.predict_volume(design, [50.0]).angle_deg)
    d = emulator_to_dict(emulator)
    models = d["balance_models"]
    group = next(iter(models))
    for field, bad in (("volume_nodes_ul", [1.0, 2.0]), ("band_scale_volume", 0.5),
                       ("band_scale_pressure", "wide"), ("gp", {"center": [0.0]})):
        good = models[group][field]
        models[group][field] = bad
        with pytest.raises(SurrogateFileError, match="balance|damaged"):
            _loaded(d)
        models[group][field] = good
    models["pdms/ecoflex_00_30"] = models[group]
    with pytest.raises(SurrogateFileError, match="no sign model"):
        _loaded(d)
    d["format_version"] = 11
    d.pop("balance_models")
    old = _loaded(d)
    with pytest.raises(InputError, match="balance"):        # refused, as before
        old.predict(design, [100.0])
