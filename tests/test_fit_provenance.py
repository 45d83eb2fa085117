"""A fitted file says how to make it again (surrogate/fit_provenance.py): the shipped
emulator of 2026-12-05 named a commit whose code writes an older file format, no
solve or fit marked uncommitted code, and the exponential file kept the fitting
machine's path to its database."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

from solver.store import record
from surrogate.fit_provenance import database_entry, file_sha256

ROOT = Path(record.__file__).resolve().parents[2]


def _git(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True,
                          check=False)


@pytest.mark.skipif(_git("rev-parse", "HEAD").returncode != 0, reason="not a git checkout")
def test_the_commit_is_marked_dirty_exactly_when_the_code_differs_from_it():
    head = _git("rev-parse", "HEAD").stdout.strip()
    code_changed = bool(_git("status", "--porcelain", "--untracked-files=no", "--",
                             *record.CODE_PATHS).stdout.strip())
    record.git_commit.cache_clear()
    try:
        assert record.git_commit() == head + ("+dirty" if code_changed else "")
    finally:
        record.git_commit.cache_clear()


@pytest.mark.skipif(_git("rev-parse", "HEAD").returncode != 0, reason="not a git checkout")
def test_a_changed_code_file_marks_the_commit_dirty(monkeypatch):
    # as git would answer with solver/stepping.py edited
    real = subprocess.run

    def fake(cmd, *a, **k):
        if cmd[:2] == ["git", "status"]:
            return subprocess.CompletedProcess(cmd, 0, " M solver/stepping.py\n", "")
        return real(cmd, *a, **k)

    monkeypatch.setattr(record.subprocess, "run", fake)
    record.git_commit.cache_clear()
    try:
        assert record.git_commit().endswith("+dirty")
    finally:
        record.git_commit.cache_clear()


def test_a_database_is_recorded_by_name_count_and_checksum(tmp_path):
    db = tmp_path / "private" / "curves.h5"
    db.parent.mkdir()
    db.write_bytes(b"\x89HDF\r\n\x1a\n" + bytes(range(256)) * 10)
    entry = database_entry(db, 12)
    assert entry == {"name": "curves.h5", "records": 12, "sha256": file_sha256(db)}
    assert "private" not in str(entry)


def test_the_emulator_file_records_its_command_and_its_databases_checksums(tmp_path):
    from solver.store import CurveStore
    from surrogate.emulator.command import fit_provenance

    dbs = {}
    for name in ("small.h5", "cal.h5"):
        dbs[name] = tmp_path / "lab" / name
        dbs[name].parent.mkdir(exist_ok=True)
        with CurveStore(dbs[name], mode="a"):
            pass
    command = "balloon fit --db small.h5 -o s.json --emulator-output e.json"
    prov = fit_provenance(dbs["small.h5"], 24, "balloon precompute g.toml --db small.h5",
                          command, dbs["cal.h5"])
    assert prov["fit_command"] == command
    assert prov["database"] == {"name": "small.h5", "records": 24,
                                "sha256": file_sha256(dbs["small.h5"])}
    assert prov["band_calibration_database"] == {"name": "cal.h5", "records": 0,
                                                 "sha256": file_sha256(dbs["cal.h5"])}
    assert prov["git_commit"] == record.git_commit()
    assert "lab" not in str(prov)
