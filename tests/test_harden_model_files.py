"""Model files validated on load, never a 500 or a wrong number inside a request: the
exponential surrogate (surrogate/exponential/file.py) and the emulator (surrogate/emulator/file.py).
A file this code writes carries a content checksum, so any later change is refused; a
file of older code (the shipped ones until refitted) is checked by its structure and a
trial prediction at its own data. Over HTTP: 503 naming the model, /v1/health degraded
naming the file; the CLI: one line."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import pytest
from fastapi.testclient import TestClient
from service_fakes import assert_problem, settings_for

from service.app import create_app
from service.cli import main
from surrogate import load_surrogate, save_surrogate
from surrogate.emulator.file import emulator_from_dict
from surrogate.errors import SurrogateFileError
from surrogate.file_seal import KEY

DATA = Path(__file__).resolve().parents[1] / "service" / "data"


@pytest.fixture(scope="module")
def surrogate_doc():
    doc = json.loads((DATA / "surrogate.json").read_text())
    doc.pop(KEY, None)  # as older code wrote it: only the structure and a trial check it
    return doc


@pytest.fixture(scope="module")
def emulator_doc():
    doc = json.loads((DATA / "emulator.json").read_text())
    doc.pop(KEY, None)
    return doc


def put(doc, path, value):
    """``doc`` with ``value`` at ``path`` (or the item deleted), ``doc`` unchanged: only
    the containers along the path are copied (a deep copy of the 30 MB emulator
    document took ~1.5 s a case)."""
    out = copy.copy(doc)
    target = out
    for k in path[:-1]:
        target[k] = copy.copy(target[k])
        target = target[k]
    if value is DELETE:
        del target[path[-1]]
    else:
        target[path[-1]] = value
    return out


DELETE = object()
EXP = ("families", 0, "parameters", "exponential")
SURROGATE_DAMAGE = {
    "default_form a list": (("families", 0, "default_form"), [1.0]),
    "domain end null": (("families", 0, "domain", "t_mm", 1), None),
    "value a string": ((*EXP, "values", 0), "x"),
    "value 1e308": ((*EXP, "values", 0), 1e308),
    "negative scatter": ((*EXP, "residual_sd"), -1.0),
    "covariance cut": ((*EXP, "covariance"), [[1.0]]),
    "name a boolean": ((*EXP, "names", 0), True),
    "no families": (("families",), []),
    "band scale 0": ((*EXP, "band_scale"), 0.0),
    "values missing": ((*EXP, "values"), DELETE),
}


@pytest.mark.parametrize("damage", SURROGATE_DAMAGE)
def test_a_damaged_surrogate_file_is_refused_on_load(surrogate_doc, tmp_path, damage):
    path = tmp_path / "surrogate.json"
    path.write_text(json.dumps(put(surrogate_doc, *SURROGATE_DAMAGE[damage])))
    with pytest.raises(SurrogateFileError, match="surrogate.json"):
        load_surrogate(path)


def test_any_change_to_a_sealed_surrogate_file_is_refused(tmp_path):
    s = load_surrogate(DATA / "surrogate.json")
    path = save_surrogate(s, tmp_path / "surrogate.json")
    doc = json.loads(path.read_text())
    assert KEY in doc
    assert load_surrogate(path).family_fits == s.family_fits  # unchanged: loads the same
    values = doc["families"][0]["parameters"]["exponential"]["values"]
    values[0] *= 1.01  # plausible, and wrong: only the checksum can tell
    path.write_text(json.dumps(doc))
    with pytest.raises(SurrogateFileError, match="content changed since it was written"):
        load_surrogate(path)


COVERAGE = ("report", "random_design_calibration", "group_coverage_after",
            "pdms/ecoflex_00_30+", "pressure", "far")
EMULATOR_DAMAGE = {
    "band scale a string": (("pairs", 0, "band_scale"), "x"),
    "band scales cut": (("pairs", 0, "band_scale"), [1.0, 2.0]),
    "a band scale negative": (("pairs", 0, "band_scale"), [1.0] * 40 + [-1.0] + [1.0] * 27),
    "sign 0.5": (("pairs", 0, "sign"), 0.5),
    "near-failed band scale below 1": (("pairs", 0, "near_failed_band_scale"),
                                       [1.0] * 63 + [0.5]),
    "near-failed band scales cut": (("pairs", 0, "near_failed_band_scale"), [2.0]),
    "lengths cut": (("pairs", 0, "curves", "gps", 0, "lengths"), [1.0]),
    "coordinates missing a row": (("pairs", 1, "coordinates", 0), DELETE),
    "centre null": (("pairs", 0, "curves", "center"), None),
    "group coverage a string": ((*COVERAGE, "coverage"), "x"),
    "group coverage above 1": ((*COVERAGE, "coverage"), 1.5),
    "group coverage points negative": ((*COVERAGE, "points"), -1),
}


@pytest.mark.parametrize("damage", EMULATOR_DAMAGE)
def test_a_damaged_emulator_file_is_refused_on_load(emulator_doc, damage):
    with pytest.raises(SurrogateFileError, match="emulator.json"):
        emulator_from_dict(put(emulator_doc, *EMULATOR_DAMAGE[damage]), "emulator.json")


def test_any_change_to_a_sealed_emulator_file_is_refused(emulator_doc):
    from surrogate.file_seal import seal

    doc = seal(emulator_doc)
    doc["pairs"][0]["curves"]["gps"][0]["lengths"][0] *= 1.01
    with pytest.raises(SurrogateFileError, match="content changed since it was written"):
        emulator_from_dict(doc, "emulator.json")


def test_a_canonical_file_is_checked_on_its_bytes_and_any_edit_is_refused():
    """The emulator is written as canonical JSON, so its checksum is checked on the bytes
    (no re-serialisation of 30 MB); an edit that keeps the checksum's member is refused,
    and a file in any other layout is checked on the canonical form of what it parses to."""
    from surrogate.file_seal import _raw_matches, canonical_text, check_seal, seal

    doc = seal({"format": "x", "pairs": [{"lengths": [0.5, 1.25]}], "z": "last"})
    raw = canonical_text(doc).encode()
    assert _raw_matches(raw, doc[KEY])
    check_seal(json.loads(raw), "emulator.json", raw)
    edited = raw.replace(b"1.25", b"1.35")
    assert not _raw_matches(edited, doc[KEY])
    with pytest.raises(SurrogateFileError, match="content changed since it was written"):
        check_seal(json.loads(edited), "emulator.json", edited)
    # another layout of the same document: not canonical bytes, accepted as parsed
    indented = json.dumps(doc, indent=2).encode()
    assert not _raw_matches(indented, doc[KEY])
    check_seal(json.loads(indented), "emulator.json", indented)
    # bytes that are canonical but not what was parsed cannot pass for it
    with pytest.raises(SurrogateFileError, match="content changed since it was written"):
        check_seal({**json.loads(raw), "z": "other"}, "emulator.json", edited)


def test_damaged_model_files_are_503_naming_the_model_and_degraded_health(
        tmp_path, surrogate_doc, emulator_doc):
    sur, emu = tmp_path / "surrogate.json", tmp_path / "emulator.json"
    sur.write_text(json.dumps(put(surrogate_doc, *SURROGATE_DAMAGE["negative scatter"])))
    emu.write_text(json.dumps(put(emulator_doc, *EMULATOR_DAMAGE["sign 0.5"])))
    app = create_app(settings_for(tmp_path, surrogate_path=sur, emulator_path=emu))
    with TestClient(app, raise_server_exceptions=False) as c:
        for model in ("emulator", "exponential"):
            for r in (c.post("/v1/predict", json={"design": {"L_mm": 7.1, "t_mm": 0.5},
                                                  "pressures_pa": [1000], "model": model}),
                      c.post("/v1/inverse/pressure", json={"design": {"L_mm": 7.1, "t_mm": 0.5},
                                                  "angles_deg": [20], "model": model})):
                body = assert_problem(r, 503)
                assert f'model "{model}"' in body["detail"], body
                assert str(tmp_path) not in r.text
        health = c.get("/v1/health").json()
        assert health["status"] == "degraded"
        assert "surrogate.json" in health["surrogate"]["error"]
        assert "emulator.json" in health["emulator"]["error"]
        assert str(tmp_path) not in json.dumps(health)
        r = c.post("/v1/predict", json={"design": {"L_mm": 7.1, "t_mm": 0.5},
                                        "pressures_pa": [1000], "model": "paper"})
        assert r.status_code == 200  # the other models still answer


def test_balloon_predict_with_a_damaged_surrogate_file_is_one_line(tmp_path, surrogate_doc,
                                                                   capsys):
    path = tmp_path / "surrogate.json"
    path.write_text(json.dumps(put(surrogate_doc, *SURROGATE_DAMAGE["value 1e308"])))
    code = main(["predict", "--L-mm", "7.1", "--t-mm", "0.5", "--pressures", "1000",
                 "--model", str(path)])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "surrogate.json" in err, err
    assert "Traceback" not in err


def test_a_loaded_emulator_is_reused_only_while_its_file_is_unchanged(tmp_path, emulator_doc):
    """load_emulator keeps what it built, keyed by the file's content: the same file gives
    the same object (an app per test does not refactorise ~600 GPs), and a file changed in
    place is read afresh, so a damaged replacement is refused, not masked by the cache."""
    from surrogate.emulator import load_emulator

    path = tmp_path / "emulator.json"
    path.write_bytes((DATA / "emulator.json").read_bytes())
    first = load_emulator(path)
    assert load_emulator(path) is first
    assert load_emulator(DATA / "emulator.json") is load_emulator(DATA / "emulator.json")
    path.write_text(json.dumps(put(emulator_doc, *EMULATOR_DAMAGE["sign 0.5"])))
    with pytest.raises(SurrogateFileError, match="emulator.json"):
        load_emulator(path)
