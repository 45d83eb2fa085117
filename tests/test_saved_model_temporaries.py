"""A save killed between writing and publishing (kill -9 of the service) leaves its
temporary file in the models directory (``.m0.json.zxhhghv0.tmp``, perhaps 0 bytes, mode
0600); no half-written model is ever served, but nothing else removes them. The models
registry removes them when it opens the directory: only files of a save's own naming,
only older than a minute, so that a save in progress is never touched."""

from __future__ import annotations

import os
import time

from service_fakes import settings_for

from service.app import create_app

STALE_S = 120.0     # past the registry's minute (_saved.STALE_AFTER_S)

LEFT_BY_KILLED_SAVES = (".m0.json.zxhhghv0.tmp", ".m5.json.do7a0_uz.tmp",
                        ".lab-1.2.json._8mc_9m5.tmp")
NOT_OURS = (
    "m1.json",                       # a saved model
    ".notes.tmp",                    # not a save's name
    ".m0.json.zxhhghv.tmp",          # 7 characters, not mkstemp's 8
    ".m0.json.ZXHHGHV0.tmp",         # mkstemp's are lower case
    ".m0.json.zxhhghv0.tmp.bak",
    "m0.json.zxhhghv0.tmp",          # no leading dot
    ".emulator.json.zxhhghv0",       # no .tmp
)


def _make(folder, name: str, age_s: float, text: str = "{}") -> None:
    path = folder / name
    path.write_text(text)
    os.chmod(path, 0o600)
    then = time.time() - age_s
    os.utime(path, (then, then))


def test_the_registry_removes_stale_temporaries_of_saves_and_nothing_else(tmp_path):
    models = tmp_path / "models"
    models.mkdir()
    for name in LEFT_BY_KILLED_SAVES:
        _make(models, name, STALE_S, "" if ".m5." in name else '{"format"')
    for name in NOT_OURS:
        _make(models, name, 3600.0)
    _make(models, ".m9.json.abcdefgh.tmp", 1.0)    # a save in progress: young
    (models / ".m8.json.abcdefgh.tmp").mkdir()      # not a regular file
    os.utime(models / ".m8.json.abcdefgh.tmp", (0, 0))
    create_app(settings_for(tmp_path), load_surrogate=False)
    left = sorted(p.name for p in models.iterdir())
    assert left == sorted([*NOT_OURS, ".m9.json.abcdefgh.tmp", ".m8.json.abcdefgh.tmp"])


def test_removing_stale_temporaries_says_which_and_minds_a_missing_directory(tmp_path):
    from surrogate.calibration._saved import STALE_AFTER_S, remove_stale_temporaries

    assert STALE_AFTER_S == 60.0
    assert remove_stale_temporaries(tmp_path / "none") == []
    _make(tmp_path, ".lab1.json.k3j9x_2a.tmp", 61.0)
    _make(tmp_path, ".lab2.json.k3j9x_2a.tmp", 30.0)
    assert remove_stale_temporaries(tmp_path) == [".lab1.json.k3j9x_2a.tmp"]
    assert remove_stale_temporaries(tmp_path, older_than_s=10.0) == [
        ".lab2.json.k3j9x_2a.tmp"]
    assert list(tmp_path.iterdir()) == []
