"""Headers with units, as labs write them (``Pressure (kPa)``, ``Angle [°]``, ``t [min]``):
read as the canonical columns, the values converted once, the reading said in the report;
an unknown unit, a unitless quantity and two headers of one column refused naming the
header (docs/measured-data.md, "Headers with units")."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from fastapi.testclient import TestClient
from service_fakes import assert_problem, settings_for

from service.app import create_app
from surrogate.calibration import DataError, load_observations, observations_from_rows


def rows(n_curves: int = 2, n: int = 5) -> list[dict]:
    """Canonical rows: two curves of 5 readings with time, flow and force."""
    return [{"curve_id": f"s{c}", "L_mm": 7.1, "t_mm": 0.5, "body_material": "pdms_1_10",
             "membrane_material": "ecoflex_00_30", "pressure_pa": 300.0 * i,
             "angle_deg": 2.0 * i + c, "time_s": 2.0 * i, "flow_ul_s": 1.25,
             "force_mn": 0.5 * i}
            for c in range(n_curves) for i in range(n)]


def relabel(data: list[dict], column: str, header: str, factor: float) -> list[dict]:
    """``data`` with ``column`` named ``header`` and its values in the header's unit."""
    return [{(header if k == column else k): (v / factor if k == column else v)
             for k, v in r.items()} for r in data]


def csv_text(data: list[dict], sep: str = ",") -> str:
    cols = list(data[0])
    return "\n".join([sep.join(cols)] + [sep.join(str(r[c]) for c in cols) for r in data])


# (header, canonical column, factor to the canonical unit): the brief's list and more
HEADERS = [
    ("Pressure (kPa)", "pressure_pa", 1000.0), ("Pressure [mbar]", "pressure_pa", 100.0),
    ("p / psi", "pressure_pa", 6894.757293168361), ("p_mbar", "pressure_pa", 100.0),
    ("Druck [kPa]", "pressure_pa", 1000.0), ("P (mmHg)", "pressure_pa", 133.322387415),
    ("Angle (deg)", "angle_deg", 1.0), ("Angle [°]", "angle_deg", 1.0),
    ("theta (rad)", "angle_deg", 180.0 / math.pi), ("Bending angle [deg]", "angle_deg", 1.0),
    ("Time (s)", "time_s", 1.0), ("t [min]", "time_s", 60.0), ("t (ms)", "time_s", 1e-3),
    ("Force (mN)", "force_mn", 1.0), ("Force [N]", "force_mn", 1000.0),
    ("Tip force (gf)", "force_mn", 9.80665),
    ("Flow (ul/s)", "flow_ul_s", 1.0), ("Flow rate [µl/s]", "flow_ul_s", 1.0),
    ("Flow (ml/min)", "flow_ul_s", 1000.0 / 60.0), ("Q [ml/h]", "flow_ul_s", 1000.0 / 3600.0),
    ("Flow_ul_min", "flow_ul_s", 1.0 / 60.0),
    # a German lab's export beside Druck, Zeit and Winkel (until 2026-12-07 "unknown column")
    ("Fluss [µl/min]", "flow_ul_s", 1.0 / 60.0),
    ("Durchfluss (ml/h)", "flow_ul_s", 1000.0 / 3600.0),
]


@pytest.mark.parametrize("header, column, factor", HEADERS)
def test_a_header_with_a_unit_is_read_as_its_column_in_its_unit(tmp_path, header, column,
                                                                 factor):
    """Each was "required column is missing (found ...: the column must be named
    exactly ...)" or "unknown column": now the values are converted once and the report
    says how the header was read."""
    plain = load_observations(_write(tmp_path / "plain.csv", csv_text(rows())))
    path = _write(tmp_path / "lab.csv", csv_text(relabel(rows(), column, header, factor)))
    obs = load_observations(path)
    np.testing.assert_allclose(getattr(obs, column), getattr(plain, column), rtol=1e-12,
                               atol=1e-12)
    assert [r.words() for r in obs.columns_read] == [
        f"`{header}` read as {column} x {factor:.6g}"]
    assert plain.columns_read == ()


def test_exact_names_read_as_before_and_say_nothing(tmp_path):
    obs = load_observations(_write(tmp_path / "plain.csv", csv_text(rows())))
    again = observations_from_rows(rows())
    assert obs.sha256 == again.sha256 and obs.columns_read == ()


def test_a_converted_file_has_the_canonical_files_hash(tmp_path):
    """The hash is of the rows as read (canonical units): a file written in kPa and one in
    Pa of the same readings are one data set."""
    data = rows()
    kpa = relabel(data, "pressure_pa", "Pressure (kPa)", 1000.0)
    assert observations_from_rows(kpa).sha256 == observations_from_rows(data).sha256


def test_a_german_excel_file_with_units_reads_its_decimal_commas(tmp_path):
    """';' between fields, ',' as the decimal mark: a converted column's cells are numbers
    too ('0,3' kPa is 300 Pa)."""
    data = relabel(rows(), "pressure_pa", "Druck [kPa]", 1000.0)
    text = csv_text(data, sep=";").replace(".", ",")
    obs = load_observations(_write(tmp_path / "de.csv", text))
    assert obs.pressure_pa.max() == pytest.approx(1200.0)


@pytest.mark.parametrize("header, words", [
    ("Pressure (atm?)", "'atm?' is not a unit of pressure"),
    ("Angle (grad)", "'grad' is not a unit of angle"),
    ("Pressure (s)", "'s' is not a unit of pressure"),
    ("Pressure", "no unit is given for pressure"),
])
def test_a_known_quantity_in_an_unknown_unit_is_refused_naming_the_units(tmp_path, header,
                                                                         words):
    column = "angle_deg" if header.startswith("Angle") else "pressure_pa"
    path = _write(tmp_path / "lab.csv", csv_text(relabel(rows(), column, header, 1.0)))
    with pytest.raises(DataError) as err:
        load_observations(path)
    text = str(err.value)
    assert err.value.column == header and words in text and "\n" not in text
    assert ("kpa" in text) if column == "pressure_pa" else ("rad" in text)


def test_two_headers_of_one_quantity_are_refused_naming_both():
    data = [{**r, "Pressure (kPa)": r["pressure_pa"] / 1000} for r in rows()]
    with pytest.raises(DataError) as err:
        observations_from_rows(data)
    assert "'pressure_pa' and 'Pressure (kPa)' are both read as pressure_pa" in str(err.value)


@pytest.mark.parametrize("header, factor", [("Volume (uL)", 1.0), ("V [ml]", 1000.0),
                                            ("volume_mm^3", 1.0), ("Injected volume (nl)",
                                                                   1e-3), ("vol / cc", 1000.0),
                                            ("Volumen (ml)", 1000.0)])
def test_an_injected_volume_column_is_read_in_its_unit(header, factor):
    """A pump's dispensed volume (until 2026-12-07 refused: "an injected-volume column is
    not read") is volume_ul, converted once (docs/measured-data.md)."""
    data = relabel([{**r, "volume_ul": 1.25 * r["time_s"]} for r in rows()], "volume_ul",
                   header, factor)
    obs = observations_from_rows(data)
    assert obs.columns_read[0].column == "volume_ul" and obs.columns_read[0].factor == factor
    np.testing.assert_allclose(obs.measured_volume_ul, 1.25 * obs.time_s)


def test_a_converted_cell_out_of_range_is_named_by_its_header():
    data = relabel(rows(), "pressure_pa", "Pressure (kPa)", 1000.0)
    data[3]["Pressure (kPa)"] = 5000.0            # 5 MPa
    with pytest.raises(DataError) as err:
        observations_from_rows(data)
    assert err.value.column == "Pressure (kPa)" and err.value.row == 4
    assert "read as pressure_pa x 1000" in str(err.value)
    assert "<= pressure_pa <= 1e+06" in str(err.value)


def test_http_names_the_header_as_sent(tmp_path):
    """Over HTTP the rows' keys are the file's headers (the explorer page sends them as
    read): a refused header is the problem's field, a read one is said in the report."""
    app = create_app(settings_for(tmp_path), load_surrogate=False)
    data = relabel(rows(), "angle_deg", "Angle (grad)", 1.0)
    from test_calibration_service import measured_rows

    kpa = relabel(measured_rows(), "pressure_pa", "Pressure (kPa)", 1000.0)
    with TestClient(app) as client:
        r = client.post("/v1/calibrate", json={"rows": data, "model": "paper"})
        ok = client.post("/v1/calibrate", json={"rows": kpa, "model": "paper"})
    body = assert_problem(r, 422)
    assert body["errors"][0]["field"] == "rows.Angle (grad)"
    assert "not a unit of angle" in body["detail"]
    assert ok.status_code == 200, ok.text
    assert ok.json()["data"]["columns_read"][0]["reading"] == (
        "`Pressure (kPa)` read as pressure_pa x 1000")


def _write(path, text: str):
    path.write_text(text, encoding="utf-8")
    return path


def test_the_json_rows_and_the_csv_read_alike(tmp_path):
    data = relabel(rows(), "pressure_pa", "Pressure (kPa)", 1000.0)
    a = load_observations(_write(tmp_path / "lab.csv", csv_text(data)))
    b = load_observations(_write(tmp_path / "lab.json", json.dumps({"rows": data})))
    assert a.sha256 == b.sha256 and a.columns_read == b.columns_read


def test_the_cli_converts_and_says_how_it_read_each_header(tmp_path, capsys):
    """``balloon calibrate`` on a file in kPa and minutes: the report's data and its
    interpretation (printed) say how the headers were read."""
    from test_calibration_service import main, measured_rows

    data = [{**r, "time_s": r["time_s"] / 60.0} for r in measured_rows()]
    data = relabel(relabel(data, "pressure_pa", "Pressure (kPa)", 1000.0), "time_s",
                   "t [min]", 60.0)
    path = _write(tmp_path / "lab.csv", csv_text(data))
    code = main(["calibrate", str(path), "--report", str(tmp_path / "r.json"), "--model",
                 "paper"])
    assert code == 0
    report = json.loads((tmp_path / "r.json").read_text())
    assert [r["reading"] for r in report["data"]["columns_read"]] == [
        "`Pressure (kPa)` read as pressure_pa x 1000", "`t [min]` read as time_s x 60"]
    assert "`Pressure (kPa)` read as pressure_pa x 1000" in capsys.readouterr().out


@pytest.mark.timeout(10)
@pytest.mark.parametrize("key", ["p" + " " * 10_000 + "(kPa)", "p_" * 5_000])
def test_a_huge_key_is_an_unknown_column_said_short_and_fast(key):
    """Every split of a 10,000-character key read as a header took 0.4-0.6 s (a stray
    key over HTTP, many of them): a key beyond 100 characters names no quantity."""
    data = [{**r, key: 1} for r in rows()]
    with pytest.raises(DataError) as err:
        observations_from_rows(data)
    assert "unknown column" in str(err.value) and len(str(err.value)) < 400


def test_a_huge_header_in_place_of_a_missing_column_is_said_short():
    """A 5000-character header that looks like the missing pressure column ('Pressure
    (kkk...Pa)') was echoed whole in the refusal (5258 characters over HTTP and the CLI);
    it is shown cut, with its length."""
    header = "Pressure (" + "k" * 5000 + "Pa)"
    data = [{(header if k == "pressure_pa" else k): v for k, v in r.items()} for r in rows()]
    with pytest.raises(DataError) as err:
        observations_from_rows(data)
    text = str(err.value)
    assert "pressure_pa" in text and "characters" in text and len(text) < 400, text[:500]
