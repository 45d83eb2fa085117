"""The store across real processes: a reader looping while a writer adds records, and
writers killed with SIGKILL at random moments (the file stays readable, every record
whose put returned is kept, and every record present is whole)."""

import json
import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

from solver.store import CurveStore

HERE = Path(__file__).resolve().parent
ENV = {**os.environ, "PYTHONPATH": os.pathsep.join([str(HERE), str(HERE.parent)])}

COMMON = """
import json, sys, time
import numpy as np
from solver.design import Design
from solver.settings import SolverSettings
from solver.store import CurveStore, make_record, record_key
from test_precompute_fakes import fake_curve
SETTINGS = SolverSettings(mesh_level=0, element="hex1")
def record(i):
    d = Design(L_mm=round(4.0 + 0.01 * i, 4)).validated()
    return make_record(d, SETTINGS, fake_curve(d))
def check(db, key):
    r = db.get(key)
    assert r.key == key == record_key(r.design, r.settings), key
    expected = fake_curve(r.design)
    for name in expected.ARRAY_FIELDS:
        np.testing.assert_array_equal(getattr(r.curve, name), getattr(expected, name))
"""

WRITER = COMMON + """
path, start, n = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
with CurveStore(path, mode="a") as db:
    for i in range(start, start + n):
        r = record(i)
        db.put(r)
        print(r.key, flush=True)
"""

READER = COMMON + """
path, wanted, timeout = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
seen, errors, reads, end = [], [], 0, time.monotonic() + timeout
long_lived = CurveStore(path)
while time.monotonic() < end:
    try:
        db = long_lived if reads % 2 else CurveStore(path)  # alternate: kept open / fresh
        keys = db.keys()
        for key in keys:
            check(db, key)
        reads += 1
        if db is not long_lived:
            db.close()
        if not seen or len(keys) != seen[-1]:
            seen.append(len(keys))
        if len(keys) >= wanted:
            break
    except Exception as exc:
        errors.append(f"{type(exc).__name__}: {exc}")
print(json.dumps({"seen": seen, "errors": errors[:5], "reads": reads}))
"""


def start(script: str, *args: object) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-c", script, *map(str, args)], env=ENV,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)


def test_reader_loops_while_a_writer_adds_records(tmp_path):
    path = tmp_path / "curves.h5"
    CurveStore(path, mode="a").close()  # an empty database for the reader to open
    n = 40
    reader = start(READER, path, n, 60)
    time.sleep(1.0)  # let the reader import and start looping
    writer = start(WRITER, path, 0, n)
    out, err = writer.communicate(timeout=60)
    assert writer.returncode == 0, err
    assert len(out.split()) == n
    report, err = reader.communicate(timeout=90)
    assert reader.returncode == 0, err
    result = json.loads(report)
    assert result["errors"] == []
    assert result["seen"][-1] == n
    assert result["seen"] == sorted(result["seen"])  # never saw a record disappear
    # the reader saw intermediate versions, i.e. it really ran during the writes
    assert len(result["seen"]) >= 3, result


def test_kill_9_during_puts_keeps_the_file_and_every_finished_record(tmp_path):
    path = tmp_path / "curves.h5"
    rng = random.Random(20240607)
    confirmed: list[str] = []
    for round_ in range(5):
        writer = start(WRITER, path, 1000 * round_, 500)
        for _ in range(rng.randint(2, 25)):  # a put has returned for each line read
            line = writer.stdout.readline().strip()
            assert line, writer.stderr.read()
            confirmed.append(line)
        time.sleep(rng.uniform(0.0, 0.02))  # land somewhere inside a later put
        os.killpg(writer.pid, signal.SIGKILL)
        writer.wait(timeout=30)
        confirmed += [k for k in writer.stdout.read().split() if k]
        check = subprocess.run([sys.executable, "-c", COMMON + (
            "db = CurveStore(sys.argv[1])\n"
            "keys = db.keys()\n"
            "[check(db, k) for k in keys]\n"
            "print(json.dumps(keys))\n"), path], env=ENV, capture_output=True, text=True,
            timeout=60)
        assert check.returncode == 0, check.stderr
        stored = set(json.loads(check.stdout))
        assert set(confirmed) <= stored, f"round {round_}: lost {set(confirmed) - stored}"
        assert len(stored) - len(confirmed) <= 1  # at most the put in flight got through
        confirmed = sorted(stored)
    # the next writer clears the orphaned temporary file of the last killed one
    CurveStore(path, mode="a").close()
    assert not list(tmp_path.glob(".curves.h5.tmp-*"))
