"""Prediction, one-design inverse, validity flags, refusals, and surrogate files.

Reference numbers: the paper preset's constants (surrogate/exponential/paper_tables.py) and the
closed-form model angle = a L (exp(p / tau) - 1), tau = a_t log10(b_t t).
"""

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import surrogate
from solver.design import Design
from solver.errors import InputError, NotFoundError
from solver.materials import get_material, make_material
from surrogate import (
    OutOfFamilyError,
    SurrogateFileError,
    fit_surrogate,
    load_surrogate,
    paper_surrogate,
    save_surrogate,
)
from surrogate.exponential.synthetic_curves import synthetic_curves
from surrogate.exponential.validity import past_fe
from surrogate.predictor import one_signed


@pytest.fixture(scope="module")
def fitted():
    curves = synthetic_curves(np.array([0.1, 700.0, 7.0, 0.05]), noise_deg=0.3, seed=11)
    curves += synthetic_curves(np.array([-0.05, 900.0, 6.0]), body="ecoflex_00_30",
                               membrane="pdms_1_15", noise_deg=0.2, seed=12)
    return fit_surrogate(curves, name="synthetic")


def test_public_names_are_complete() -> None:
    public = {n for n in dir(surrogate) if not n.startswith("_")} - {
        "annotations", "band_level", "dataset", "errors", "exponential", "json_plain",
        "json_repeats", "fit_provenance", "model_file",
        "calibration", "emulator", "predictor", "search", "hydraulics",
        "volume_control", "file_seal", "measured_cell"}
    assert public <= set(surrogate.__all__) | {"inverse_design"}
    for name in ("Surrogate", "Prediction", "InversePrediction", "load_surrogate",
                 "save_surrogate", "paper_surrogate", "fit_surrogate", "inverse_design",
                 "OutOfFamilyError"):
        assert name in surrogate.__all__


def test_prediction_is_the_closed_form_model() -> None:
    d = Design(L_mm=11.1, t_mm=0.75)
    p = np.array([0.0, 800.0, 1600.0])
    tau = 731.2 * np.log10(7.179 * 0.75)
    expected = 0.101 * 11.1 * np.expm1(p / tau)
    np.testing.assert_allclose(paper_surrogate().predict(d, p).angle_deg, expected, rtol=1e-12)


@settings(max_examples=60, deadline=None)
@given(L=st.floats(4.1, 15.1), t=st.floats(0.5, 1.0), angle=st.floats(0.01, 150.0),
       extended=st.booleans())
def test_inverse_round_trip(fitted, L: float, t: float, angle: float, extended: bool) -> None:
    s = fitted.with_form("extended" if extended else "exponential")
    d = Design(L_mm=L, t_mm=t)
    inv = s.inverse(d, angle)
    if np.isnan(inv.pressure_pa[0]):  # past the family's FE range: no number
        assert "past_fe_range" in inv.validity["flags"]
        assert np.isnan(inv.lower_pa[0]) and np.isnan(inv.upper_pa[0])
        return
    assert inv.pressure_pa[0] <= inv.validity["fe_limit_pa"] * (1 + 1e-9)
    back = s.predict(d, inv.pressure_pa).angle_deg
    np.testing.assert_allclose(back, angle, rtol=1e-9)
    assert inv.lower_pa[0] <= inv.pressure_pa[0] <= inv.upper_pa[0]


def test_inverse_round_trip_for_the_reversed_pair(fitted) -> None:
    d = Design(body_material=get_material("ecoflex_00_30"),
               membrane_material=get_material("pdms_1_15"))
    inv = fitted.inverse(d, [-5.0, -40.0])
    np.testing.assert_allclose(fitted.predict(d, inv.pressure_pa).angle_deg, [-5.0, -40.0])
    with pytest.raises(InputError, match="negative angles"):
        fitted.inverse(d, 10.0)


def test_inverse_band_matches_the_prediction_band_roughly() -> None:
    # Where the angle band is [lo, hi] at p, the inverse band at angle(p) spans about the
    # pressures where the upper/lower band curves reach that angle (within 5 %: the two
    # are different linearisations of the same uncertainty).
    s, d = paper_surrogate(), Design()
    inv = s.inverse(d, 45.0)
    grid = np.linspace(1000, 2500, 3001)
    pred = s.predict(d, grid)
    p_from_upper = grid[np.nanargmin(np.abs(pred.upper_deg - 45.0))]
    p_from_lower = grid[np.nanargmin(np.abs(pred.lower_deg - 45.0))]
    assert inv.lower_pa[0] == pytest.approx(p_from_upper, rel=0.05)
    assert inv.upper_pa[0] == pytest.approx(p_from_lower, rel=0.05)


def test_out_of_family_design_is_refused_with_the_precompute_to_run() -> None:
    d = Design(body_material=get_material("pdms_1_15"))
    with pytest.raises(OutOfFamilyError) as err:
        paper_surrogate().predict(d, [100.0])
    text = str(err.value)
    assert "pdms_1_15" in text and "balloon precompute" in text and "[[sweep]]" in text
    with pytest.raises(OutOfFamilyError):
        paper_surrogate().predict(Design(T_mm=2.0), [100.0])
    custom = make_material("pdms_1_10", [10.0], [2.0])  # same id, other parameters
    with pytest.raises(OutOfFamilyError, match="parameters differ"):
        paper_surrogate().inverse(Design(body_material=custom), 10.0)


def test_validity_flags() -> None:
    s = paper_surrogate()
    ok = s.predict(Design(), [500.0, 1500.0]).validity
    assert ok["in_domain"] and ok["flags"] == []
    v = s.predict(Design(L_mm=20.0, t_mm=0.3), [500.0, 3500.0]).validity
    assert not v["in_domain"]
    assert {"L_outside_fitted_range", "t_outside_fitted_range", "two_balloon_regime",
            "pressure_beyond_fe", "angle_beyond_fe"} <= set(v["flags"])
    assert len(v["messages"]) == len(v["flags"])
    assert "width_not_fitted" in s.predict(replace(Design(), W_mm=4.0), [1.0]).validity["flags"]


@pytest.mark.parametrize(("pressures", "field"), [([-1.0], "pressures_pa"),
                                                   ([float("nan")], "pressures_pa"),
                                                   ([], "pressures_pa"), ("abc", "pressures_pa")])
def test_bad_pressures_are_input_errors(pressures, field) -> None:
    with pytest.raises(InputError) as err:
        paper_surrogate().predict(Design(), pressures)
    assert err.value.field == field


def test_bad_level_and_tiny_thickness_are_input_errors() -> None:
    with pytest.raises(InputError, match="level"):
        paper_surrogate().predict(Design(), [1.0], level=1.5)
    with pytest.raises(InputError) as err:
        paper_surrogate().predict(Design(t_mm=0.1), [1.0])  # b_t t < 1: tau <= 0
    assert err.value.field == "t_mm"


def test_loaded_surrogate_equals_the_saved_one(fitted, tmp_path) -> None:
    path = save_surrogate(fitted, tmp_path / "s.json")
    loaded = load_surrogate(path)
    assert loaded == fitted
    d = Design(L_mm=9.0, t_mm=0.6)
    np.testing.assert_array_equal(loaded.predict(d, [700.0]).upper_deg,
                                  fitted.predict(d, [700.0]).upper_deg)
    paper_path = save_surrogate(paper_surrogate(), tmp_path / "paper.json")
    assert load_surrogate(paper_path) == paper_surrogate()


def test_newer_format_version_and_garbage_are_refused(fitted, tmp_path) -> None:
    path = save_surrogate(fitted, tmp_path / "s.json")
    data = json.loads(path.read_text())
    data["format_version"] += 1
    newer = tmp_path / "newer.json"
    newer.write_text(json.dumps(data))
    with pytest.raises(SurrogateFileError, match="newer"):
        load_surrogate(newer)
    (tmp_path / "bad.json").write_text("{not json")
    with pytest.raises(SurrogateFileError):
        load_surrogate(tmp_path / "bad.json")
    with pytest.raises(NotFoundError):
        load_surrogate(tmp_path / "missing.json")


def test_failed_save_keeps_the_old_file(fitted, tmp_path) -> None:
    path = save_surrogate(fitted, tmp_path / "s.json")
    before = path.read_bytes()
    broken = replace(fitted, provenance={"bad": float("nan")})
    save_surrogate(broken, path)  # NaN is stored as null: the write succeeds
    assert json.loads(path.read_text())["provenance"]["bad"] is None
    path.write_bytes(before)
    with pytest.raises(TypeError):
        save_surrogate(replace(fitted, name=object()), path)  # type: ignore[arg-type]
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["s.json"]


def test_provenance_records_the_source(fitted) -> None:
    prov = fitted.provenance
    assert prov["format_version"] == surrogate.FORMAT_VERSION == 3
    assert prov["record_keys"] and prov["created_utc"]
    assert "package_version" in prov and "git_commit" in prov
    fam = fitted.families[0]
    assert {"body_material", "membrane_material", "T_mm", "b_mm", "h_mm", "parameters",
            "domain"} <= set(fam)
    params = fitted.family_parameters(Design())
    for key in ("a_deg_per_mm", "a_t_pa", "b_t_per_mm", "tau_form", "covariance",
                "covariance_names", "standard_errors", "residual_sd_deg"):
        assert key in params
    assert params["covariance_names"][2] == "log10_b_t_per_mm"


DATA = Path(__file__).parent / "data"


def test_format_version_1_file_loads_with_the_same_answers(tmp_path) -> None:
    """tests/data/surrogate_v1.json is service/data/surrogate.json as shipped at commit
    5d1f4a8 (format version 1: covariances in b_t, 1/mm; report stripped), and
    surrogate_v1_expected.json holds that code's predictions and inverses from it. Read
    now, the covariance is converted to log10 b_t (delta method, exact to first order),
    so every band comes out the same; saved again it is a file of the current version, still
    without a pressure-volume relation (by volume: a 422 naming volumes_ul)."""
    old = load_surrogate(DATA / "surrogate_v1.json")
    cases = json.loads((DATA / "surrogate_v1_expected.json").read_text())["cases"]
    assert len(cases) == 18
    for c in cases:
        fam = next(f for f in old.family_fits if (f.body_material.id, f.membrane_material.id)
                   == (c["body"], c["membrane"]))
        d = Design(L_mm=c["L_mm"], t_mm=c["t_mm"], body_material=fam.body_material,
                   membrane_material=fam.membrane_material, T_mm=fam.T_mm, b_mm=fam.b_mm,
                   h_mm=fam.h_mm)
        pred = old.predict(d, c["pressure_pa"], form=c["form"])
        inv = old.inverse(d, c["inverse_angle_deg"], form=c["form"])
        # that code gave numbers past the family's FE range too; this one gives NaN there,
        # and no band across zero for a family that bends one way (one_signed)
        past = past_fe(fam.domain, c["pressure_pa"], c["angle_deg"])
        sign = 1.0 if np.nansum(c["angle_deg"]) >= 0 else -1.0
        c["angle_deg"], c["lower_deg"], c["upper_deg"] = (x.tolist() for x in one_signed(
            c["angle_deg"], c["lower_deg"], c["upper_deg"], sign))
        past_inv = past_fe(fam.domain, c["inverse_pressure_pa"], c["inverse_angle_deg"])
        for got, key, where in (
                (pred.angle_deg, "angle_deg", past), (pred.lower_deg, "lower_deg", past),
                (pred.upper_deg, "upper_deg", past),
                (inv.pressure_pa, "inverse_pressure_pa", past_inv),
                (inv.lower_pa, "inverse_lower_pa", past_inv),
                (inv.upper_pa, "inverse_upper_pa", past_inv)):
            np.testing.assert_allclose(got, np.where(where, np.nan, c[key]), rtol=1e-12,
                                       err_msg=key)
    std = next(f for f in old.family_fits if f.body_material.id == "pdms_1_10")
    # b_t = 7.7 /mm with sd 0.14 /mm in the v1 file -> log10 b_t sd 0.008
    assert std.parameters["exponential"].standard_errors["log10_b_t_per_mm"] == \
        pytest.approx(0.00803, rel=1e-3)
    again = load_surrogate(save_surrogate(old, tmp_path / "v3.json"))
    assert json.loads((tmp_path / "v3.json").read_text())["format_version"] == 3
    assert again == old
    assert all(f.volume is None for f in again.family_fits)
    with pytest.raises(InputError, match="volumes_ul: .*no pressure-volume relation.*refit"):
        again.predict_volume(d, [5.0])
