"""The forty-second session's hostile-input audit, round three (after
tests/test_hostile_s41.py and tests/test_hostile_s42.py): odd entries in the saved-models
directory, concurrent cancels of one FE job, the CLI's ``--where`` errors naming the
option, and what a fresh probe of the pump targets, the lock files and the explorer's
inverse form found.

Each test failed on the code before its fix (commit messages say which).
"""

from __future__ import annotations

import os

import pytest
from fastapi.testclient import TestClient
from service_fakes import assert_problem, settings_for
from test_cli_fuzz import run, visible_lines

from service.app import create_app

DESIGN = {"L_mm": 9.1, "t_mm": 0.6}


# -- 1. the saved-models directory's odd entries ------------------------------------------

def _odd_entries(models_dir):
    """A FIFO, a directory, a link out of the directory and a dangling link, each under a
    model's name; a link to a model file inside the directory is no oddity."""
    models_dir.mkdir(parents=True)
    os.mkfifo(models_dir / "pipe.json")
    (models_dir / "folder.json").mkdir()
    outside = models_dir.parent / "elsewhere.json"
    outside.write_text("{}")
    (models_dir / "away.json").symlink_to(outside)
    (models_dir / "gone.json").symlink_to(models_dir / "missing.json")
    (models_dir / "inside.json").write_text("{}")
    (models_dir / "alias.json").symlink_to(models_dir / "inside.json")


@pytest.mark.parametrize(("name", "kind"), [
    ("pipe", "not a regular file"), ("folder", "a directory"),
    ("away", "a symbolic link out of the models directory"),
    ("gone", "a symbolic link to nothing")])
def test_an_odd_entry_under_a_models_name_is_said_to_be_one(tmp_path, name, kind):
    """A FIFO or a directory under a model's name was answered 404 "no saved model", and
    a symbolic link was followed out of the directory (the server read and answered by
    any JSON file on its disk: 503 "not a calibrated model" for the file it read). Each is
    a 503 naming the entry's kind, never a path."""
    settings = settings_for(tmp_path)
    _odd_entries(settings.models_dir)
    with TestClient(create_app(settings, load_surrogate=False)) as client:
        r = client.post("/v1/predict", json={"design": DESIGN, "pressures_pa": [1000],
                                             "model": name})
    problem = assert_problem(r, 503)
    assert kind in problem["detail"] and repr(name) in problem["detail"]
    assert str(tmp_path) not in r.text


def test_a_link_to_a_model_inside_the_directory_is_read_through(tmp_path):
    """The check refuses no ordinary link: a link to a file inside the directory is read
    (here a malformed one, so the answer is the reader's own 503, not the link's)."""
    settings = settings_for(tmp_path)
    _odd_entries(settings.models_dir)
    with TestClient(create_app(settings, load_surrogate=False)) as client:
        r = client.post("/v1/predict", json={"design": DESIGN, "pressures_pa": [1000],
                                             "model": "alias"})
    assert "not a calibrated model" in assert_problem(r, 503)["detail"]


def test_the_cli_says_a_fifo_under_a_models_name_is_one(tmp_path, monkeypatch):
    """``balloon predict --model pipe`` with a FIFO there: one line, not "no saved model"."""
    _odd_entries(tmp_path / "models")
    monkeypatch.setenv("BALLOON_MODELS_DIR", str(tmp_path / "models"))
    code, out, err, escaped = run(["predict", "--L-mm", "9.1", "--t-mm", "0.6",
                                   "--pressures", "1000", "--model", "pipe"])
    assert escaped is None and code not in (0, None)
    lines = visible_lines(err)
    assert len(lines) == 1 and "not a regular file" in lines[0], err
