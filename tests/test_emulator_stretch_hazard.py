"""Answers where a design's FE curve may end in a Newton failure are flagged
(surrogate/emulator/stretch_hazard.py): past the angle at which the emulated membrane
stretch passes HAZARD_STRETCH.

The random designs are the held-out FE sets' (benchmarks/heldout, drawn uniformly from the
box by benchmarks/heldout_designs.py; none in the database) and the band calibration set
(service/data/band-calibration.h5, which only widened the bands)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from service.settings import DATA_DIR
from solver.design import Design
from solver.design_space import locate
from solver.errors import InputError
from solver.settings import SolverSettings
from solver.store import CurveStore
from surrogate.emulator import load_emulator
from surrogate.emulator.file import FORMAT_VERSION, emulator_from_dict, emulator_to_dict
from surrogate.emulator.stretch_hazard import (
    FLAG,
    HAZARD_STRETCH,
    STRETCH_NODES_DEG,
    reached_hazard,
    stretch_nodes,
)
from surrogate.errors import SurrogateFileError
from surrogate.file_seal import KEY

HELDOUT = Path(__file__).resolve().parents[1] / "benchmarks" / "heldout"
SETS = [DATA_DIR / "band-calibration.h5"] + [HELDOUT / f"ho{s}.h5" for s in range(2028, 2036)]


@pytest.fixture(scope="module")
def emulator():
    return load_emulator(DATA_DIR / "emulator.json")


@pytest.fixture(scope="module")
def newton_failed_pdms():
    """(design, FE curve) of every PDMS-bodied random design whose default-FE free-tip
    curve ended in a Newton failure."""
    out = []
    for path in SETS:
        with CurveStore(path) as db:
            for rec in db.records():
                c = rec.curve
                if (rec.settings == SolverSettings() and c is not None
                        and c.status == "failed" and len(c.angle_deg) >= 3
                        and rec.design.body_material.id.startswith("pdms")):
                    out.append((rec.design, c))
    return out


def _curve(emulator, design):
    """The design's emulated curve (``Emulator.curve_band``)."""
    return emulator.curve_band(locate(design, reduced=True), 1.96)[1]


def test_the_stretch_nodes_of_a_curve():
    angle = np.array([0.0, 10.0, 40.0, 70.0])
    stretch = np.array([1.0, 2.0, 5.0, 8.0])
    nodes = stretch_nodes(-angle, stretch)         # a reversed pair: |angle|
    np.testing.assert_allclose(np.exp(nodes[:5]) + 1.0, [1.5, 2.5, 4.0, 5.5, 7.0])
    assert np.isnan(nodes[STRETCH_NODES_DEG > 70]).all()
    assert reached_hazard(stretch) and not reached_hazard(stretch[:3])


def test_answers_past_a_newton_failure_the_range_does_not_foresee_are_flagged(
        emulator, newton_failed_pdms):
    """Asked just past its FE's last pressure, a random PDMS-bodied design whose FE curve
    failed is either refused there (the range foresaw it) or flagged; before this model
    11 of those answers had no flag saying the FE might end there (14 answered, 3 flagged
    near_early_ended_fe_curves)."""
    answered = flagged = 0
    for design, c in newton_failed_pdms:
        end_pa = float(np.max(c.pressure_pa))
        a = emulator.predict(design, [1.01 * end_pa, 1.02 * end_pa])
        if not np.isfinite(np.asarray(a.angle_deg, float)).any():
            continue
        answered += 1
        flags = a.validity["flags"]
        flagged += FLAG in flags
        if FLAG in flags:
            onset = abs(a.validity["high_stretch_from_deg"])
            assert onset <= np.nanmax(np.abs(np.asarray(a.angle_deg, float))) + 1e-9
            assert a.validity["high_stretch_from_pa"] <= 1.02 * end_pa
            assert f"stretch passes {HAZARD_STRETCH:g}" in " ".join(a.validity["messages"])
    assert answered >= 10
    assert flagged >= answered - 2, (flagged, answered)


def test_the_onset_comes_before_the_fe_failure(emulator, newton_failed_pdms):
    """Where the FE's own membrane stretch passed HAZARD_STRETCH before it failed, the
    emulated onset is within 15 deg of where the FE's did, and mostly before the end."""
    before = n = 0
    for design, c in newton_failed_pdms:
        if not reached_hazard(c.max_membrane_stretch):
            continue
        fe_onset = float(np.abs(c.angle_deg)[np.argmax(c.max_membrane_stretch
                                                        >= HAZARD_STRETCH)])
        try:
            cb = _curve(emulator, design)
        except InputError:
            continue
        n += 1
        before += cb.stretch_onset_deg <= abs(c.angle_deg[-1])
        assert abs(cb.stretch_onset_deg - fe_onset) < 15.0, (design, fe_onset)
    assert n >= 10 and before >= 0.8 * n


def test_a_design_far_below_the_stretch_is_not_flagged(emulator):
    """The standard design: its stretch stays near 5.5 at 90 deg; no flag anywhere, by
    pressure, by volume or backwards."""
    d = Design().validated()
    assert np.isinf(_curve(emulator, d).stretch_onset_deg)
    for answer in (emulator.predict(d, np.linspace(0, 2500, 30)),
                   emulator.predict_volume(d, np.linspace(0, 100, 30)),
                   emulator.inverse(d, [10.0, 80.0])):
        assert FLAG not in answer.validity["flags"]
        assert "high_stretch_from_deg" not in answer.validity


def test_every_axis_flags_the_same_onset(emulator):
    """A design whose emulated stretch passes the hazard below the end of its range:
    flagged by pressure, by volume and backwards at an angle above the onset, not below."""
    d = Design(L_mm=7.1, t_mm=0.5, T_mm=1.5, b_mm=2.0, h_mm=0.2).validated()
    cb = _curve(emulator, d)
    onset = cb.stretch_onset_deg
    assert 20.0 < onset < cb.limit_angle_deg - 1.0
    below, above = onset - 5.0, 0.5 * (onset + cb.limit_angle_deg)
    assert FLAG not in emulator.inverse(d, [below]).validity["flags"]
    inv = emulator.inverse(d, [below, above])
    assert FLAG in inv.validity["flags"]
    assert FLAG in emulator.predict(d, [float(inv.pressure_pa[1])]).validity["flags"]
    assert FLAG not in emulator.predict(d, [float(inv.pressure_pa[0])]).validity["flags"]
    by_volume = emulator.predict_volume(d, [float(inv.volume_ul[1])])
    assert FLAG in by_volume.validity["flags"]
    assert by_volume.validity["high_stretch_from_deg"] == pytest.approx(onset)
    assert FLAG not in emulator.predict_volume(d, [float(inv.volume_ul[0])]).validity["flags"]


def test_the_hazard_is_stored_older_files_read_without_it_and_damage_is_refused(emulator,
                                                                                no_curve_gps):
    key = next(k for k, pe in emulator.pairs.items() if k.startswith("pdms"))
    pe = emulator.pairs[key]
    d = emulator_to_dict(emulator)
    d.pop(KEY, None)
    d["pairs"] = [p for p in d["pairs"] if p["pair"] == key]    # one pair: a faster load
    back = emulator_from_dict(d, "other.json").pairs[key]
    u = pe.coordinates[:3]
    assert [back.stretch_hazard.onset_deg(x) for x in u] == \
        [pe.stretch_hazard.onset_deg(x) for x in u]
    assert (back.stretch_hazard.reached, back.stretch_hazard.failed) == \
        (pe.stretch_hazard.reached, pe.stretch_hazard.failed) != (0, 0)

    stored = d["pairs"][0].pop("stretch_hazard")
    d["format_version"] = 15
    assert emulator_from_dict(d, "old.json").pairs[key].stretch_hazard is None
    d["format_version"] = FORMAT_VERSION
    for field, value in (("reached", -1), ("failed", stored["reached"] + 1),
                         ("reached", "x"), ("nodes_deg", [5.0, 90.0]),
                         ("hazard_stretch", 6.0), ("model", None)):
        d["pairs"][0]["stretch_hazard"] = {**stored, field: value}
        # refused before the pair's curve GPs are factorised
        with no_curve_gps(), pytest.raises(SurrogateFileError, match="damaged emulator file"):
            emulator_from_dict(d, "other.json")


def test_the_flag_and_where_it_starts_reach_the_http_answer(shipped_client):
    """POST /v1/predict and /v1/inverse/pressure carry the flag, its message and
    high_stretch_from_deg / _pa (the Validity schema keeps them)."""
    design = {"L_mm": 7.1, "t_mm": 0.5, "T_mm": 1.5, "b_mm": 2.0, "h_mm": 0.2}
    inv = shipped_client.post("/v1/inverse/pressure", json={"design": design,
                                                   "angles_deg": [20.0, 58.0]})
    assert inv.status_code == 200, inv.text
    v = inv.json()["validity"]
    assert FLAG in v["flags"] and 20.0 < v["high_stretch_from_deg"] < 58.0
    p_above = inv.json()["pressure_pa"][1]
    r = shipped_client.post("/v1/predict", json={"design": design,
                                                 "pressures_pa": [100.0, p_above]})
    assert r.status_code == 200, r.text
    v = r.json()["validity"]
    assert FLAG in v["flags"]
    assert v["high_stretch_from_pa"] == pytest.approx(
        inv.json()["validity"]["high_stretch_from_pa"])
    assert any("stretch passes 7" in m for m in v["messages"])


def test_the_design_search_names_the_listed_designs_past_their_stretch_onset(emulator):
    """A design search whose listed designs include one that reaches the target past its
    emulated stretch onset (80 deg at 3000 Pa, thick PDMS 1:10 bodies) says which ranks
    do, in its explanation; the ranking itself is unchanged (a flag, not a cut)."""
    from surrogate.search.design_search import SearchBounds, search_designs
    from surrogate.search.design_target import DesignTarget

    res = search_designs(emulator, DesignTarget("angle_at_pressure", 3000.0, angle_deg=80.0),
                         SearchBounds(T_mm=(1.8, 2.0), pairs=(("pdms_1_10", "ecoflex_00_30"),)),
                         n_results=5)
    flagged = [c.rank for c in res.candidates if FLAG in c.curve.validity["flags"]]
    assert flagged and len(flagged) < len(res.candidates), flagged
    said = f"rank{'s' if len(flagged) > 1 else ''} {', '.join(map(str, flagged))} reach"
    assert said in res.explanation, res.explanation
    assert "an FE solve (POST /v1/solve)" in res.explanation
