"""A measured injected volume (``volume_ul``: a syringe pump's dispensed volume) read
by the calibration (docs/measured-data.md, "A measured volume"; until 2026-12-07 every
file with such a column was refused). Data from the FE curves (tests/calibration_lab.py):
the lab's volume column is the pump's V(t) at each reading, rounded to 0.001 ul.

* with time_s and flow_ul_s too, a volume that agrees with the pump history changes
  nothing; one 10 % off on a curve is warned about, naming it, and used there;
* with the volume alone, the readings are placed by it: an angle offset is found as with
  time and flow, and the time effects are not identifiable ("record time_s");
* a bad volume column is one line naming it and what is allowed (CLI, HTTP).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from calibration_lab import FULL_LOOP, LOOP, Lab, Truth, _pump, emulator, fe, measure
from fastapi.testclient import TestClient
from service_fakes import assert_problem, settings_for

from service.app import create_app
from surrogate.calibration import DataError, observations_from_rows, run_calibration

TIME_EFFECTS = ("viscoelastic_creep", "pressure_relaxation", "chamber_leak", "gauge_drift",
                "line_compliance")


def with_volume(rows: list[dict], protocol, scale: dict[str, float] | None = None
                ) -> list[dict]:
    """``rows`` with the pump's own volume log (the generator's V(t) at each reading,
    ul, to 0.001 ul), multiplied by ``scale[curve_id]`` where given (a log that is off)."""
    out = []
    for r in rows:
        t, v, _, _ = _pump(protocol, r["flow_ul_s"], 1.0)
        k = int(np.searchsorted(t, r["time_s"] - 1e-9))
        out.append({**r, "volume_ul": round(float(v[k]) * (scale or {}).get(
            r["curve_id"], 1.0), 3)})
    return out


def volume_only(rows: list[dict]) -> list[dict]:
    """The rows of a lab that logs the pump's volume but neither time nor flow (in the
    order it took them)."""
    return [{k: v for k, v in r.items() if k not in ("time_s", "flow_ul_s")} for r in rows]


OFFSET_LAB = Lab(designs=fe.PERTURBED_BASES, protocol=FULL_LOOP)
OFFSET = Truth(offset_deg=2.0)


@pytest.fixture(scope="module")
def offset_reports() -> dict[str, dict]:
    """One calibration each: time and flow; time, flow and volume; volume alone."""
    plain = measure(OFFSET_LAB, OFFSET)
    both = with_volume(plain, FULL_LOOP)
    return {name: run_calibration(rows, emulator()).report
            for name, rows in (("plain", plain), ("both", both),
                               ("volume", volume_only(both)))}


def test_a_volume_column_that_agrees_with_the_pump_history_changes_nothing(offset_reports):
    plain, both = offset_reports["plain"], offset_reports["both"]
    assert both["data"]["has_volume_ul"] and not plain["data"]["has_volume_ul"]
    assert both["data"]["injected_volume"] == plain["data"]["injected_volume"] == (
        "pump history")
    assert both["data"]["volume_ul_used_for"] == []
    for r in (plain, both):
        del r["data"]["sha256"], r["data"]["has_volume_ul"]
    assert json.dumps(both, sort_keys=True, default=str) == json.dumps(
        plain, sort_keys=True, default=str)
    assert plain["selected_effects"] == ["angle_offset"]


def test_the_volume_alone_places_the_readings_and_finds_the_offset(offset_reports):
    r = offset_reports["volume"]
    assert r["data"]["injected_volume"] == "measured"
    assert r["pressure_channel"]["used"], r["pressure_channel"]
    assert r["selected_effects"] == ["angle_offset"]
    p = r["fitted"]["effects"]["offset_deg"]
    assert abs(p["value"] - 2.0) <= 3.0 * p["sd"] and p["sd"] < 0.5
    assert r["rmse_after_deg"] <= 1.3 * r["noise_floor_deg"]
    reasons = {c["effect"]: c for c in r["not_identifiable"]}
    for effect in TIME_EFFECTS:
        assert reasons[effect]["measure"] == "record time_s", reasons.get(effect)
    assert reasons["hydraulic_resistance"]["measure"] == "record flow_ul_s"


def test_the_volume_alone_reads_the_history_the_pump_ran():
    """Loading, hold and unloading from the volume's rises, stands and falls: the
    directions the readings with time give, and the same injected volumes."""
    rows = with_volume(measure(Lab(designs=fe.PERTURBED_BASES, protocol=LOOP,
                                   flows_ul_s=(1.25, 2.5))), LOOP)
    timed, alone = observations_from_rows(rows), observations_from_rows(volume_only(rows))
    np.testing.assert_array_equal(alone.direction, timed.direction)
    np.testing.assert_allclose(alone.volume_ul, timed.volume_ul, atol=1e-3)
    assert alone.has_volume and not alone.has_time and alone.switch_names == ()


def test_a_volume_log_ten_percent_off_on_one_curve_is_warned_and_used_there():
    rows = measure(Lab(designs=fe.PERTURBED_BASES, protocol=LOOP))
    off = rows[0]["curve_id"]
    obs = observations_from_rows(with_volume(rows, LOOP, {off: 1.1}))
    plain = observations_from_rows(rows)
    (warning,) = obs.warnings
    assert warning.startswith("volume_ul: ") and repr(off) in warning
    assert "+10 %" in warning and "1 curve(s)" in warning and "measured volume is used" \
        in warning
    mine = obs.curve == obs.curve_ids.index(off)
    np.testing.assert_allclose(obs.volume_ul[mine], 1.1 * plain.volume_ul[mine], atol=1e-3)
    np.testing.assert_array_equal(obs.volume_ul[~mine], plain.volume_ul[~mine])
    assert obs.volume_source == "pump history and measured"
    assert not np.any(obs.switch_after[mine]) and not np.any(obs.switch_at[mine])
    with pytest.raises(DataError, match=r"refused: strict"):
        observations_from_rows(with_volume(rows, LOOP, {off: 1.1}), strict=True)


def test_a_volume_within_a_pumps_accuracy_is_not_warned_about():
    rows = measure(Lab(designs=fe.PERTURBED_BASES, protocol=LOOP))
    obs = observations_from_rows(with_volume(rows, LOOP, {rows[0]["curve_id"]: 1.008}))
    assert obs.warnings == () and obs.volume_source == "pump history"


def small_rows() -> list[dict]:
    """Two curves of loading and unloading, the volume logged (no time, no flow)."""
    volumes = (2.5, 5.0, 7.5, 10.0, 7.5, 5.0)
    return [{"curve_id": f"c{c}", "L_mm": 7.1, "t_mm": 0.5, "body_material": "pdms_1_10",
             "membrane_material": "ecoflex_00_30", "pressure_pa": 100.0 * v,
             "angle_deg": 3.0 * v, "volume_ul": v} for c in range(2) for v in volumes]


def bad(column: str, row: int, value) -> list[dict]:
    rows = small_rows()
    rows[row - 1][column] = value
    return rows


BAD = {
    "negative": (bad("volume_ul", 3, -1.0), "volume_ul", "negative: -1"),
    "infinite": (bad("volume_ul", 3, "inf"), "volume_ul", "not a finite number"),
    "missing": (bad("volume_ul", 3, ""), "volume_ul", "missing value"),
    "a dip while loading": (bad("volume_ul", 2, 1.0), "volume_ul", "2.5, 1, 7.5 ul inside "
                            "a loading run"),
    "against the pump's log": ([{**r, "pump": "hold" if i == 3 else "load" if i < 4
                                 else "unload"} for i, r in enumerate(small_rows())],
                               "volume_ul", "moves from 7.5 to 10 ul where the pump column "
                               "logs 'hold'"),
    "a time unit": ([{("Volume (s)" if k == "volume_ul" else k): v for k, v in r.items()}
                     for r in small_rows()], "Volume (s)", "not a unit of volume"),
}


@pytest.mark.parametrize("case", list(BAD))
def test_a_bad_volume_column_is_one_line_naming_it_and_what_is_allowed(case):
    rows, column, words = BAD[case]
    with pytest.raises(DataError) as err:
        observations_from_rows(rows)
    text = str(err.value)
    assert err.value.column == column and words in text and "\n" not in text
    assert "allowed" in text


def test_the_cli_says_a_bad_volume_column_in_one_line(tmp_path, capsys):
    from test_calibration_service import main

    rows = BAD["a dip while loading"][0]
    cols = list(rows[0])
    path = tmp_path / "lab.csv"
    path.write_text("\n".join([",".join(cols)] + [",".join(str(r[c]) for c in cols)
                                                  for r in rows]))
    assert main(["calibrate", str(path), "--report", str(tmp_path / "r.json")]) != 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("balloon: error: volume_ul: row 2:"), err
    assert "Traceback" not in err[0] and str(tmp_path) not in err[0]


def test_http_refuses_a_bad_volume_column_as_a_problem_and_reads_a_good_one(tmp_path):
    from test_calibration_service import measured_rows

    app = create_app(settings_for(tmp_path), load_surrogate=False)
    good = [{**r, "V [ml]": round(2.5 * r["time_s"] / 1000, 6)} for r in measured_rows()]
    dip = [dict(r) for r in good]
    dip[2]["V [ml]"] = 0.0001
    with TestClient(app) as client:
        refused = client.post("/v1/calibrate", json={"rows": dip, "model": "paper"})
        negative = client.post("/v1/calibrate", json={"rows": bad("volume_ul", 3, -1.0),
                                                      "model": "paper"})
        ok = client.post("/v1/calibrate", json={"rows": good, "model": "paper"})
    body = assert_problem(refused, 422, "rows.2.V [ml]")
    assert "inside a loading run" in body["detail"]
    assert_problem(negative, 422)
    assert ok.status_code == 200, ok.text
    assert ok.json()["data"]["columns_read"][0]["reading"] == "`V [ml]` read as volume_ul x 1000"
    assert ok.json()["data"]["injected_volume"] == "pump history"


def test_a_flow_of_zero_beside_a_measured_volume_is_refused():
    """A curve timed at flow 0 but with a rising measured volume: taken until 2026-12-07
    (the volume said what was injected, the two said to disagree); a flow of 0 is now
    refused wherever it stands, with the pump's range: leave the column out, and the
    measured volume places the readings."""
    rows = [{**r, "time_s": float(i), "flow_ul_s": 0.0}
            for i, r in enumerate(small_rows()[:4])]
    with pytest.raises(DataError) as err:
        observations_from_rows(rows)
    assert err.value.column == "flow_ul_s" and "1e-06 <= flow_ul_s" in str(err.value)
