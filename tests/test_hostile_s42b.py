"""The forty-second session's hostile-input audit, round three (after
tests/test_hostile_s41.py and tests/test_hostile_s42.py): odd entries in the saved-models
directory, concurrent cancels of one FE job, the CLI's ``--where`` errors naming the
option, and what a fresh probe of the pump targets, the lock files and the explorer's
inverse form found.

Each test failed on the code before its fix (commit messages say which).
"""

from __future__ import annotations

import json
import os
import threading
import time

import pytest
from explorer_browser import LiveServer, open_explorer
from fastapi.testclient import TestClient
from service_fakes import assert_problem, fast_solve, settings_for, slow_solve
from test_cli_fuzz import run, visible_lines

from service.app import create_app
from service.errors import ConflictError
from service.jobs import JobManager
from solver.design import Design
from solver.settings import SolverSettings

SHIPPED_DB = "service/data/curves.h5"
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


def test_the_cli_says_a_fifo_under_a_models_name_is_one(tmp_path):
    """``balloon predict --model pipe`` with a FIFO there: one line, not "no saved model"."""
    _odd_entries(tmp_path / "models")
    # the option, not BALLOON_MODELS_DIR: the process's settings are read once and kept
    # (get_settings), so an earlier test in the same worker would hide the variable
    code, out, err, escaped = run(["predict", "--L-mm", "9.1", "--t-mm", "0.6",
                                   "--pressures", "1000", "--model", "pipe",
                                   "--models-dir", str(tmp_path / "models")])
    assert escaped is None and code not in (0, None)
    lines = visible_lines(err)
    assert len(lines) == 1 and "not a regular file" in lines[0], err


# -- 2. cancels of one running job ---------------------------------------------------------

def _running(jobs: JobManager, job_id: str) -> None:
    deadline = time.monotonic() + 60
    while jobs.get(job_id).progress.get("step", 0) < 1 and time.monotonic() < deadline:
        time.sleep(0.02)
    assert jobs.get(job_id).status == "running"


def test_of_three_concurrent_cancels_one_cancels_and_two_are_told_it_is_cancelled():
    """Three DELETEs of one running job all answered 200 (each waited and returned the
    cancelled job), while a DELETE after them answered 409 "already cancelled": the
    answer depended on timing. RFC 9110 9.2.2: DELETE is idempotent in its effect (the
    job ends cancelled, once), not in its answers; the one that cancelled it gets 200 with
    the job, the others 409 naming the status, as a later DELETE does."""
    jobs = JobManager(slow_solve, lambda *a: "c" * 32, workers=1, queue_size=1)
    jobs.start()
    try:
        job = jobs.submit(Design(), SolverSettings(), "k")
        _running(jobs, job.id)
        answers: list[object] = []

        def cancel() -> None:
            try:
                answers.append(jobs.cancel(job.id).status)
            except ConflictError as exc:
                answers.append(str(exc))

        threads = [threading.Thread(target=cancel) for _ in range(3)]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join(30)
        assert sorted(answers, key=str) == ["cancelled"] + [
            f"job {job.id} is already cancelled"] * 2, answers
        assert jobs.get(job.id).status == "cancelled"
    finally:
        jobs.shutdown()


def test_a_cancel_while_the_curve_is_stored_is_refused_and_the_curve_kept():
    """A DELETE that arrived while a finished solve's curve was being written waited for
    the write and answered 200 with the job "finished": a cancel that did not cancel. It
    is a 409 at once, the write goes on, and the job ends finished with its curve."""
    writing, release, written = threading.Event(), threading.Event(), []

    def slow_write(design, settings, curve):
        writing.set()
        release.wait(30)
        written.append(curve)
        return "c" * 32

    jobs = JobManager(fast_solve, slow_write, workers=1, queue_size=1)
    jobs.start()
    try:
        job = jobs.submit(Design(), SolverSettings(), "k")
        assert writing.wait(60)
        with pytest.raises(ConflictError, match="being stored"):
            jobs.cancel(job.id, wait_s=2.0)
        release.set()
        deadline = time.monotonic() + 30
        while jobs.get(job.id).active and time.monotonic() < deadline:
            time.sleep(0.02)
        done = jobs.get(job.id)
        assert done.status == "finished" and done.curve_id == "c" * 32 and len(written) == 1
        with pytest.raises(ConflictError, match="already finished"):
            jobs.cancel(job.id)
    finally:
        release.set()
        jobs.shutdown()


# -- 3. `balloon db ls --where` names the option -------------------------------------------

@pytest.mark.parametrize(("argv", "field"), [
    (["--where", "L_mm=nan"], "--where L_mm: "),
    (["--where", "status=bogus"], "--where status: "),
    (["--where", "nope=3"], "--where nope: "),
    (["--where", "L_mm=7.1", "L_mm=8"], "--where L_mm: given twice"),
    (["--status", "failed", "--where", "status=complete"], "--status: "),
])
@pytest.mark.parametrize("command", ["ls", "export"])
def test_a_bad_filter_is_named_by_the_option_typed(command, argv, field):
    """``--where L_mm=nan`` was refused as ``L_mm: ...`` (the store's name); a field
    given twice, or a status by both options, was read as its last value."""
    code, out, err, escaped = run(["db", command, SHIPPED_DB, *argv])
    assert escaped is None and code in (1, 2), (code, err)
    lines = visible_lines(err)
    assert len(lines) == 1 and f"balloon: error: {field}" in lines[0], err


# -- the fresh probe ---------------------------------------------------------------------

@pytest.mark.parametrize("extra", [
    ["--volume-ul", "20"], ["--time-s", "3"], ["--kind", "angle_at_volume"],
    ["--angle-deg", "40"], ["--pressure-pa", "1000"], ["--force-mn", "2"],
    ["--L-range", "5", "9"], ["--membrane-stiffness-range", "1", "1.2"],
    ["--pair", "pdms_1_10/ecoflex_00_30"], ["--objective", "compact"], ["-n", "3"]])
def test_one_designs_pressures_refuse_a_searchs_options(extra):
    """``balloon inverse --L-mm 9 --t-mm 0.6 --angles-deg 30 --volume-ul 20`` printed the
    pressures for 30 deg and dropped --volume-ul (and every other option of a design
    search: --time-s, --kind, the ranges, --pair, -n), though the search refuses one
    design's --L-mm the other way round."""
    code, out, err, escaped = run(["inverse", "--L-mm", "9", "--t-mm", "0.6",
                                   "--angles-deg", "30", "--model", "paper", *extra])
    assert escaped is None and code in (1, 2) and not out, (code, out)
    lines = visible_lines(err)
    flag = extra[0]
    assert len(lines) == 1 and lines[0].startswith(f"balloon: error: {flag}: "), err


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    """The app with the shipped models, served for the browser test (the ``watched``
    fixture's page opens on it)."""
    with LiveServer(tmp_path_factory.mktemp("explorer-s42b")) as live:
        yield live


@pytest.mark.timeout(300)
def test_the_search_form_never_reads_an_unreadable_number_as_empty(watched, server):
    """A number box the browser cannot read ("1e999": badInput) reads as "": the form sent
    the volume target as null (answered "got none" beside a filled box), a bound as the
    box's edge and the number of designs as 5, each silently. The text then went to the
    server, which refused it at its field; since the forty-fifth session the boxes are
    text boxes and the page names it out of range beside its box, sending nothing
    (tests/test_hostile_s45.py)."""
    page = open_explorer(watched, server.url)
    bodies: list = []
    page.on("request", lambda r: bodies.append(r.post_data_json)
            if r.url.endswith("/v1/inverse") and r.method == "POST" else None)
    page.select_option("#inv-kind", "angle_at_volume")
    for box, error in [("#inv-volume", "#err-inv-volume"), ("#inv-L-lo", "#err-inv-L"),
                       ("#inv-n", "#err-inv-n")]:
        page.fill("#inv-volume", "20")
        page.fill("#inv-L-lo", "")
        page.fill("#inv-n", "3")
        page.fill(box, "1e999")
        page.click("#inv-run")
        page.wait_for_selector(f"{error}:not([hidden])")
        assert bodies == []
        assert page.input_value(box) == "1e999"
        assert "1e999 is outside the allowed range" in page.inner_text(error)


def test_a_pump_searchs_json_is_json():
    """``balloon inverse --kind volume_budget ... --json`` printed ``NaN`` 57 times (a pump
    target's listed designs have no angle at a target pressure): no JSON reader but
    Python's takes it. Every quantity a design has none of is null."""
    code, out, err, escaped = run(["inverse", "--kind", "volume_budget", "--volume-ul", "20",
                                   "--angle-deg", "45", "-n", "2", "--pair",
                                   "pdms_1_10/ecoflex_00_30", "--json"])
    assert escaped is None and code == 0, err
    assert "NaN" not in out and "Infinity" not in out
    body = json.loads(out, parse_constant=lambda word: pytest.fail(f"{word} in the JSON"))
    first = body["candidates"][0]
    assert first["value_at_pressure"] is None and first["volume_needed_ul"] > 0
