"""The forty-second session's hostile-input audit (round two after tests/test_hostile_s41.py):
a compressed body, truthy words for a query's bool, locks an interrupted command left
behind, a FIFO where a file goes, a user's stop angle the FE landed beside, and what a
fresh probe of every route and command found.

Each test failed on the code before its fix (commit messages say which).
"""

from __future__ import annotations

import contextlib
import gzip
import os
import signal
import socket
import subprocess
import sys
import threading
from pathlib import Path

import pytest
from fastapi.testclient import TestClient
from service_fakes import PROBLEM, assert_problem, settings_for
from test_cli_fuzz import run, visible_lines
from test_precompute_job import ENV
from test_store import record_for

from service.app import create_app
from solver.store import CurveStore, StoreBusyError
from solver.store.locking import WriterLock


@pytest.fixture
def client(tmp_path):
    """The app over fakes (no model loaded): the HTTP plumbing, not the physics."""
    with TestClient(create_app(settings_for(tmp_path), load_surrogate=False)) as c:
        yield c


@pytest.mark.parametrize("coding", ["gzip", "deflate", "br", "gzip, identity"])
def test_a_compressed_body_is_a_415_naming_what_is_taken(client, coding):
    """A gzip-encoded body was read as JSON and refused 422 "cannot be parsed as JSON",
    which never said why. It is a 415 with ``Accept-Encoding: identity`` (RFC 9110
    15.5.16), never decoded (a decompression bomb would expand past the body limit)."""
    body = gzip.compress(b'{"design": {}, "pressures_pa": [1000]}')
    r = client.post("/v1/predict", content=body, headers={
        "Content-Type": "application/json", "Content-Encoding": coding})
    problem = assert_problem(r, 415, "Content-Encoding")
    assert r.headers["accept-encoding"] == "identity"
    assert problem["errors"][0]["allowed"] == "identity"
    assert "uncompressed" in problem["detail"]
    spec = client.get("/openapi.json").json()
    assert "415" in spec["paths"]["/v1/predict"]["post"]["responses"]


def test_an_identity_coding_or_a_bodyless_request_passes(client):
    """``Content-Encoding: identity`` is no coding; a GET with the header has no body."""
    r = client.post("/v1/predict", content=b'{"pressures_pa": [true]}', headers={
        "Content-Type": "application/json", "Content-Encoding": "identity"})
    assert_problem(r, 422, "pressures_pa.0")
    assert client.get("/v1/health", headers={"Content-Encoding": "gzip"}).status_code == 200


@pytest.mark.parametrize("word", ["yes", "on", "1", "0", "True", "off", "f", ""])
def test_a_query_bool_is_true_or_false_as_json_spells_them(client, word):
    """``/v1/predict/plot?inlet=yes`` (or on, 1, True, off, f) was read as a bool in
    pydantic's lax mode. A query's bool is spelt as a JSON body's is: exactly ``true`` or
    ``false``; anything else is a 422 naming the field and those two words."""
    r = client.get("/v1/predict/plot", params={"inlet": word, "flow_ul_s": 2.5,
                                               "model": "paper"})
    problem = assert_problem(r, 422, "inlet")
    (error,) = problem["errors"]
    assert error["allowed"] == "true or false" and repr(word) in error["message"], error
    assert r.headers["content-type"] == PROBLEM


@pytest.mark.parametrize("word", ["true", "false"])
def test_a_query_bool_takes_true_and_false(client, word):
    """Taken: the request reaches the model (the paper's, which answers by pressure only,
    refuses the flow rate: the plot's time axis)."""
    r = client.get("/v1/predict/plot", params={"inlet": word, "flow_ul_s": 2.5,
                                               "model": "paper"})
    assert [e["field"] for e in assert_problem(r, 422)["errors"]] == ["flow_ul_s"]


# -- 3. lock files: removed by their holder, a dead holder's recognised, a live one's kept --

def test_a_writer_removes_its_lock_file_when_it_lets_go(tmp_path):
    """Every command left ``<db>.lock`` (and precompute ``<db>.job.lock``) behind, so a
    user saw a "stale lock" after each interrupted run and was tempted to delete one that
    a live writer held. The holder removes it as it lets go; only a process killed
    outright leaves one, which blocks nothing."""
    db = tmp_path / "c.h5"
    with CurveStore(db, mode="a") as store:
        store.put(record_for(L_mm=7.1))
        assert (tmp_path / "c.h5.lock").exists()
    with CurveStore(db, mode="a", hold_lock=False) as store:
        store.put(record_for(L_mm=4.1))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.h5"]


LOCK_AND_DIE = """
import os, signal, sys
from solver.store.locking import WriterLock
lock = WriterLock(sys.argv[1])
lock.acquire()
os.kill(os.getpid(), signal.SIGKILL)
"""


def test_a_lock_left_by_a_killed_writer_blocks_nothing(tmp_path):
    """kill -9 leaves the lock file (with the dead writer's pid and host); the kernel has
    dropped its flock, so the next writer takes it at once and removes it after."""
    lock = tmp_path / "c.h5.lock"
    done = subprocess.run([sys.executable, "-c", LOCK_AND_DIE, str(lock)], env=ENV)
    assert done.returncode == -signal.SIGKILL
    assert lock.read_text().endswith(f"@{socket.gethostname()}")
    taker = WriterLock(lock)
    taker.acquire()          # no wait: the holder is dead
    assert lock.read_text() == f"{os.getpid()}@{socket.gethostname()}"
    taker.release()
    assert not lock.exists()


@pytest.fixture
def held_lock(tmp_path):
    """``c.h5.lock`` held by a live writer (this process, through a lock of its own)."""
    holder = WriterLock(tmp_path / "c.h5.lock")
    holder.acquire()
    yield holder
    holder.release()


def _refusal(held: WriterLock, stamp: str) -> str:
    held.path.write_text(stamp)      # what that holder's file says
    with pytest.raises(StoreBusyError) as caught:
        WriterLock(held.path).acquire()
    return str(caught.value)


def test_a_live_holder_on_another_host_is_named_with_its_host(held_lock):
    """The file held the pid alone: a writer on another host sharing the directory was
    told "pid 4242" of a process this host has not got. Now the pid and the host, what to
    do, and not to delete the file (its holder would write on beside the next)."""
    said = _refusal(held_lock, "4242@lab-node-7")
    assert "(pid 4242 on host lab-node-7): wait for it to finish or stop it there" in said
    assert "do not delete c.h5.lock" in said
    assert held_lock.held and held_lock.path.exists()   # never stolen


def test_a_holder_whose_pid_has_ended_is_said_to_have_ended(held_lock):
    """A pid of this host that has ended while its lock is held: a process it started
    holds the lock (a fork kept the descriptor); "wait for pid N" could never end."""
    ended = subprocess.Popen(["true"])
    ended.wait()
    said = _refusal(held_lock, f"{ended.pid}@{socket.gethostname()}")
    assert f"(pid {ended.pid}): it has ended, but a process it started holds" in said
    assert held_lock.held


def test_a_waiter_never_shares_the_lock_with_the_next_writer(tmp_path):
    """The holder removes its file as it lets go: a waiter that had opened that file
    then locks a file no longer at the path, while a third writer creates and locks a new
    one. The waiter checks that its file is still the lock's and, if not, locks the one
    there (busy, here), never holding a lock beside another writer's."""
    path = tmp_path / "c.h5.lock"
    first = WriterLock(path)
    first.acquire()
    stale = os.open(path, os.O_RDWR)           # the waiter's open, before the release
    first.release()
    third = WriterLock(path)
    third.acquire()
    waiter = WriterLock(path)
    opened = [stale]
    waiter._open = lambda: opened.pop() if opened else WriterLock._open(waiter)
    with pytest.raises(StoreBusyError):
        waiter.acquire()
    assert not waiter.held and third.held
    third.release()


def test_a_solve_the_database_cannot_take_for_its_lock_is_parked_not_lost(tmp_path):
    """A service solve whose database's writer lock stayed held past the writer's wait
    (a user's script with ``CurveStore(db, "a")`` open) failed with "storing it failed:
    /full/path/curves.h5 is being written by another process": the finished result lost
    and the server's path sent to the client. It is parked, as precompute parks, named
    by the file's name only, and written by the next put."""
    from service.store_access import ResultParkedError, ResultWriter
    from solver.precompute.parking import parked_files

    db = tmp_path / "curves.h5"
    writer = ResultWriter(db, busy_wait_s=0.0)
    record = record_for(L_mm=9.1)
    with CurveStore(db, mode="a"), pytest.raises(ResultParkedError) as caught:
        writer(record.design, record.settings, record.curve)
    assert str(tmp_path) not in str(caught.value) and "curves.h5" in str(caught.value)
    assert len(parked_files(db)) == 1
    later = record_for(L_mm=4.1)
    writer(later.design, later.settings, later.curve)      # writes the parked one first
    with CurveStore(db) as store:
        assert len(store) == 2
    assert parked_files(db) == []


# -- 4. a FIFO, a device or a socket where an input file goes --------------------------

@contextlib.contextmanager
def fifo_unblocked_later(fifo: Path):
    """A named pipe that a late writer opens (and closes) after a while, so that a command
    which waits in ``open`` for a writer -- the code before the fix -- ends (reading an
    empty file) and its test fails instead of hanging; a command that never opens it for
    reading leaves the writer nothing to open."""
    os.mkfifo(fifo)
    stop = threading.Event()

    def late_writer() -> None:
        while not stop.wait(5.0):
            try:
                os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))
            except OSError:     # no reader: nobody waits
                pass

    thread = threading.Thread(target=late_writer, daemon=True)
    thread.start()
    try:
        yield fifo
    finally:
        stop.set()
        thread.join()


GRID_TOML = Path(__file__).resolve().parents[1] / "grids" / "default.toml"


@pytest.mark.parametrize("argv, option", [
    (["calibrate", "{f}", "--model", "paper", "--report", "{tmp}/r.md"], "file"),
    (["precompute", "{f}", "--db", "{tmp}/n.h5", "--dry-run"], "grid"),
    (["precompute", str(GRID_TOML), "--db", "{tmp}/n.h5", "--dry-run", "--adaptive", "2",
      "--emulator", "{f}"], "--emulator"),
])
def test_a_fifo_given_as_an_input_file_is_refused_at_once(tmp_path, argv, option):
    """``balloon calibrate FIFO`` and ``balloon precompute FIFO`` waited in ``open`` for a
    writer that never came: the command hung. A named pipe (as a device) is refused with
    one line naming the argument, as a directory is."""
    with fifo_unblocked_later(tmp_path / "data.fifo") as fifo:
        code, _, err, escaped = run([a.format(f=fifo, tmp=tmp_path) for a in argv])
    assert escaped is None and code == 2, err
    (line,) = visible_lines(err)
    assert line.startswith(f"balloon: error: {option}: ") and "not a regular file" in line, line
    assert "a regular file)" in line, line       # the allowed form


@pytest.mark.parametrize("device", ["/dev/null", "/dev/zero"])
def test_a_device_given_as_the_data_is_named_a_device(tmp_path, device):
    """/dev/null was "the file is empty", /dev/zero read 64 MiB of zeros first."""
    code, _, err, escaped = run(["calibrate", device, "--model", "paper", "--report",
                                 str(tmp_path / "r.md")])
    (line,) = visible_lines(err)
    assert escaped is None and code == 2 and "not a regular file" in line, line


# -- the fresh probe --------------------------------------------------------------------

def test_a_row_of_thousands_of_stray_keys_is_refused_at_the_columns(client):
    """One measured row with 200,000 stray keys (2.3 MB, inside the calibration's 4 MiB
    body) took the server 37 s of CPU to answer "L_mm: required column is missing": every
    key's header reading rebuilt the table of quantity names. More than 1,000 columns is
    refused first, naming ``columns`` and the bound; the table is made once."""
    row = {"curve_id": "a", **{f"c{i}": 1 for i in range(1001)}}   # docs/measured-data.md
    r = client.post("/v1/calibrate", json={"rows": [row], "model": "paper"})
    problem = assert_problem(r, 422, "rows.columns")
    assert problem["errors"][0]["allowed"] == "at most 1000 columns"


@pytest.mark.parametrize("path", ["/v1/curves/{}", "/v1/jobs/{}"])
def test_a_long_id_is_not_echoed_whole(tmp_path, path):
    """A 100,000-character record or job id (curl) came back whole in the 404's detail
    (with the path's own echo in ``instance``, 200 kB for a 100 kB request): a message
    never echoes a long input (the validation errors' rule, ``service.errors.short_input``)."""
    with CurveStore(tmp_path / "curves.h5", mode="a") as store:
        store.put(record_for(L_mm=7.1))
    with TestClient(create_app(settings_for(tmp_path), load_surrogate=False)) as c:
        r = c.get(path.format("a" * 60_000))      # (httpx takes URLs to 65,536)
    problem = assert_problem(r, 404)
    assert len(problem["detail"]) < 200 and "aaa..." in problem["detail"], problem["detail"][:300]


EXPORT_UNDER_A_SIZE_LIMIT = """
import resource, sys
from service.cli import main
resource.setrlimit(resource.RLIMIT_FSIZE, (int(sys.argv[1]), int(sys.argv[1])))
sys.exit(main(sys.argv[2:]))
"""


def test_an_export_the_disk_cannot_take_leaves_the_former_file(tmp_path):
    """A full disk (here a file-size limit, as ``ulimit -f``) in the middle of ``balloon
    db export`` left a truncated CSV in place of the former export and said only "File
    too large". The export is written beside it and renamed when whole: the former file
    stays, no temporary is left, and the one line names the file."""
    db = tmp_path / "c.h5"
    with CurveStore(db, mode="a") as store:
        store.put_many([record_for(L_mm=L) for L in (4.1, 7.1, 9.1, 11.1)])
    former = tmp_path / "out.csv"
    former.write_text("the former export\n")
    done = subprocess.run([sys.executable, "-c", EXPORT_UNDER_A_SIZE_LIMIT, "2048", "db",
                           "export", str(db), "--format", "csv", "-o", str(former)],
                          env=ENV, capture_output=True, text=True)
    assert done.returncode == 1, done.stderr
    assert done.stderr.strip().splitlines() == [f"balloon: error: {former}: File too large"]
    assert former.read_text() == "the former export\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.h5", "out.csv"]


def test_an_atomic_output_that_fails_names_the_target_and_keeps_the_former(tmp_path):
    from solver.atomic_file import atomic_output

    target = tmp_path / "curve.png"
    target.write_bytes(b"former")
    with pytest.raises(OSError) as caught, atomic_output(target, keep_suffix=True) as tmp:
        assert tmp.suffix == ".png" and tmp.parent == tmp_path
        tmp.write_bytes(b"half")
        raise OSError(27, "File too large", str(tmp))
    assert caught.value.filename == str(target)
    assert target.read_bytes() == b"former" and list(tmp_path.iterdir()) == [target]


def test_the_plots_refusal_of_a_pressure_only_model_offers_the_plots_own_terms():
    """`GET /v1/predict/plot?flow_ul_s=2.5&model=paper` was told "(allowed: pressures_pa;
    ...)", /v1/predict's field, which the plot's query does not have; it is offered the
    plot against pressure (p_max_pa, without flow_ul_s)."""
    with TestClient(create_app()) as c:
        r = c.get("/v1/predict/plot", params={"flow_ul_s": 2.5, "model": "paper"})
    assert_problem(r, 422)
    (err,) = r.json()["errors"]
    assert err["loc"] == ["query", "flow_ul_s"]
    assert "pressures_pa" not in err["allowed"] and "p_max_pa" in err["allowed"]


def test_an_app_built_without_start_up_loading_answers_by_the_exponential_model():
    """An app used in-process without its lifespan (a batch job's TestClient, no `with`)
    loaded the emulator on first use but answered model "exponential" with a 503 "no
    fitted surrogate is loaded (None)"; it is loaded on first use too."""
    c = TestClient(create_app())
    r = c.post("/v1/predict", json={"pressures_pa": [500, 1000], "model": "exponential"})
    assert r.status_code == 200, r.text
    assert all(a > 0 for a in r.json()["angle_deg"])


@pytest.mark.parametrize("word", ["1,,2", ",,500", "500,,", "100,200 300,,400"])
def test_an_empty_place_between_commas_is_refused_not_skipped(word):
    """`--pressures 1,,2` (a spreadsheet's empty cell) was read as 1, 2: the numbers after
    the gap moved up by one, silently. It is refused in one line naming the option."""
    code, _, err, escaped = run(["predict", "--model", "paper", "--L-mm", "7", "--t-mm",
                                 "0.6", "--pressures", *word.split()])
    assert escaped is None and code == 2
    (line,) = visible_lines(err)
    assert "--pressures" in line and "empty place between two commas" in line


def test_a_trailing_comma_is_still_read():
    code, out, _, _ = run(["predict", "--model", "paper", "--L-mm", "7", "--t-mm", "0.6",
                           "--pressures", "100,200,", "300"])
    assert code == 0 and "300.000" in out


def test_a_design_search_refusal_speaks_in_options():
    """`balloon inverse --kind angle_at_volume ... --pressure-pa 1500` said "leave
    pressure_pa out (the angle_at_volume target takes volume_ul)", the HTTP schema's
    names, under the label --pressure-pa; its words are the options now."""
    code, _, err, escaped = run(["inverse", "--kind", "angle_at_volume", "--volume-ul", "20",
                                 "--angle-deg", "45", "--pressure-pa", "1500"])
    assert escaped is None and code == 2
    (line,) = visible_lines(err)
    assert "leave --pressure-pa out" in line and "takes --volume-ul" in line
    assert "pressure_pa" not in line and "volume_ul" not in line


def test_a_saved_model_file_is_read_within_the_model_files_bound(tmp_path):
    """A saved calibrated model was read whole, however large (``Path.read_text``): a
    257 MiB file under a model's name was read into memory before it failed as "not valid
    JSON". It is refused at the model files' bound, by name, before it is read."""
    from surrogate.calibration._saved import SavedModelError, load_model
    from surrogate.model_file import MAX_MODEL_FILE_BYTES

    with open(tmp_path / "huge.json", "wb") as f:   # sparse: no disk is written
        f.truncate(MAX_MODEL_FILE_BYTES + 1)
    with pytest.raises(SavedModelError, match="larger than 256 MiB") as info:
        load_model("huge", tmp_path)
    assert str(tmp_path) not in str(info.value)
