"""The loop on measured data made the way a lab makes them, from the project's own FE
curves (tests/data/fe_calibration_curves.npz, made by tests/fe_calibration_curves.py):
syringe pump at 2.5 ul/s, angle and pressure read every 1 s, 3 specimens per design with
2 % specimen scatter, 0.7 deg reading noise, loading / hold / unloading, effects applied
the way the physics acts (a stiffer membrane is another FE solve; creep a Prony
retardation of the FE curve on a 1 ms grid; tests/calibration_lab.py). The baseline is
the shipped design-space emulator (service/data/emulator.json) at the data's nominal
designs; physical effects act through its inputs. The rows carry time_s and flow_ul_s,
so the loop reads angle and gauge pressure against the pump's injected volume
(docs/calibration.md, "Two observables"). It may be refitted with more FE data:
the tests judge the selected effect, the recovered size against its own uncertainty and
the error against the noise floor, never the emulator's exact numbers.

For every catalogued effect: the loop selects it alone, recovers its size within 3
standard errors, reaches a cross-validated error within 1.3 x the noise floor, and never
reports rmse_after above rmse_before (a camera gain on the six paper designs: on three
the data do not tell it from a softer body, and the loop must say so). Clean data (the
paper's designs, the reversed pair) select nothing; two effects outside the catalogue (a
rate-independent hysteresis loop and a contact saturation of the bend) are flagged with
nothing selected (both slow; the default suite checks that report on a camera late against
the pump, tests/test_calibration_lab_fresh.py). Where the emulator cannot back a case, the
case is xfail with the figures measured on it (none since 2026-12-04).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from calibration_lab import (
    FULL_LOOP,
    LOADING,
    LOOP,
    Lab,
    Truth,
    emulator,
    fe,
    measure,
    true_floor,
)

from solver.errors import InputError
from surrogate.calibration import observations_from_rows, run_calibration
from surrogate.calibration._noise import noise_floor

PAPER_DESIGNS = tuple((L, t) for L in (4.1, 7.1, 11.1) for t in (0.5, 0.75))
BASES = fe.PERTURBED_BASES


_REPORTS: dict[str, dict] = {}


def calibrate(lab: Lab, truth: Truth = Truth()) -> dict:
    """The loop's report on the lab's data (one run per case in a session: the strict test
    of a case and its honesty test share it)."""
    key = repr((lab, truth))
    if key not in _REPORTS:
        _REPORTS[key] = run_calibration(measure(lab, truth), emulator()).report
    report = _REPORTS[key]
    assert report["rmse_after_deg"] <= report["rmse_before_deg"] + 1e-12
    return report


def assert_honest(report: dict, effect: str, truth: dict[str, float]) -> None:
    """What a case the emulator cannot decide must still do: select the truth or nothing
    (never another effect alone), or, when it selects another, name the truth among the
    explanations the data cannot tell apart, with its size right and what to measure."""
    selected = report["selected_effects"]
    if selected in ([], [effect]):
        return
    alike = {tuple(a["effects"]): a for a in report["indistinguishable"]}
    assert (effect,) in alike, (selected, list(alike), _why(report))
    for name, value in truth.items():
        p = alike[(effect,)]["params"][name]
        assert abs(p["value"] - value) <= 3.0 * p["sd"], (name, p, value)
    from surrogate.calibration import EFFECTS

    assert EFFECTS[effect].measure_directly in report["interpretation"]
    assert "do not tell" in report["interpretation"]


def assert_recovers(report: dict, effect: str, truth: dict[str, float]) -> None:
    assert report["selected_effects"] == [effect], _why(report)
    for name, value in truth.items():
        p = report["fitted"]["effects"][name]
        assert abs(p["value"] - value) <= 3.0 * p["sd"], (name, p, value)
        null = _null(effect, name)
        if math.isfinite(null):  # a size, not a shape: the recovery must say something
            assert p["sd"] < 0.5 * abs(value - null)
    assert report["rmse_after_deg"] <= 1.3 * report["noise_floor_deg"]
    assert not report["residual_structured_after"]


def _null(effect: str, name: str) -> float:
    from surrogate.calibration import EFFECTS

    return next(p.null for p in EFFECTS[effect].parameters if p.name == name)


def _why(report: dict) -> list:
    return [(c["effect"], c["rmse_cv_deg"], c["why_not"]) for c in report["candidates"]]


@pytest.mark.parametrize("designs", [BASES, pytest.param(PAPER_DESIGNS,
                                                          marks=pytest.mark.slow)],
                         ids=["three-designs", "all-six"])
def test_clean_fe_data_on_the_papers_designs_select_nothing(designs):
    r = calibrate(Lab(designs=designs, protocol=FULL_LOOP))
    assert r["selected_effects"] == [], _why(r)
    assert not r["residual_structured_after"]
    assert r["rmse_before_deg"] <= 1.3 * r["noise_floor_deg"]
    assert r["baseline"]["open_parameters"] == []  # a design-space model leaves nothing open


def test_the_reversed_pair_bends_negative_and_selects_nothing():
    lab = Lab(designs=((7.1, 0.5), (11.1, 0.5)), materials=fe.REVERSED, protocol=FULL_LOOP)
    rows = measure(lab)
    assert min(r["angle_deg"] for r in rows) < -20.0
    r = run_calibration(rows, emulator()).report
    assert r["selected_effects"] == [], _why(r)
    assert not r["residual_structured_after"]


MEASUREMENT_CASES = [
    # by volume (time_s and flow_ul_s: docs/calibration.md, "Two observables") a gauge
    # offset moves only the pressure against volume: told from a stiffer body, which
    # moves both (on the angle against pressure alone body_stiffness 1.29 tied with it)
    ("pressure_offset", Truth(p0_pa=120.0), {"p0_pa": 120.0}, LOADING, (2.5,)),
    ("hydraulic_resistance", Truth(R_pa_per_ul_s=60.0), {"R_pa_per_ul_s": 60.0}, LOOP,
     (2.5,)),
    ("angle_offset", Truth(offset_deg=2.0), {"offset_deg": 2.0}, LOADING, (2.5,)),
    ("camera_gain", Truth(k_angle=1.08), {"k_angle": 1.08}, LOOP, (2.5,)),
    # by volume a gauge gain leaves the angle against volume alone: told from the
    # membrane_stiffness + chamber_length pair that tied with it against pressure alone
    ("pressure_gain", Truth(k_pressure=1.06), {"k_pressure": 1.06}, LOOP, (2.5,)),
    ("viscoelastic_creep", Truth(g_retarded=0.25, tau_retardation_s=2.0),
     {"g_retarded": 0.25, "tau_retardation_s": 2.0}, LOOP, (1.25, 2.5)),
]


MEASUREMENT_IDS = ["pressure_offset", "hydraulic_resistance", "angle_offset", "camera_gain",
                   "pressure_gain", "viscoelastic_creep"]


# On the three bases a camera gain is told from a softer body only by the gauge's level at
# a volume (a body 16 % softer raises the angle at a volume much as a gain of 1.08 does and
# lowers the gauge by ~1.5 %), which the specimens' mean (2 % scatter, 9 specimens: s.e.
# 0.7 %) and the emulator's pressure scale (1 %) leave open: measured 2026-12-04 over lab
# seeds 1-5, camera_gain selected at 2, 4 and 5; body_stiffness 0.842 +/- 0.037 at seed 1
# (this case's), a stiffer membrane with a gauge gain at 3, each naming camera_gain among
# the explanations the data do not tell apart. So the three bases test the honest answer
# (below), and the six paper designs, where the two differ in the angle's shape, test the
# recovery (selected at every seed 1-5, 1.068-1.097 for 1.08, each within 1.5 sd).
STRICT_MEASUREMENT_IDS = [i for i in MEASUREMENT_IDS if i != "camera_gain"]


@pytest.mark.parametrize("effect, truth, values, protocol, flows",
                         [c for c in MEASUREMENT_CASES if c[0] != "camera_gain"],
                         ids=STRICT_MEASUREMENT_IDS)
def test_each_measurement_and_time_effect_is_found_and_sized(effect, truth, values, protocol,
                                                             flows):
    lab = Lab(designs=BASES, protocol=protocol, flows_ul_s=flows)
    assert_recovers(calibrate(lab, truth), effect, values)


@pytest.mark.slow
def test_a_camera_gain_is_found_where_the_designs_tell_it_from_a_softer_body():
    lab = Lab(designs=PAPER_DESIGNS, protocol=LOOP)
    assert_recovers(calibrate(lab, Truth(k_angle=1.08)), "camera_gain", {"k_angle": 1.08})


@pytest.mark.parametrize("effect, truth, values, protocol, flows", MEASUREMENT_CASES,
                         ids=MEASUREMENT_IDS)
def test_each_measurement_effect_is_found_or_named_among_its_equivalents(effect, truth, values,
                                                                         protocol, flows):
    lab = Lab(designs=BASES, protocol=protocol, flows_ul_s=flows)
    assert_honest(calibrate(lab, truth), effect, values)


# Each physical change is an FE solve of its own at each of the designs (all three bases
# where the change stays inside the emulator's box: t 0.45 mm is outside it).
PHYSICAL_CASES = [
    ("membrane_stiffness", Truth(membrane_mu_scale=1.3), {"membrane_mu_scale": 1.3}, BASES,
     None),
    # by volume 0.743 +/- 0.008, CV 1.18 x the floor (against pressure alone the
    # emulator's own error at L 4.1 mm kept it at 1.7-1.9 x the floor)
    ("membrane_stiffness", Truth(membrane_mu_scale=0.75), {"membrane_mu_scale": 0.75}, BASES,
     None),
    # by volume the thinner membrane (-0.052 +/- 0.008 mm) and the longer chamber
    # (0.55 +/- 0.07 mm) are selected alone: against pressure alone they tied with a
    # pressure gain or were not backed (on the 368-record emulator)
    ("membrane_thickness", Truth(dt_mm=-0.05), {"dt_mm": -0.05}, ((7.1, 0.75),), None),
    ("chamber_length", Truth(dL_mm=0.5), {"dL_mm": 0.5}, BASES, None),
    # a stiffer body: xfail until 2026-12-04 (the emulator's own error at L 4.1 mm / body
    # x 1.5 kept its CV at 1.6 x the floor); on the balanced 2275-record emulator
    # 1.485 +/- 0.043, CV 1.14 x the floor (benchmarks/calibration_cases.py)
    ("body_stiffness", Truth(body_mu_scale=1.5), {"body_mu_scale": 1.5}, BASES, None),
]

PHYSICAL_IDS = [f"{c[0]}-{list(c[2].values())[0]:g}" for c in PHYSICAL_CASES]


@pytest.mark.parametrize("effect, truth, values, designs", [
    pytest.param(*c[:4], marks=([pytest.mark.xfail(reason=c[4], strict=False)] if c[4]
                                else []) + ([pytest.mark.slow] if i else []))
    for i, c in enumerate(PHYSICAL_CASES)], ids=PHYSICAL_IDS)
def test_each_physical_effect_acts_through_the_fe_and_is_found(effect, truth, values, designs):
    assert_recovers(calibrate(Lab(designs=designs, protocol=FULL_LOOP), truth), effect,
                    values)


@pytest.mark.parametrize("effect, truth, values, designs", [
    pytest.param(*c[:4], marks=[pytest.mark.slow] if i else [])
    for i, c in enumerate(PHYSICAL_CASES)], ids=PHYSICAL_IDS)
def test_each_physical_effect_is_found_or_nothing_else_is_claimed(effect, truth, values,
                                                                  designs):
    assert_honest(calibrate(Lab(designs=designs, protocol=FULL_LOOP), truth), effect, values)


def test_a_design_outside_the_emulators_box_is_refused_naming_the_field_and_the_nearest():
    rows = [dict(r, t_mm=0.45) for r in measure(Lab(designs=((11.1, 0.5),), protocol=LOADING))]
    with pytest.raises(InputError) as err:
        run_calibration(rows, emulator())
    text = str(err.value)
    assert err.value.field == "model"
    assert "t_mm" in text and "outside the emulator's box" in text and "nearest" in text


def test_a_thinner_membrane_past_the_box_edge_is_said_so_not_fitted_past_it():
    # Lab data of 50 um thinner membranes on nominal t = 0.5 mm designs (FE solves at
    # t = 0.45 mm): the emulator's box ends at t = 0.5 mm, so the calibration fits the
    # thickness only where the emulator answers and says where that ends.
    r = calibrate(Lab(designs=((11.1, 0.5), (4.1, 0.5)), protocol=FULL_LOOP), Truth(dt_mm=-0.05))
    reach = r["baseline_reach"]["membrane_thickness"]
    assert reach["lower"] == 0.0 and reach["upper"] > 0.1
    assert any("t_mm: 0.5 <= t_mm" in w for w in reach["limits"])
    assert "membrane_thickness" not in r["selected_effects"]
    assert "chamber_length" in r["baseline_reach"]  # L 4.1 mm: dL >= -0.1 mm


# the contact saturation is slow since 2026-12-07 (the default suite 624 s, over its 10
# minutes), the hysteresis loop since 2026-12-08 (24 s, the loop's heaviest default case;
# the default suite 535-645 s): the default suite keeps the outside-catalogue path, with
# every assertion below, in tests/test_calibration_lab_fresh.py (a camera late against
# the pump, 14 s)
@pytest.mark.slow
@pytest.mark.parametrize("truth", [Truth(hysteresis_deg=5.0), Truth(contact_deg=25.0)],
                         ids=["hysteresis-loop", "contact-saturation"])
def test_effects_outside_the_catalogue_are_flagged_not_explained(truth):
    r = calibrate(Lab(designs=BASES, protocol=FULL_LOOP), truth)
    assert r["selected_effects"] == [], _why(r)
    assert r["residual_structured_after"]
    assert r["unexplained_rms_deg"] > 0.5
    assert r["unexplained_where"] and "outside the catalogue" in r["interpretation"]
    near = r["closest_rejected"]  # the nearest catalogued set is named with why it fails
    assert near is None or (near["why_not"] and "+".join(near["effects"]).split("+")[0]
                            in r["interpretation"])


def test_creep_from_loading_at_one_flow_rate_is_not_identifiable_and_says_what_to_measure():
    r = calibrate(Lab(designs=BASES, protocol=LOADING), Truth())
    entry = next(c for c in r["not_identifiable"] if c["effect"] == "viscoelastic_creep")
    assert "one flow rate" in entry["reason"] and "hold" in entry["measure"]
    assert "viscoelastic_creep" not in r["selected_effects"]


def test_noise_floor_follows_the_loading_history_with_creep_holds_and_unloading():
    # Creep makes loading and unloading differ and the angle move during holds: fitted
    # against pressure alone that would count as scatter. The floor must find the true
    # scatter (reading noise + specimen scatter, at the reading's pressure in the same
    # segment; tests/calibration_lab.py true_floor) however strong the creep.
    for g in (0.0, 0.3):
        ratios = []
        for seed in (1, 2, 3):
            lab = Lab(designs=BASES, protocol=LOOP, flows_ul_s=(1.25, 2.5), seed=seed)
            truth = Truth(g_retarded=g, tau_retardation_s=2.0)
            floor = noise_floor(observations_from_rows(measure(lab, truth)))
            assert floor.source == "replicates"
            ratios.append(floor.rms_deg / true_floor(lab, truth))
        assert 0.85 < float(np.mean(ratios)) < 1.15, (g, ratios)
    lab = Lab(designs=BASES, protocol=LOOP, specimen_sd=0.0)
    clean = noise_floor(observations_from_rows(measure(lab, Truth(g_retarded=0.3))))
    assert clean.rms_deg < 1.3 * 0.7  # reading noise only: the loop and the creep are not noise
    assert math.isfinite(clean.rms_deg)


def test_the_injected_volume_and_the_pressure_floor_follow_the_pump():
    # The pump's volume from time, flow and direction (the lab's own V(t)), and the gauge
    # pressure's replicate scatter at the same volume against the generator's realised
    # scatter (2 % specimen scatter of the chamber pressure, 3 Pa reading noise); the
    # inlet's R Q, shared by replicates, is not scatter.
    from surrogate.calibration._noise import volume_floor

    lab = Lab(designs=BASES, protocol=LOOP, flows_ul_s=(1.25, 2.5))
    obs = observations_from_rows(measure(lab, Truth(R_pa_per_ul_s=60.0)))
    t, q = obs.time_s, obs.flow_ul_s
    expected = np.where(t <= 6, q * t, np.where(t <= 10, 6 * q, q * (16 - t)))
    np.testing.assert_allclose(obs.volume_ul, expected, atol=1e-9)
    ratios = []
    for seed in (1, 2, 3):
        lab_s = Lab(designs=BASES, protocol=LOOP, seed=seed)
        rows = measure(lab_s, Truth(R_pa_per_ul_s=60.0))
        clean_r = measure(Lab(**{**lab_s.__dict__, "specimen_sd": 0.0, "noise_deg": 0.0,
                                 "specimens": 1, "extra": {"exact": True}}),
                          Truth(R_pa_per_ul_s=60.0))
        mean = {(r["L_mm"], r["t_mm"], r["time_s"]): r["pressure_pa"] for r in clean_r}
        true = np.sqrt(np.mean([(r["pressure_pa"] - mean[(r["L_mm"], r["t_mm"],
                                                          r["time_s"])]) ** 2 for r in rows]))
        obs_s = observations_from_rows(rows)
        ratios.append(volume_floor(obs_s, obs_s.pressure_pa).rms_deg / true)
    assert 0.85 < float(np.mean(ratios)) < 1.15, ratios
