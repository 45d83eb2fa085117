"""The shipped design-space emulator against the shipped FE database and over HTTP.

Reference numbers: the FE curves of service/data/curves.h5 (made by
`balloon precompute grids/emulator.toml`, the command is in the file) and the FE's own
invariances; nothing here is computed by the emulator's fitting forms.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from service.settings import DATA_DIR
from solver.design import Design
from solver.design_space import OutOfBoxError, locate, scaled_material
from solver.errors import InputError
from solver.materials import MATERIALS
from solver.store import CurveStore
from surrogate.emulator import load_emulator
from surrogate.predictor import Predictor

EMULATOR = DATA_DIR / "emulator.json"
DB = DATA_DIR / "curves.h5"


@pytest.fixture(scope="module")
def emulator():
    return load_emulator(EMULATOR)


def test_the_emulator_is_a_predictor(emulator):
    assert isinstance(emulator, Predictor)


def test_database_designs_are_reproduced_within_0_2_deg(emulator, shipped_records):
    """Every database curve the emulator interpolates, at its own FE pressures (up to
    89 deg). Measured on the 1115-record database: 654 of 657 within 0.2 deg; the other
    three 0.23-0.92 deg, between angle nodes where the FE curve bends over (0.92 deg at
    -88.9 deg, where p rises 0.5 % over the last 3 deg), or at -0.1 deg (a coarse-mesh
    initial bend the other way, docs/verification.md). The issue's 0.2 deg holds for 99 %
    of the designs, not all (benchmarks/RESULTS.md)."""
    keys = sorted({k for pe in emulator.pairs.values() for k in pe.keys})
    worst = []
    answered = total = 0
    by_key = {r.key: r for r in shipped_records}
    for key in keys:
        c = by_key[key].curve
        inside = (np.abs(c.angle_deg) <= 89.0) & (c.pressure_pa > 0)
        pred = emulator.predict(by_key[key].design, c.pressure_pa[inside])
        ok = np.isfinite(pred.angle_deg)   # a nearby early-ended curve may cap the range
        answered, total = answered + int(ok.sum()), total + int(ok.size)
        worst.append(float(np.max(np.abs(pred.angle_deg[ok] - c.angle_deg[inside][ok]))))
    worst = np.array(worst)
    assert answered >= 0.99 * total, (answered, total)
    assert len(worst) >= 400
    assert np.mean(worst <= 0.2) >= 0.99, np.sort(worst)[-10:]
    assert worst.max() <= 1.0, worst.max()


def _early_ended_database_curves(records):
    """The default-FE free-tip database curves that ended before 90 deg (the volume stop,
    a Newton failure, the pressure stop) and are in the emulator's box
    (``benchmarks/early_ended_database_designs.py`` asks all of them)."""
    from solver.settings import SolverSettings

    out = []
    for rec in records:
        c = rec.curve
        if (rec.settings != SolverSettings() or c is None or len(c.angle_deg) < 3
                or np.abs(c.angle_deg).max() >= 90.0):
            continue
        try:
            locate(rec.design, reduced=True)
        except InputError:
            continue
        out.append(rec)
    return out


def test_early_ended_database_designs_are_reproduced(emulator, shipped_records):
    """A database design whose FE curve ended early (a quarter of the database) asked at
    every FE point of its own curve, by pressure and by volume: the share of them whose
    answered points are within 0.2 deg RMS. Every third such design (188 of 565), for
    time. Before the thirty-eighth session the emulator blended in the early-ended curves
    only by the design's emulated end, dropped every curve's last reached node, shifted
    the volume outputs by the wrong reference and let the balance model (fitted on the
    volume-stop curves) answer at Newton failures: 0.59 by pressure and 0.63 by volume
    (all 558 in the box), 0.597 and 0.618 of these 186; after it 0.753 and 0.823
    (benchmarks/RESULTS.md, thirty-eighth session)."""
    curves = _early_ended_database_curves(shipped_records)[::3]
    assert len(curves) >= 150
    within = {"pressure": 0, "volume": 0}
    for rec in curves:
        c = rec.curve
        for axis, x, ask in (("pressure", c.pressure_pa, emulator.predict),
                             ("volume", c.volume_ul, emulator.predict_volume)):
            keep = x > 0
            try:
                a = np.asarray(ask(rec.design, x[keep]).angle_deg, float)
            except InputError:
                continue
            ok = np.isfinite(a)
            if ok.any() and np.sqrt(np.mean((a[ok] - c.angle_deg[keep][ok]) ** 2)) <= 0.2:
                within[axis] += 1
    share = {k: v / len(curves) for k, v in within.items()}
    assert share["pressure"] >= 0.72 and share["volume"] >= 0.78, share


def test_angle_is_monotone_in_pressure_and_signed(emulator):
    p = np.linspace(0, 4000, 200)
    standard = emulator.predict(Design(), p)
    a = standard.angle_deg[np.isfinite(standard.angle_deg)]
    assert (np.diff(a) >= -1e-9).all() and a[-1] > 45
    reversed_pair = emulator.predict(Design(body_material=MATERIALS["ecoflex_00_30"],
                                            membrane_material=MATERIALS["pdms_1_15"]), p)
    r = reversed_pair.angle_deg[np.isfinite(reversed_pair.angle_deg)]
    assert (np.diff(r) <= 1e-9).all() and r[-1] < -45     # bends towards the membrane
    finite = np.isfinite(standard.angle_deg)
    assert (standard.lower_deg[finite] <= standard.angle_deg[finite] + 1e-9).all()
    assert (standard.upper_deg[finite] >= standard.angle_deg[finite] - 1e-9).all()


def test_both_moduli_scaled_scale_the_pressure_axis(emulator):
    s = 1.6
    base = emulator.predict(Design(L_mm=9.0, t_mm=0.7), [400, 900, 1400])
    stiff = Design(L_mm=9.0, t_mm=0.7, body_material=scaled_material("pdms_1_10", s),
                   membrane_material=scaled_material("ecoflex_00_30", s))
    scaled = emulator.predict(stiff, [400 * s, 900 * s, 1400 * s])
    np.testing.assert_allclose(scaled.angle_deg, base.angle_deg, atol=1e-9)


def test_a_scaled_inline_material_is_recognised_and_other_inline_ones_are_refused():
    mu = [1.3 * m for m in MATERIALS["ecoflex_00_30"].mu_kpa]
    ok = Design(membrane_material=MATERIALS["ecoflex_00_30"].__class__(
        "my_eco", tuple(mu), MATERIALS["ecoflex_00_30"].alpha))
    assert locate(ok).pressure_scale == pytest.approx(1.3)
    other = MATERIALS["ecoflex_00_30"].__class__("odd", (1.0,), (2.0,))
    with pytest.raises(OutOfBoxError) as info:
        locate(Design(membrane_material=other))
    assert info.value.field == "membrane_material"


def test_past_the_fe_range_no_number_is_given(shipped_client):
    r = shipped_client.post("/v1/predict", json={"pressures_pa": [1000, 2500, 5000, 20000]})
    assert r.status_code == 200, r.text
    body = r.json()
    assert body["model"] == "emulator"
    assert body["angle_deg"][0] is not None and 0 < body["angle_deg"][0] < 90
    assert body["angle_deg"][1:] == [None, None, None]
    assert body["upper_deg"][1:] == [None, None, None]
    v = body["validity"]
    # in_domain is about the design (in the box); the points past the range are flagged
    assert "past_fe_range" in v["flags"] and v["in_domain"] is True
    assert 1000 < v["fe_limit_pa"] < 2500 and v["fe_limit_angle_deg"] == 90
    assert "FE" in " ".join(v["messages"])


def test_outside_the_box_is_refused_with_the_nearest_design(shipped_client):
    r = shipped_client.post("/v1/predict", json={"design": {"L_mm": 3.0}, "pressures_pa": [500]})
    assert r.status_code == 422, r.text
    body = r.json()
    assert r.headers["content-type"] == "application/problem+json"
    assert [e["loc"] for e in body["errors"]] == [["body", "design", "L_mm"]]
    assert body["errors"][0]["field"] == "design.L_mm"   # where the request holds it
    text = r.text
    assert "4 <= L_mm <= 18" in text
    assert "nearest" in text and "/v1/solve" in text


def test_the_default_design_at_another_width_is_answered_as_its_scaled_copy(emulator):
    """The default body length (12 mm, or L + 2 mm) and centred chamber scale with W, so a
    design given at W = 6 mm with every length doubled is the W = 3 mm design's scaled
    copy (the same angle(p), 8x the volume), not a refusal; a body length that breaks the
    rule is refused naming the field and the length the rule gives, and the nearest
    design offered is at the user's own width."""
    small = Design(L_mm=9.0, t_mm=0.7, T_mm=1.3, b_mm=1.9, h_mm=0.2)
    big = Design(L_mm=18.0, t_mm=1.4, T_mm=2.6, b_mm=3.8, h_mm=0.4, W_mm=6.0)
    p = np.array([200.0, 800.0, 1500.0])
    a, b = emulator.predict(small, p), emulator.predict(big, p)
    np.testing.assert_allclose(b.angle_deg, a.angle_deg, rtol=1e-12)
    np.testing.assert_allclose(b.volume_ul, 8 * a.volume_ul, rtol=1e-9)
    from dataclasses import replace

    with pytest.raises(OutOfBoxError) as info:
        emulator.predict(replace(big, body_length_mm=20.0), p)
    assert info.value.field == "body_length_mm" and "24" in info.value.allowed
    assert info.value.nearest.W_mm == 6.0 and info.value.nearest.L_mm == 18.0
    assert "W_mm=6" in info.value.detail


def test_refusal_names_the_nearest_in_box_design(emulator):
    with pytest.raises(InputError) as info:
        emulator.predict(Design(L_mm=20.0, body_length_mm=24.0), [100])
    assert info.value.field == "L_mm"
    assert info.value.nearest is not None and info.value.nearest.L_mm == 18.0


def test_a_direction_with_too_few_curves_is_refused_in_words(emulator):
    """Database record 66ee5bf2 (service/data/curves.h5): Ecoflex x3.95 on PDMS 1:15, a
    reversed pair stiff enough in the body to bend away from the membrane (its FE curve
    +82 deg at the volume stop). The database holds 3 curves of that direction, too few to
    emulate: the refusal names the direction and what is answered, not the emulator's
    internal group keys ("allowed: ecoflex_00_30/ecoflex_00_30+, ..." before)."""
    design = Design(L_mm=7.703335, t_mm=0.546804, T_mm=1.767237, b_mm=1.196761,
                    h_mm=0.220012, body_material=scaled_material("ecoflex_00_30", 3.95208),
                    membrane_material=MATERIALS["pdms_1_15"])
    with pytest.raises(InputError) as err:
        emulator.predict(design, [500.0])
    assert err.value.field == "body_material"
    assert "bends away from the membrane" in err.value.detail
    assert "towards the membrane" in err.value.allowed and "POST /v1/solve" in err.value.allowed
    assert "+" not in err.value.allowed


def test_a_design_near_an_early_ended_database_curve_is_flagged(emulator):
    """Within NEAR_FAILED_RADIUS of a database curve that ended early the answer carries
    the flag and says why and what to do; the standard design is far from every one."""
    import math

    from solver.design_space import contrast_range, from_unit
    from surrogate.emulator.emulator import NEAR_FAILED_RADIUS

    pe = emulator.pairs["ecoflex_00_30/pdms_1_15-"]          # the reversed pair
    lo, hi = contrast_range("ecoflex_00_30/pdms_1_15")
    answered = 0
    for fu, _, _ in pe.failed[:20]:     # beside early-ended curves the sign may flip
        u = np.clip(np.asarray(fu, float) + 0.02, 0.0, 1.0)
        geometry, _ = from_unit(u)
        contrast = math.exp(math.log(lo) + u[-1] * (math.log(hi) - math.log(lo)))
        ratio = contrast * MATERIALS["pdms_1_15"].mu0_kpa / MATERIALS["ecoflex_00_30"].mu0_kpa
        design = Design(body_material=scaled_material("ecoflex_00_30", ratio),
                        membrane_material=MATERIALS["pdms_1_15"], **geometry)
        point = locate(design, reduced=True)
        assert np.linalg.norm(point.coordinates() - u) < 1e-4
        assert pe.distance_to_failed(point.coordinates()) < NEAR_FAILED_RADIUS
        try:
            out = emulator.predict(design, [100.0, 500.0])
        except InputError:
            continue
        if "near_stiffness_balance" in out.validity["flags"]:
            continue        # the balance model: fitted on the curves that end early
        answered += 1
        assert "near_early_ended_fe_curves" in out.validity["flags"]
        assert any("ended early" in m and "POST /v1/solve" in m
                   for m in out.validity["messages"])
    assert answered >= 3
    assert "near_early_ended_fe_curves" not in emulator.predict(Design(), [500.0]).validity[
        "flags"]


def test_inverse_round_trip(emulator):
    d = Design(L_mm=11.0, t_mm=0.8, T_mm=1.4, b_mm=2.0, h_mm=0.2)
    inv = emulator.inverse(d, [10.0, 45.0, 80.0])
    fwd = emulator.predict(d, inv.pressure_pa)
    np.testing.assert_allclose(fwd.angle_deg, [10.0, 45.0, 80.0], atol=0.05)
    # past the FE's 90 deg: no number, flagged, the angles within answered as before (as a
    # prediction by pressure; a whole list was refused for one such angle until 2026-12-06)
    past = emulator.inverse(d, [10.0, 120.0])
    assert np.isnan(past.pressure_pa[1]) and np.isnan(past.volume_ul[1])
    assert np.isnan(past.lower_pa[1]) and np.isnan(past.upper_pa[1])
    assert past.pressure_pa[0] == pytest.approx(inv.pressure_pa[0])
    assert "past_fe_range" in past.validity["flags"]
    assert "past_fe_range" not in inv.validity["flags"]
    with pytest.raises(InputError, match="bends the other way"):
        emulator.inverse(d, [-10.0])


def test_by_volume_the_fe_records_own_volume_column_is_reproduced(emulator):
    """The syringe-pump view: angle and pressure at the FE's own injected volumes."""
    keys = {k for pe in emulator.pairs.values() for k in pe.keys}
    with CurveStore(DB) as db:
        for key in sorted(keys)[::20]:
            c = db.get(key).curve
            inside = (np.abs(c.angle_deg) <= 89.0) & (c.volume_ul > 0)
            pred = emulator.predict_volume(db.get(key).design, c.volume_ul[inside])
            assert np.nanmax(np.abs(pred.angle_deg - c.angle_deg[inside])) < 0.5
            rel = np.abs(pred.pressure_pa / c.pressure_pa[inside] - 1)
            assert np.nanmax(rel[np.abs(c.angle_deg[inside]) > 1]) < 0.01


def test_predict_by_volume_or_time_over_http(shipped_client):
    by_v = shipped_client.post("/v1/predict", json={"volumes_ul": [5, 10, 20, 400]}).json()
    by_t = shipped_client.post("/v1/predict", json={"times_s": [2, 4, 8, 160],
                                            "flow_ul_s": 2.5}).json()
    assert by_v["angle_deg"][:3] == pytest.approx(by_t["angle_deg"][:3])
    assert by_t["time_s"] == [2, 4, 8, 160] and by_v["volume_ul"] == [5, 10, 20, 400]
    assert by_v["angle_deg"][3] is None and "past_fe_range" in by_v["validity"]["flags"]
    assert 0 < by_v["pressure_pa"][0] < by_v["pressure_pa"][2]
    both = shipped_client.post("/v1/predict", json={"volumes_ul": [5], "pressures_pa": [100]})
    assert both.status_code == 422 and "exactly one" in both.text
    lone = shipped_client.post("/v1/predict", json={"times_s": [5]})
    assert lone.status_code == 422 and "flow_ul_s" in lone.text


HELD_OUT_SETS = ("ho2028", "ho2029", "ho2030", "ho2031", "ho2032")


def _free_curve_scores(emulator, records) -> dict:
    """Per axis (pressure, volume) over free-tip FE ``records``: answered FE points (|angle|
    <= 90 deg), those inside the 95 % band, curves within the issue's per-curve target
    (RMSE <= 1 and max <= 3 deg over the answered points); and the queries past an
    early-ended FE curve's last pressure that were answered with a number."""
    scores = {"pressure": [0, 0, 0], "volume": [0, 0, 0], "curves": 0, "past": [0, 0]}
    for rec in records:
        c = rec.curve
        keep = (np.abs(c.angle_deg) <= 90.0) & (c.pressure_pa > 0)
        try:
            answers = {"pressure": emulator.predict(rec.design, c.pressure_pa[keep]),
                       "volume": emulator.predict_volume(rec.design, c.volume_ul[keep])}
        except InputError:
            continue                         # refused: too near the Ecoflex/Ecoflex balance
        scores["curves"] += 1
        for axis, pred in answers.items():
            ok = np.isfinite(pred.angle_deg)
            fe = c.angle_deg[keep][ok]
            err = pred.angle_deg[ok] - fe
            s = scores[axis]
            s[0] += int(ok.sum())
            s[1] += int(((fe >= pred.lower_deg[ok]) & (fe <= pred.upper_deg[ok])).sum())
            s[2] += int(ok.any() and np.sqrt(np.mean(err**2)) <= 1.0
                        and np.abs(err).max() <= 3.0)
        if np.abs(c.angle_deg).max() < 89.0:        # the FE stopped early: nothing past it
            past = emulator.predict(rec.design, c.pressure_pa.max() * np.array([1.02, 1.3]))
            scores["past"][0] += 2
            scores["past"][1] += int(np.isfinite(past.angle_deg).sum())
    return scores


def test_free_curves_of_random_designs_outside_the_database(emulator):
    """The cheap version of the slow test below: 101 free-tip FE curves of random designs
    of the box the database does not hold (benchmarks/heldout/ho2028-ho2032.h5, drawn by
    benchmarks/heldout_designs.py: uniform in every length and each layer's stiffness
    scale, the four pairs in turn), asked by their own pressures and by their own injected
    volumes. The 95 % band covers 0.90-0.98 of the answered points on both axes, no
    number is given past the pressure where an FE curve stopped early, and at least 70 %
    of the curves meet the issue's per-curve target (on the shipped fit: coverage 0.961 by
    pressure and 0.963 by volume; 81 and 80 of 101 curves within the target;
    benchmarks/RESULTS.md says where the rest miss)."""
    heldout = Path(__file__).resolve().parents[1] / "benchmarks" / "heldout"
    records = []
    for name in HELD_OUT_SETS:
        with CurveStore(heldout / f"{name}.h5") as db:
            records += [r for r in db.records()
                        if r.status == "complete" and r.settings.tip != "blocked"]
    assert len(records) >= 100
    scores = _free_curve_scores(emulator, records)
    print(scores)
    assert scores["curves"] >= 95
    for axis in ("pressure", "volume"):
        answered, inside, within = scores[axis]
        assert 0.90 <= inside / answered <= 0.98, (axis, inside / answered)
        assert within >= 0.7 * scores["curves"], (axis, within)
    assert scores["past"][0] >= 20 and scores["past"][1] == 0, scores["past"]


def _answered_draws(emulator, body: str, membrane: str, ranges: dict, rng, tries: int = 6):
    """Up to ``tries`` random designs of a pair (uniform in each length of ``ranges`` and
    each layer's stiffness scale) that the emulator answers: a draw at the
    Ecoflex/Ecoflex balance is refused and the next one taken."""
    from solver.design_space import STIFFNESS_SCALE_RANGE

    for _ in range(tries):
        s_b, s_m = rng.uniform(*STIFFNESS_SCALE_RANGE, size=2)
        design = Design(body_material=scaled_material(body, round(s_b, 3)),
                        membrane_material=scaled_material(membrane, round(s_m, 3)),
                        **{k: round(rng.uniform(lo, hi), 3) for k, (lo, hi) in ranges.items()})
        try:
            emulator.predict(design, [100.0])
        except InputError:
            continue
        yield design


@pytest.mark.slow
def test_held_out_random_designs_solved_by_the_fe(emulator):
    """Designs the test draws itself over the whole box (uniform in every length and each
    layer's stiffness scale, two per material pair; not the database's Sobol points),
    solved by the default FE. Asserted: the honesty guarantees (the 95 % band covers at
    least 80 % of the answered FE points on each axis, no angle past the FE's range is a
    number). The issue's accuracy target (RMSE <= 1 deg, max <= 3 deg per curve) is
    printed, not asserted: benchmarks/RESULTS.md says where it stands."""
    from types import SimpleNamespace

    from solver import SolverSettings, solve
    from solver.design_space import BOX_MM, PAIRS

    rng = np.random.default_rng()
    records = []
    for body, membrane in PAIRS:
        kept = 0
        for design in _answered_draws(emulator, body, membrane, BOX_MM, rng):
            curve = solve(design, SolverSettings())
            if curve.status == "failed" or len(curve.pressure_pa) < 3:
                continue
            records.append(SimpleNamespace(design=design, curve=curve))
            one = _free_curve_scores(emulator, records[-1:])
            print(f"{design.body_material.id}/{design.membrane_material.id} "
                  f"{ {k: getattr(design, k) for k in BOX_MM} }: {one}")
            far = emulator.predict(design, [curve.pressure_pa.max() * 3])
            assert np.isnan(far.angle_deg[0])
            kept += 1
            if kept == 2:
                break
    scores = _free_curve_scores(emulator, records)
    print(scores)
    assert scores["curves"] >= 6
    for axis in ("pressure", "volume"):
        answered, inside, _ = scores[axis]
        assert inside >= 0.8 * answered, (axis, inside, answered)
    assert scores["past"][1] == 0, scores["past"]


def _force_against_fe(emulator, records) -> tuple[int, int, int]:
    """(FE points with |F| > 1 uN within 2500 Pa, points the answer gives a force at, of
    those inside its band) over blocked-tip FE ``records``; no force past the range."""
    points = given = inside = 0
    for rec in records:
        c = rec.curve
        keep = (c.pressure_pa > 0) & (c.pressure_pa <= 2500.0) & (np.abs(c.force_mn) > 1e-3)
        pred = emulator.predict(rec.design, c.pressure_pa[keep])
        if pred.force_mn is None:            # at the Ecoflex/Ecoflex balance: no direction
            assert "near_stiffness_balance" in pred.validity["flags"]
            continue
        assert pred.force_mn is not None            # every group has a force model
        fe, f = c.force_mn[keep], pred.force_mn
        ok = np.isfinite(f)
        points += int(keep.sum())
        given += int(ok.sum())
        inside += int(((fe[ok] >= pred.force_lower_mn[ok] - 1e-9)
                       & (fe[ok] <= pred.force_upper_mn[ok] + 1e-9)).sum())
        if not ok.all():
            assert {"force_band_too_wide", "force_past_fe_range"} & set(
                pred.validity["flags"])
    return points, given, inside


def test_force_on_blocked_tip_fe_curves_of_random_designs_outside_the_database(emulator):
    """38 blocked-tip FE curves of random designs of the box that the database does not
    hold (benchmarks/heldout/force3040.h5: four pairs in turn, each layer's stiffness
    scaled): the force is given at most of their points (the former F/p-over-secant model:
    390 of 751, none for the soft-body pairs) and its 95 % band covers 0.9-0.99 of them
    (0.984 on the fit of 2026-12-06, 0.993 with the designs on the box's faces; since the
    force bands' calibration on random blocked-tip designs, forty-fourth session, 454 of
    the 470 points given, 0.966)."""
    path = Path(__file__).resolve().parents[1] / "benchmarks" / "heldout" / "force3040.h5"
    with CurveStore(path) as db:
        records = [r for r in db.records()
                   if r.status == "complete" and r.settings.tip == "blocked"]
    assert len(records) >= 30
    points, given, inside = _force_against_fe(emulator, records)
    assert given >= 0.7 * points, (given, points)
    assert 0.9 <= inside / given <= 0.99, inside / given


@pytest.mark.slow
def test_force_on_blocked_tip_fe_solves_the_test_draws_itself(emulator):
    """Designs the test draws itself, one per pair, the tip held, solved by the default FE
    to the database's blocked-tip pressure: the band covers at least 80 % of the points
    the force is given at, and a force is given at some of them for every pair."""
    from dataclasses import replace
    from types import SimpleNamespace

    from solver import SolverSettings, solve
    from solver.design_space import PAIRS
    from solver.precompute.grid import BLOCKED_MAX_PRESSURE_PA

    blocked = replace(SolverSettings(), tip="blocked", max_pressure_pa=BLOCKED_MAX_PRESSURE_PA)
    rng = np.random.default_rng()
    interior = {"L_mm": (5, 16), "t_mm": (0.55, 1.1), "T_mm": (0.7, 1.8), "b_mm": (1.2, 2.2),
                "h_mm": (0.12, 0.28)}
    total = [0, 0, 0]
    for body, membrane in PAIRS:
        for design in _answered_draws(emulator, body, membrane, interior, rng, tries=5):
            solved = SimpleNamespace(design=design, curve=solve(design, blocked))
            points, given, inside = _force_against_fe(emulator, [solved])
            print(f"{body}/{membrane}: {given} of {points} given, {inside} inside the band")
            total = [a + b for a, b in zip(total, (points, given, inside), strict=True)]
            break
    assert total[1] > 0 and total[2] >= 0.8 * total[1], total


def test_fit_report_sets_the_emulator_beside_the_exponential_on_the_same_curves(emulator):
    """``balloon fit`` prints, per exponential family, both models' held-out RMSE over the
    same FE curves: the emulator's figure is the RMS of its LOO per-curve RMSEs of exactly
    the family's records it holds."""
    import json

    from surrogate.emulator.command import cv_rmse_by_key, side_by_side

    families = json.loads((DATA_DIR / "surrogate.json").read_text())["report"]["families"]
    loo = cv_rmse_by_key(emulator)
    assert len(loo) == sum(len(pe.keys) for pe in emulator.pairs.values())
    lines = side_by_side(families, emulator)
    assert len(lines) == len(families) + 2
    for fam, line in zip(families, lines[2:]):
        held = [loo[k] for k in fam["record_keys"] if k in loo]
        assert held, fam["family"]          # the paper grid's curves are in the emulator
        assert f"{np.sqrt(np.mean(np.square(held))):.2f}" in line
        assert f"{fam['lodo']['exponential']['rmse']:.2f}" in line


def test_force_is_predicted_with_its_band_and_reproduces_blocked_tip_records(
        emulator, monkeypatch, shipped_records):
    """Every material group has a force model fitted from the database's blocked-tip FE
    curves, as the ratio of the force to the free tip's emulated angle at the same
    pressure: at the designs it is fitted to (those whose curve reaches the group's force
    range and pushes the way the group bends) the force model gives the FE's force (mN) to
    5 % of its largest value within the range (the ratio is interpolated between nodes),
    with a band about it, most of it is answered (the band within 2 x the force), and
    nothing is given past the range (the group's, the free curve's end, or 90 % of where
    the design's blocked-tip curve is emulated to end)."""
    import surrogate.emulator.force_answer as force_answer_module
    from surrogate.emulator.database_rows import is_force_record

    assert all(pe.force is not None and pe.force_form == "angle_ratio"
               for pe in emulator.pairs.values())
    checked, answered, inside_total = 0, 0, 0
    records = [r for r in shipped_records if is_force_record(r.settings)]
    for rec in records:
        try:
            point = locate(rec.design, reduced=True)
            pe, cb = emulator.curve_band(point, 1.96)
            pred = emulator.predict(rec.design, rec.curve.pressure_pa)
        except InputError:
            continue                         # near the Ecoflex/Ecoflex balance
        c = rec.curve
        limit_red = pe.force_end_pa(cb.limit_pressure_pa, cb.blocked_end_pa)
        if (c.pressure_pa.max() < pe.force_limit_pa * point.pressure_scale
                or limit_red < pe.force_limit_pa or pe.sign * c.force_mn[-1] <= 0):
            continue     # its blocked or free curve ends before the group's force range
            #              (not fitted), or it pushes the other way
        limit_pa = limit_red * point.pressure_scale
        inside = (c.pressure_pa > 0) & (c.pressure_pa <= limit_pa)
        with monkeypatch.context() as m:
            m.setattr(force_answer_module, "FORCE_BAND_LIMIT", np.inf)
            model = emulator.predict(rec.design, c.pressure_pa[inside])
        f, lo, hi = model.force_mn, model.force_lower_mn, model.force_upper_mn
        fe = c.force_mn[inside]
        assert np.isfinite(f).all()
        assert np.abs(f - fe).max() <= 0.05 * np.abs(fe).max() + 1e-3
        assert ((lo <= f + 1e-12) & (f <= hi + 1e-12)).all()   # its coverage: held out
        assert np.isnan(pred.force_mn[c.pressure_pa > limit_pa * 1.001]).all()
        answered += int(np.isfinite(pred.force_mn[inside]).sum())
        inside_total += int(inside.sum())
        checked += 1
    assert checked >= 40
    assert answered >= 0.8 * inside_total, (answered, inside_total)


def test_force_range_keeps_the_nodes_most_blocked_tip_curves_reach():
    """A soft pair's blocked-tip FE curves stop early (the 500 ul volume stop): the group's
    force range ends at the last node that 60 % of them, and at least 10, reach."""
    from surrogate.emulator.features import FORCE_PRESSURE_NODES_PA, force_at
    from surrogate.emulator.force_fit import force_range

    n_nodes = len(FORCE_PRESSURE_NODES_PA)
    y = np.ones((20, n_nodes))
    y[:8, 10:] = np.nan                  # 8 curves stop after node 10, 12 go on
    y[8:11, 12:] = np.nan                # 3 more stop after node 12
    k, u, yk = force_range(np.zeros((20, 6)), y)
    assert (k, len(u), yk.shape) == (12, 12, (12, 12))
    assert force_range(np.zeros((5, 6)), y[:5])[0] == 0       # too few curves
    per_kpa = np.linspace(1.0, 2.0, 4)
    q = FORCE_PRESSURE_NODES_PA[:4]
    np.testing.assert_allclose(force_at(per_kpa, q), q / 1000 * per_kpa)
    np.testing.assert_allclose(force_at(per_kpa, 10.0), 0.01 * per_kpa[0])


def test_the_force_variable_is_f_over_p_normalised_by_the_free_secant_and_back():
    """features.force_feature: asinh of (F/p) over the free tip's secant theta/p at the
    first angle node; linear through zero (a sign change of the initial reaction), log
    where large, and exactly invertible for either bending sign."""
    from surrogate.emulator.features import (
        FORCE_RATIO_UNIT,
        force_feature,
        free_secant_deg_per_pa,
        per_kpa_from_feature,
    )

    node_mean = np.array([[np.log(200.0), 1.0], [np.log(50.0), 2.0]])  # log(p/theta) first
    for sign in (1.0, -1.0):
        s0 = free_secant_deg_per_pa(node_mean, sign)
        np.testing.assert_allclose(s0, sign * np.array([1 / 200.0, 1 / 50.0]))
        per_kpa = np.array([[-1e-4, 0.0, 2e-3, 0.4], [1e-5, 3e-3, 0.05, 1.0]]) * sign
        y = force_feature(per_kpa, s0)
        np.testing.assert_allclose(per_kpa_from_feature(y, s0), per_kpa, rtol=1e-12,
                                   atol=1e-15)
        assert np.all(np.diff(y, axis=1) > 0)        # monotone in F/p (s0 of its sign)
    # large ratios: a log, so a relative change of F is an additive one of the variable
    big = force_feature(np.array([100.0, 200.0]), 1.0 / FORCE_RATIO_UNIT)
    assert abs((big[1] - big[0]) - np.log(2.0)) < 1e-4


def test_the_force_variable_is_f_over_the_free_angle_and_its_band_combines_both():
    """features.force_angle_feature: asinh of F / theta (mN/deg) over FORCE_ANGLE_UNIT, exact
    back, NaN where theta is 0; force_from_angle_ratio: F = theta k, and each side of the
    band the root sum of squares of the angle's and the ratio's deviations (a hand
    computation), the angle's moving F the way k's sign says."""
    from surrogate.emulator.features import (
        FORCE_ANGLE_UNIT,
        angle_ratio_from_feature,
        force_angle_feature,
        force_from_angle_ratio,
    )

    f = np.array([-2e-5, 0.0, 0.01, 0.5])
    a = np.array([0.02, 0.5, 2.0, 40.0])
    y = force_angle_feature(f, a)
    np.testing.assert_allclose(angle_ratio_from_feature(y), f / a, rtol=1e-12, atol=1e-18)
    assert np.isnan(force_angle_feature(np.array([0.1]), np.array([0.0]))).all()
    big = force_angle_feature(np.array([100.0, 200.0]) * FORCE_ANGLE_UNIT, np.ones(2))
    assert abs((big[1] - big[0]) - np.log(2.0)) < 1e-4        # a log where large
    # theta 10 (8..13) deg, k 0.01 (0.009..0.012) mN/deg: F 0.1 mN,
    # up sqrt((0.01 x 3)^2 + (10 x 0.002)^2), down sqrt((0.01 x 2)^2 + (10 x 0.001)^2)
    one = np.ones(1)
    f, lo, hi = force_from_angle_ratio(10 * one, 8 * one, 13 * one, 0.01 * one,
                                       0.009 * one, 0.012 * one)
    np.testing.assert_allclose([f[0], hi[0] - f[0], f[0] - lo[0]],
                               [0.1, np.hypot(0.03, 0.02), np.hypot(0.02, 0.01)])
    # a negative ratio (the initial reaction's other sign): a larger angle lowers F
    f, lo, hi = force_from_angle_ratio(10 * one, 8 * one, 13 * one, -0.01 * one,
                                       -0.011 * one, -0.009 * one)
    np.testing.assert_allclose([f[0], hi[0] - f[0], f[0] - lo[0]],
                               [-0.1, np.hypot(0.02, 0.01), np.hypot(0.03, 0.01)])


def test_no_force_number_where_its_band_is_wider_than_twice_the_force(emulator):
    """Wherever the force band is wider than FORCE_BAND_LIMIT x the force (and wider than
    FORCE_BAND_FLOOR_MN, far below what a force sensor resolves), no force is given and
    validity says why; the standard design has a force at every pressure of its range,
    its first steps (0.01 uN, the initial reaction's sign uncertain) included."""
    from surrogate.emulator.force_answer import FORCE_BAND_FLOOR_MN, FORCE_BAND_LIMIT

    p = np.linspace(100.0, 2000.0, 20)
    for d in (Design(), Design(L_mm=10, t_mm=0.9, T_mm=1.3, b_mm=1.6, h_mm=0.2)):
        pred = emulator.predict(d, p)
        f, lo, hi = pred.force_mn, pred.force_lower_mn, pred.force_upper_mn
        shown = np.isfinite(f)
        width = hi[shown] - lo[shown]
        assert ((width <= FORCE_BAND_LIMIT * np.abs(f[shown]) + 1e-9)
                | (width <= FORCE_BAND_FLOOR_MN)).all()
        if (~shown).any():
            assert "force_band_too_wide" in pred.validity["flags"]
    pred = emulator.predict(Design(), np.linspace(0.0, 2000.0, 81))
    assert np.isfinite(pred.force_mn).all(), pred.validity["messages"]


def test_bands_are_calibrated_per_angle_bin_on_cross_validated_curves(shipped_records):
    """One band multiplier for the whole curve was set by the low-angle FE points (half of
    them lie below 10 deg) and covered every held-out point above 10 deg with +-30 deg bands.
    Per angle bin, the cross-validated bands of 50 of the reversed pair's database curves (5
    folds, each predicted by the emulator refitted without it) cover 95 % in
    every bin (at least 0.92, 0.929 at 40-60 deg on the 1419-record database: a bin's
    nodes also shape the band just outside it), by
    pressure and by injected volume, and not every point (not needlessly wide), with no
    multiplier near its cap."""
    from surrogate.band_level import z_value
    from surrogate.emulator.band_scales import (
        ANGLE_BINS_DEG,
        angle_bin,
        cross_validated,
        held_out_curves,
        node_band_scales,
    )
    from surrogate.emulator.build import fit_curve_gps
    from surrogate.emulator.database_rows import collect_rows

    free, *_ = collect_rows(shipped_records)
    rows = free["ecoflex_00_30/pdms_1_15"]
    keep = np.array(rows.signs) < 0
    # the first 50 of the pair's curves (151 in the shipped database): the calibration is
    # the same procedure on any set, and 5 refits of 64 per-node GPs on 40 curves take seconds
    u, y = np.array(rows.u)[keep][:50], np.array(rows.y)[keep][:50]
    curves = [c for c, k in zip(rows.curves, keep) if k][:50]
    mean, var = cross_validated(u, y, fit=fit_curve_gps)
    scales = node_band_scales(curves, mean, var, 0.95)
    for axis in ("pressure", "volume"):
        held = held_out_curves(curves, mean, var, scales, z_value(0.95), axis)
        fe = np.concatenate([a for a, *_ in held])
        inside = np.concatenate([(a >= lo - 1e-9) & (a <= hi + 1e-9)
                                 for a, _, lo, hi in held])
        bins = angle_bin(fe)
        for b in range(len(ANGLE_BINS_DEG) - 1):
            if (bins == b).sum() >= 50:
                assert inside[bins == b].mean() >= 0.92, (axis, ANGLE_BINS_DEG[b])
        assert inside.mean() <= 0.99, axis
    # no bin is held at the multiplier's cap: before the band's floor of 0.05 deg
    # (emulator.floored_band) FE points of a few thousandths of a degree, covered
    # relatively, held the lowest bin there in every group
    assert scales.max() < 10


def _shifted_records(records, scale: float, count: int = 12):
    """Complete default-FE curves of the shipped database (``records``), PDMS group, their
    pressures times ``scale``: FE-shaped curves the emulator misses by a known stiffness
    error."""
    from dataclasses import replace

    from solver.settings import SolverSettings

    recs = [r for r in records if r.settings == SolverSettings()
            and "pdms" in r.design.body_material.id and r.curve.angle_deg[-1] >= 89.0]
    return [replace(r, curve=replace(r.curve, pressure_pa=r.curve.pressure_pa * scale))
            for r in recs[:count]]


def test_bands_are_calibrated_on_random_designs_fe_curves(emulator, shipped_records):
    """The second calibration: where the calibration curves lie outside the bands (here FE
    curves whose pressures read 25 % high: the emulator misses them by a known stiffness
    error), the bands widen per angle bin until ``level`` of their points are inside;
    where the curves lie inside (the same curves unshifted: database designs, which it
    reproduces), nothing changes; the report says what was done."""
    from surrogate.emulator.random_calibration import (
        calibrate_on_random_designs,
        coverage,
        point_factors,
    )

    shifted = _shifted_records(shipped_records, 1.25)
    before = coverage(point_factors(emulator, shifted))
    assert before["pressure"]["all"] < 0.5
    cal = calibrate_on_random_designs(emulator, shifted, source={"database_name": "x.h5"})
    rep = cal.report["random_design_calibration"]
    assert rep["coverage_before"]["pressure"]["all"] == pytest.approx(
        before["pressure"]["all"])
    assert rep["coverage_after"]["pressure"]["all"] >= 0.93
    assert rep["coverage_after"]["volume"]["all"] >= 0.93
    assert max(rep["factors"]["pressure"]["far"]) > 1.5
    assert rep["curves"] == 12 and rep["source"]["database_name"] == "x.h5"
    for key, pe in cal.pairs.items():       # every group alike, by the same factors
        ratio = pe.band_scale / emulator.pairs[key].band_scale
        np.testing.assert_allclose(ratio, cal.pairs["pdms/ecoflex_00_30+"].band_scale
                                   / emulator.pairs["pdms/ecoflex_00_30+"].band_scale)
    wide = cal.predict(Design(), [1500.0])
    narrow = emulator.predict(Design(), [1500.0])
    assert (wide.upper_deg - wide.lower_deg)[0] > 1.4 * (narrow.upper_deg
                                                          - narrow.lower_deg)[0]
    same = calibrate_on_random_designs(emulator, _shifted_records(shipped_records, 1.0))
    for key, pe in same.pairs.items():
        np.testing.assert_allclose(pe.band_scale, emulator.pairs[key].band_scale)
    # the mask of the fit's report is the query's flag: within NEAR_FAILED_RADIUS
    from surrogate.emulator.accuracy_report import near_failed_mask

    u = np.random.default_rng(0).uniform(size=(50, 6))
    mask = near_failed_mask(u, [(u[0] + 0.1, 40.0, "x")])
    np.testing.assert_array_equal(mask, np.linalg.norm(u - (u[0] + 0.1), axis=1) < 0.3)
    assert not near_failed_mask(u, []).any()


def test_a_calibration_database_that_shares_curves_with_the_fit_is_refused(emulator,
                                                                           tmp_path):
    from solver.errors import InputError
    from surrogate.emulator.command import _calibrate

    with pytest.raises(InputError) as info:
        _calibrate(emulator, DB, 0.95)
    assert info.value.field == "--band-calibration-db"


def test_the_widened_band_applies_only_near_early_ended_curves(emulator):
    """A pair's ``near_failed_band_scale`` multiplies the sd of a query within
    NEAR_FAILED_RADIUS of an early-ended curve, and of no other; the batch distance
    (``nearest_failed``) is the single one."""
    from dataclasses import replace

    from surrogate.emulator.emulator import N_NODES, NEAR_FAILED_RADIUS

    pe = emulator.pairs["ecoflex_00_30/pdms_1_15-"]
    wide = replace(pe, near_failed_band_scale=np.full(2 * N_NODES, 2.0))
    d = np.array([0.0, NEAR_FAILED_RADIUS * 0.99, NEAR_FAILED_RADIUS * 1.01, np.inf])
    got = wide.band_scales(d)
    np.testing.assert_allclose(got[:2], 2.0 * np.tile(pe.band_scale, (2, 1)))
    np.testing.assert_allclose(got[2:], np.tile(pe.band_scale, (2, 1)))
    np.testing.assert_allclose(replace(pe, near_failed_band_scale=None).band_scales(d),
                               np.tile(pe.band_scale, (4, 1)))
    fu = np.asarray(pe.failed[0][0], float)
    near_u = np.clip(fu + 0.01, 0, 1)
    assert wide.nearest_failed(near_u[None])[0] == pytest.approx(
        wide.distance_to_failed(near_u))


def test_a_fit_from_part_of_the_database_predicts_force_and_survives_its_file(
        tmp_path, monkeypatch, shipped_records):
    """The fit end to end on a slice of the shipped database (the PDMS group's first 16
    complete free-tip curves and its blocked-tip curves): the force model is the angle-ratio
    form, reproduces its blocked-tip designs, and a saved file answers identically."""
    from surrogate.emulator.build import fit_emulator
    from surrogate.emulator.database_rows import LIMIT_ANGLE_DEG, is_force_record
    from surrogate.emulator.features import curve_features
    from surrogate.emulator.file import load_emulator as load
    from surrogate.emulator.file import save_emulator

    def interpolated(r) -> bool:
        """Rising to the FE's stop (a curve past a limit point is an early-ended one)."""
        pt, c = locate(r.design, reduced=True), r.curve
        f = curve_features(c.pressure_pa / pt.pressure_scale,
                           c.volume_ul / pt.length_scale**3, c.angle_deg)
        return f.end_angle_deg >= LIMIT_ANGLE_DEG and bool(np.isfinite(f.log_p).all())

    recs = [r for r in shipped_records if "pdms" in r.design.body_material.id]
    free = [r for r in recs if not is_force_record(r.settings) and interpolated(r)][:16]
    early = [r for r in recs if not is_force_record(r.settings)
             and 5.0 < r.curve.angle_deg[-1] < 80.0][:4]
    blocked = [r for r in recs if is_force_record(r.settings)]
    e = fit_emulator(free + early + blocked)
    pe = e.pairs["pdms/ecoflex_00_30+"]
    assert pe.force is not None and pe.force_form == "angle_ratio"
    assert pe.range_model is not None and len(pe.failed) == len(early)
    path = save_emulator(e, tmp_path / "e.json")
    # written as canonical JSON: the checksum is checked on the file's bytes
    import json

    from surrogate.file_seal import KEY, _raw_matches
    raw = path.read_bytes()
    assert _raw_matches(raw, json.loads(raw)[KEY])
    again = load(path)
    # loading makes no kernel's L^-1 or K (a query's first variance does); warm_up makes
    # every one the queries below need, and remembers no answer
    assert _kernels_made(again) == 0
    again.warm_up()
    warm = _kernels_made(again)
    assert warm > 0 and len(again._memo) == 0
    # the pressure nodes share one kernel (build.fit_curve_gps; 16 designs are too few
    # for the top pressure GPs: TOP_PRESSURE_MIN_DESIGNS): the variance is exact at every
    # node (variance_nodes.py), one product per query, and the file keeps the nodes
    from surrogate.emulator.emulator import N_NODES
    from surrogate.emulator.shape_gps import TOP_PRESSURE_MIN_DESIGNS
    assert e.report["variance_nodes"]["shared_kernel"]
    np.testing.assert_array_equal(e.variance_nodes, np.arange(N_NODES))
    assert len(pe.coordinates) < TOP_PRESSURE_MIN_DESIGNS and pe.curves.top_pressure is None
    assert pe.curves.kernels(slice(0, N_NODES)) == 1
    assert pe.curves.kernels(slice(N_NODES, 2 * N_NODES)) == N_NODES
    np.testing.assert_array_equal(again.variance_nodes, e.variance_nodes)
    rec = blocked[0]
    c = rec.curve
    inside = (c.pressure_pa > 0) & (c.pressure_pa <= pe.force_limit_pa)
    a, b = (m.predict(rec.design, c.pressure_pa[inside]) for m in (e, again))
    np.testing.assert_array_equal(a.force_mn, b.force_mn)
    np.testing.assert_array_equal(a.angle_deg, b.angle_deg)
    assert a.validity["fe_limit_pa"] == b.validity["fe_limit_pa"]
    # the emulated end of the FE curve (deg / 90) reproduces where each curve ended
    ends = [a for _, a, _ in pe.failed] + [90.0] * len(free)
    coords = np.array([np.asarray(u, float) for u, _, _ in pe.failed] + list(pe.coordinates))
    emulated = 90.0 * again.pairs[pe.pair].range_model.predict_many(coords)[0][:, 0]
    np.testing.assert_allclose(emulated, ends, atol=0.5)
    # a database design: the force GP interpolates its own F / theta, so the force model
    # (read where the answer withholds it too: with 16 free curves the free angle's band,
    # part of the force band, is wide) reproduces its FE curve, inside its band
    import surrogate.emulator.force_answer as force_answer_module
    monkeypatch.setattr(force_answer_module, "FORCE_BAND_LIMIT", np.inf)
    full = e.predict(rec.design, c.pressure_pa[inside])
    fe = c.force_mn[inside]
    np.testing.assert_allclose(full.force_mn, fe, atol=0.02 * np.abs(fe).max())
    assert np.all((full.force_lower_mn <= fe + 1e-9) & (fe <= full.force_upper_mn + 1e-9))
    answered = np.isfinite(a.force_mn)
    np.testing.assert_array_equal(a.force_mn[answered], full.force_mn[answered])
    for r in free[:3] + early[:2]:
        again.predict(r.design, [300.0, 900.0])
        again.predict_volume(r.design, [2.0, 8.0])
    assert _kernels_made(again) == warm


def _kernels_made(emulator) -> int:
    """How many kernels of the emulator's GPs hold their L^-1 (``VectorGP._linv_t``)."""
    gps = list(emulator.sign_models.values()) + [m.gp for m in emulator.balance_models.values()]
    for pe in emulator.pairs.values():
        c = pe.curves
        gps += [c.gp, c._pressure_gp, pe.range_model]
        gps += list(getattr(pe.force, "segments", [pe.force]))
        gps += [g.gp for g in (c.volume, c.top_pressure) if g is not None]
    return sum(len(g._stack["linv_t"]) for g in gps if g is not None)


def test_an_emulator_file_with_an_unknown_force_form_is_refused_and_a_format_3_file_reads(
        emulator, no_curve_gps):
    """file.py: force_form is one of FORCE_FORMS (a file that says otherwise is refused,
    naming the field); a format-3 file, which has no force_form, holds plain F/p. The
    documents are unsealed (read without a checksum): sealing 30 MB costs ~2 s each."""
    from surrogate.emulator.file import emulator_from_dict, emulator_to_dict
    from surrogate.errors import SurrogateFileError
    from surrogate.file_seal import KEY

    doc = emulator_to_dict(emulator)
    bad = {k: v for k, v in doc.items() if k != KEY}
    bad["variance_nodes"] = [0, 5, 3, 31]
    # both refused before any pair's curve GPs are factorised (~3 s for the four)
    with no_curve_gps(), pytest.raises(SurrogateFileError, match="variance_nodes"):
        emulator_from_dict(bad)
    doc.pop("variance_nodes", None)     # the format-3 file below has none
    body = {k: v for k, v in doc.items() if k != KEY}
    body["pairs"][0]["force_form"] = "newtons"
    with no_curve_gps(), pytest.raises(SurrogateFileError, match="force_form"):
        emulator_from_dict(body)
    old = {k: v for k, v in doc.items() if k != KEY}
    old["format_version"] = 3
    # the smallest group alone (each group reads alike; the file's factorisations dominate)
    old["pairs"] = [min(old["pairs"], key=lambda p: len(p["keys"]))]
    old["sign_models"] = {}
    for p in old["pairs"]:             # (shared with body's: the bad value goes too)
        del p["force_form"]
    e3 = emulator_from_dict(old)
    assert all(pe.force_form == "per_kpa" for pe in e3.pairs.values())
    # before format 8 the variance nodes were the code's: the 2155-record fit's choice
    from surrogate.emulator.variance_nodes import FORMAT_7_NODES
    assert "variance_nodes" not in old
    np.testing.assert_array_equal(e3.variance_nodes, FORMAT_7_NODES)


def test_the_range_ends_where_the_fe_would_stop_at_its_volume_limit(emulator):
    """The default FE stops at 500 ul injected (SolverSettings.max_volume_ul). Scaling every
    length by k leaves angle(p) unchanged and multiplies the volume by k^3 (the length
    invariance, tests/test_design_space_invariance.py), so the standard design made 3x
    larger injects 27x the volume at each angle: its FE curve would end where that volume
    reaches 500 ul, before 90 deg, and the emulator's range must end there too, at the
    angle where the 1x design's emulated volume is 500 / 27 ul."""
    from solver.settings import SolverSettings

    stop_ul = SolverSettings().max_volume_ul
    small = Design()
    k = 3.0
    big = Design(L_mm=k * small.L_mm, t_mm=k * small.t_mm, T_mm=k * small.T_mm,
                 b_mm=k * small.b_mm, h_mm=k * small.h_mm, W_mm=k * small.W_mm,
                 body_length_mm=k * small.resolved_body_length_mm)
    angles = np.linspace(1, 89, 89)
    v_small = emulator.inverse(small, angles).volume_ul
    assert v_small[-1] * k**3 > stop_ul        # the big one would pass the stop by 90 deg
    stop_angle = float(np.interp(stop_ul / k**3, v_small, angles))
    p = np.linspace(10, 5000, 400)
    pred = emulator.predict(big, p)
    assert pred.validity["fe_limit_angle_deg"] == pytest.approx(stop_angle, abs=0.5)
    assert "max_volume_ul" in pred.validity["fe_stop_reason"]
    # said as what it is, a scaled copy's k^3 volume, not a balloon that hardly bends (at
    # W = 20 mm the curve ended at 0.2 deg, explained so: the explorer audit, 2026-12-06)
    assert "3x the box's size" in pred.validity["fe_stop_reason"]
    assert "grows more than the actuator bends" not in pred.validity["fe_stop_reason"]
    assert np.nanmax(pred.angle_deg) <= stop_angle + 0.5
    assert np.isnan(pred.angle_deg[-1]) and "past_fe_range" in pred.validity["flags"]
    by_volume = emulator.predict_volume(big, [0.5 * stop_ul, 1.2 * stop_ul])
    assert np.isfinite(by_volume.angle_deg[0]) and np.isnan(by_volume.angle_deg[1])
    # the 1x design reaches 90 deg well inside the stop
    assert emulator.predict(small, p).validity["fe_limit_angle_deg"] == 90.0


def test_the_answer_lies_inside_its_own_band_across_the_box(emulator):
    """The band is the horizontal band of the node-wise p(theta) curves made monotone
    (asymmetric where it is wide, far from the database designs); at 120 designs drawn
    uniformly in the box (each layer's stiffness scaled on its own) and 80 pressures each,
    every answered angle lies inside its band, at least ANGLE_BAND_FLOOR_DEG (0.05 deg)
    from either side, except across zero: a design that bends one way has no band on the
    other side (surrogate.predictor.one_signed); and except at the end of the FE's range,
    where the band stops (band_within_fe) and the answer too."""
    from surrogate.predictor import one_signed

    rng = np.random.default_rng(99)
    pairs = [("pdms_1_10", "ecoflex_00_30"), ("pdms_1_15", "ecoflex_00_30"),
             ("ecoflex_00_30", "pdms_1_15"), ("ecoflex_00_30", "ecoflex_00_30")]
    p = np.linspace(50, 4000, 80)
    answered = 0
    for i in range(120):
        body, membrane = pairs[i % 4]
        design = Design(body_material=scaled_material(body, rng.uniform(0.5, 2)),
                        membrane_material=scaled_material(membrane, rng.uniform(0.5, 2)),
                        L_mm=rng.uniform(4, 18), t_mm=rng.uniform(0.5, 1.2),
                        T_mm=rng.uniform(0.6, 2.0), b_mm=rng.uniform(1.0, 2.4),
                        h_mm=rng.uniform(0.1, 0.3))
        try:
            r = emulator.predict(design, p)
        except InputError:                  # near the Ecoflex/Ecoflex balance: refused
            continue
        ok = np.isfinite(r.angle_deg)
        answered += int(ok.sum())
        a = r.angle_deg[ok]
        _, lo, hi = one_signed(a, a - 0.05, a + 0.05, 1.0 if np.sum(a) >= 0 else -1.0)
        # the band stops at the FE's range: its end angle, or the FE's angle stop where the
        # balance model answers (a curve by volume that may peak inside its range)
        cap = (90.0 if "near_stiffness_balance" in r.validity["flags"]
               else abs(r.validity["fe_limit_angle_deg"]))
        assert (np.abs(a) <= cap).all()
        lo, hi = np.clip(lo, -cap, cap), np.clip(hi, -cap, cap)
        assert (r.lower_deg[ok] <= lo + 1e-9).all() and (r.lower_deg[ok] <= a).all()
        assert (hi <= r.upper_deg[ok] + 1e-9).all() and (a <= r.upper_deg[ok]).all()
    assert answered > 5000


def test_the_band_read_between_variance_nodes_matches_the_exact_one(emulator):
    """A query computes the pressure nodes' variance exactly at the fit's variance_nodes
    only and reads the others off a spline (Emulator.spread_variance): at 40 random designs
    in the box the sd so read is within 5 % of the exact one at every node, 2 % in the
    median (12 nodes on the 2275-record fit: 3.8 % and 1.6 % on 100 designs; 17 nodes on
    the 2155-record fit: 2.9 % and 1.0 %; an evenly spread set read the
    4-10 deg nodes up to 13 % off on that fit, and that fit's set a 1356-record fit of the
    balanced mesh up to 11.8 %: so each fit chooses its own, variance_nodes.py). Since the
    pressure nodes share one kernel (2026-12-04) the fit's nodes are all 32, each exact."""
    from surrogate.emulator.emulator import N_NODES

    rng = np.random.default_rng(1)       # not the choice's seeds (7, 99)
    nodes = emulator.variance_nodes
    worst = []
    for pe in emulator.pairs.values():
        for _ in range(10):
            u = rng.uniform(0, 1, pe.coordinates.shape[1])
            _, exact = pe.curves.predict(u)
            known = np.full_like(exact, np.nan)
            known[nodes] = exact[nodes]
            read = emulator.spread_variance(known)[:N_NODES]
            worst.append(np.abs(np.sqrt(read / exact[:N_NODES]) - 1).max())
    assert max(worst) < 0.05 and np.median(worst) < 0.02


def test_where_nearby_fe_curves_end_early_the_answer_stops_too(emulator):
    """Near the Ecoflex/Ecoflex stiffness balance about half the database's curves end at
    the FE's volume stop (500 ul: the membrane balloons, the actuator hardly bends), and
    only complete curves are interpolated. This held-out design (benchmarks/heldout_designs.py
    --n 24 --seed 2028, not in the database) reached the volume stop at -58.4 deg and
    1102 Pa with the default FE; before the emulated end of the FE curve
    (PairEmulator.range_model) it was answered to -88 deg at 1100 Pa. Now the answer stops
    short of the FE's end, says why, and where it answers it is within 6 deg of the FE."""
    design = Design(L_mm=9.5184, t_mm=0.7342, T_mm=0.6765, b_mm=1.4828, h_mm=0.2402,
                    body_material=scaled_material("ecoflex_00_30", 0.6112),
                    membrane_material=scaled_material("ecoflex_00_30", 0.6536))
    fe_pressure_pa = np.array([90.9, 520.2, 888.7, 970.8, 999.2, 1036.4, 1053.1, 1078.9])
    fe_angle_deg = np.array([-0.08, -2.88, -19.48, -32.81, -39.31, -47.81, -50.83, -55.02])
    r = emulator.predict(design, fe_pressure_pa)
    # since 2026-12-05 the balance model answers it (surrogate.emulator.balance, fitted on
    # the curves that end at the volume stop): every FE point below its limit, within 5
    # deg (4.8 at the last, the curve's steep top); past the limit no number
    assert "near_stiffness_balance" in r.validity["flags"]
    assert np.isfinite(r.angle_deg).all()
    assert np.abs(r.angle_deg - fe_angle_deg).max() < 6.0
    assert "volume stop" in r.validity["fe_stop_reason"]
    limit_pa = r.validity["fe_limit_pa"]
    assert 1000.0 < limit_pa < 1102.0 and abs(r.validity["fe_limit_angle_deg"]) < 58.4
    past = emulator.predict(design, [1.02 * limit_pa])
    assert np.isnan(past.angle_deg).all() and "past_fe_range" in past.validity["flags"]


def test_force_bands_calibrated_by_cross_validation_cover_designs_left_out(emulator,
                                                                        shipped_records):
    """force_fit.force_band_scale on two thirds of each group's blocked-tip database designs;
    the bands of the GP fitted to them, read at the other third: pooled over the four
    groups and two splits they cover >= 0.9 of the force variable's values. The closed-form
    leave-one-out it replaces put every multiplier at 1, and those bands covered
    them (0.33-0.98 by split: 0.70 pooled)."""
    from surrogate.band_level import z_value
    from surrogate.emulator import database_rows, force_fit
    from surrogate.emulator.force_gps import fit_force_nodewise

    _, force, *_ = database_rows.collect_rows(r for r in shipped_records
                                              if database_rows.is_force_record(r.settings))
    inside = []
    for key, pe in emulator.pairs.items():
        fu, per_kpa = (np.array(a) for a in force[key[:-1]])
        _, fu, fy = force_fit.force_range(*force_fit.force_angle_rows(fu, per_kpa, pe.curves,
                                                                      pe.sign))
        if 2 * len(fu) // 3 < database_rows.MIN_DESIGNS:
            continue                    # too few to fit on two thirds
        for seed in (0, 1):
            order = np.random.default_rng(seed).permutation(len(fu))
            train, test = order[: 2 * len(fu) // 3], order[2 * len(fu) // 3:]
            scale, _ = force_fit.force_band_scale(fu[train], fy[train], 0.95)
            m, v = fit_force_nodewise(fu[train], fy[train]).predict_many(fu[test])
            inside.append((np.abs(m - fy[test]) <= z_value(0.95) * scale * np.sqrt(v)).ravel())
    coverage = np.concatenate(inside).mean()
    assert coverage >= 0.9, coverage


def test_a_single_querys_single_precision_band_keeps_the_double_one(emulator):
    """A single query reads each variance node's L^-1 in single precision
    (vector_gp._shifted_variance); the batch path reads it in double. On every group of the
    shipped emulator, at random box designs and at 0.001 and 0.03 from its database
    designs, the band's sd agrees within 2 % (measured 2026-12-03: at most 1.1 %, median
    1e-4). A refit whose GPs are too ill-conditioned for single precision fails here."""
    from surrogate.emulator.emulator import N_NODES

    rng = np.random.default_rng(2026)
    which = np.concatenate((emulator.variance_nodes, np.arange(N_NODES, 2 * N_NODES)))
    for pe in emulator.pairs.values():
        x = pe.curves.gp.gps[0].x
        n, d = x.shape
        queries = np.vstack((rng.random((20, d)),
                             x[rng.integers(0, n, 20)] + 1e-3 * rng.standard_normal((20, d)),
                             x[rng.integers(0, n, 20)] + 3e-2 * rng.standard_normal((20, d))))
        _, var = pe.curves.predict_many(queries, variance_of=which)
        single = np.array([pe.curves.predict(q, variance_of=which)[1] for q in queries])
        np.testing.assert_allclose(np.sqrt(single[:, which]), np.sqrt(var[:, which]),
                                   rtol=0.02, err_msg=pe.pair)


def test_the_emulated_volume_rises_at_least_as_the_fe_volumes_do():
    """volume_shape: a V(theta) that flattens at high angles (a GP artefact; every FE
    curve's d log V / d log theta stays above 0.41 from 20 deg) is lifted to rise as
    theta^0.4 from its last point; one that rises faster, and any fall below 20 deg
    (to the running maximum), is left as the running maximum leaves it."""
    from surrogate.emulator.emulator import (
        FINE_ANGLES_DEG,
        VOLUME_EXPONENT_FLOOR,
        VOLUME_FLOOR_FROM_DEG,
        volume_shape,
    )

    theta = FINE_ANGLES_DEG
    steep = 0.02 * theta**1.5
    np.testing.assert_allclose(volume_shape(steep), steep, rtol=1e-12)
    flat = np.where(theta < 60.0, steep, 0.02 * 60.0**1.5)      # flat from 60 deg
    shaped = volume_shape(flat)
    late = theta >= 60.0
    expected = 0.02 * 60.0**1.5 * (theta[late] / theta[late][0]) ** VOLUME_EXPONENT_FLOOR
    np.testing.assert_allclose(shaped[late], expected, rtol=1e-9)
    np.testing.assert_allclose(shaped[~late], flat[~late], rtol=1e-12)
    dip = steep.copy()
    low = (theta > 5.0) & (theta < 10.0)
    dip[low] = 0.02 * 5.0**1.5                                 # flat below 20 deg
    np.testing.assert_allclose(volume_shape(dip)[theta < VOLUME_FLOOR_FROM_DEG],
                               np.maximum.accumulate(dip)[theta < VOLUME_FLOOR_FROM_DEG])
    # rows are designs
    np.testing.assert_allclose(volume_shape(np.vstack((steep, flat)))[1], shaped)


def test_a_group_with_enough_calibration_points_takes_its_own_band_factors():
    """random_calibration.group_cells: a group whose points lie inside its bands keeps
    them (factor 1) though another group's points need 5x; a group with fewer than
    GROUP_MIN_POINTS points on an axis takes the pooled factors."""
    from surrogate.emulator.random_calibration import (
        GROUP_MIN_POINTS,
        PointFactors,
        cell_factors,
        group_cells,
    )

    n = GROUP_MIN_POINTS
    angle = np.tile(np.linspace(1.0, 89.0, n), 3)
    pair = np.repeat(["good+", "bad-", "few+"], n)
    factor = np.where(pair == "bad-", 5.0, 0.1)
    factor[(pair == "few+")] = 3.0
    keep = (pair != "few+") | (np.arange(3 * n) % n < 10)     # "few+": 10 points
    pf = PointFactors(angle[keep], factor[keep], np.zeros(keep.sum(), bool),
                      np.full(keep.sum(), "volume"), pair[keep], np.arange(keep.sum()) // 20)
    pooled = cell_factors(pf)
    good, bad, few = (group_cells(pf, pooled, k) for k in ("good+", "bad-", "few+"))
    assert good["volume"]["far"] == [1.0] * 6
    assert bad["volume"]["far"] == pytest.approx([5.0] * 6)
    assert few["volume"]["far"] == pooled["volume"]["far"]
    assert max(pooled["volume"]["far"]) > 1.0


def test_a_process_that_loads_an_emulator_keeps_openblas_on_one_thread():
    """A design search took 48 s with OpenBLAS's default threads against 7 s on one, on a
    loaded 2-core machine (2026-12-06): the emulator's small products gain nothing from
    threads. Checked in a fresh process without OMP_NUM_THREADS."""
    import os
    import subprocess
    import sys

    code = ("from threadpoolctl import ThreadpoolController as C\n"
            "from service.settings import DATA_DIR\n"
            "from surrogate.emulator import load_emulator\n"
            "load_emulator(DATA_DIR / 'emulator.json')\n"
            "print([i['num_threads'] for i in C().select(internal_api='openblas').info()])")
    env = {k: v for k, v in os.environ.items()
           if k not in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS")}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                         text=True, timeout=300, check=True).stdout
    threads = [int(n) for n in out.strip().strip("[]").split(",")]   # numpy's, scipy's
    assert threads and set(threads) == {1}, out


# A random box design's default FE curve (PDMS 1:10 on Ecoflex presets; POST /v1/solve in
# the thirty-sixth session's judge audit, curve 4da718dc...): complete, "reached
# max_angle_deg = 90.0" at 1661.2 Pa. Its FE points from 1533.9 Pa on.
R5 = dict(L_mm=13.139, t_mm=0.639, T_mm=0.624, b_mm=2.005, h_mm=0.232)
R5_FE_PA = np.array([1533.9, 1582.0, 1624.1])
R5_FE_DEG = np.array([70.55, 78.45, 86.22])


def test_a_design_among_complete_curves_is_answered_to_the_fes_angle_stop(emulator):
    """The range model's mean less one sd (90 +/- 6 deg among complete curves) cut the
    answer at ~83 deg for 399 of 415 random designs whose FE curves reach 90 deg, saying
    that nearby curves end early; this one was refused at 1624 Pa (FE: 86.2 deg). A design
    emulated to end at 85 deg or more, with no early-ended curve within
    NEAR_FAILED_RADIUS, is answered to the FE's 90-deg stop."""
    r = emulator.predict(Design(**R5), R5_FE_PA)
    assert np.isfinite(r.angle_deg).all(), r.validity["messages"]
    assert np.abs(r.angle_deg - R5_FE_DEG).max() < 3.0
    assert r.validity["fe_limit_angle_deg"] == 90.0
    assert "end early" not in r.validity["fe_stop_reason"]


def test_a_design_emulated_to_end_early_keeps_its_cut_and_says_why(emulator):
    """A short thick-body design (the harden tests' 25.7-deg case) is still cut one sd
    short of its emulated end, the reason naming that end."""
    r = emulator.predict(Design(L_mm=4.2, t_mm=0.57, T_mm=1.76), [5000.0])
    assert r.validity["fe_limit_angle_deg"] < 40.0
    assert "emulated to end early too, at" in r.validity["fe_stop_reason"]
    assert "past_fe_range" in r.validity["flags"]
