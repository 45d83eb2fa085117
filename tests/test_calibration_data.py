"""Measured-data contract (docs/measured-data.md): errors name the row and the column,
and nothing is half-loaded."""

from __future__ import annotations

import json

import pytest

from solver.errors import InputError
from surrogate.calibration import DataError, load_observations, observations_from_rows


def rows(n_curves: int = 2, n: int = 5) -> list[dict]:
    out = []
    for c in range(n_curves):
        for i in range(n):
            out.append({"curve_id": f"s{c}", "L_mm": "7.1", "t_mm": "0.5",
                        "body_material": "pdms_1_10", "membrane_material": "ecoflex_00_30",
                        "pressure_pa": str(300.0 * i), "angle_deg": str(2.0 * i)})
    return out


def csv_text(data: list[dict]) -> str:
    cols = list(data[0])
    return "\n".join([",".join(cols)] + [",".join(str(r[c]) for c in cols) for r in data])


def test_good_rows_load_with_defaults():
    obs = observations_from_rows(rows())
    assert obs.n == 10 and obs.n_curves == 2
    assert obs.families == (("pdms_1_10", "ecoflex_00_30", 1.0, 1.8, 0.15),)  # Table 3
    assert not obs.has_time and not obs.has_flow


def test_csv_and_json_files_give_the_same_data(tmp_path):
    data = rows()
    (tmp_path / "d.csv").write_text(csv_text(data))
    (tmp_path / "d.json").write_text(json.dumps({"rows": data}))
    a = load_observations(tmp_path / "d.csv")
    b = load_observations(tmp_path / "d.json")
    assert a.sha256 == b.sha256


@pytest.mark.parametrize("mutate, column, row", [
    (lambda d: [{k: v for k, v in r.items() if k != "angle_deg"} for r in d], "angle_deg",
     None),
    (lambda d: d[:3] + [{**d[3], "pressure_pa": "abc"}] + d[4:], "pressure_pa", 4),
    (lambda d: d[:6] + [{**d[6], "t_mm": "-0.5"}] + d[7:], "t_mm", 7),
    (lambda d: d[:1] + [{**d[1], "membrane_material": "rubber"}] + d[2:], "membrane_material",
     2),
    (lambda d: d + [{**d[0], "curve_id": "short"}], "curve_id", 11),
    (lambda d: d[:2] + [{**d[2], "L_mm": "9.1"}] + d[3:], "L_mm", 3),
    (lambda d: [{**r, "colour": "red"} for r in d], "colour", 1),
])
def test_bad_rows_name_row_and_column(mutate, column, row):
    with pytest.raises(DataError) as info:
        observations_from_rows(mutate(rows()))
    err = info.value
    assert isinstance(err, InputError)
    assert err.column == column and err.row == row
    assert column in str(err)
    if row is not None:
        assert f"row {row}" in str(err)


def test_time_column_must_be_complete():
    data = [{**r, "time_s": str(i % 5)} for i, r in enumerate(rows())]
    data[7]["time_s"] = ""
    with pytest.raises(DataError, match="row 8"):
        observations_from_rows(data)


def test_bad_file_is_not_half_loaded(tmp_path):
    data = rows()
    data[-1]["angle_deg"] = "nan?"
    path = tmp_path / "bad.csv"
    path.write_text(csv_text(data))
    with pytest.raises(DataError, match="row 10"):
        load_observations(path)
