"""Fuzzing the ``balloon`` command in-process (``service.cli.main(argv)``): hostile
numbers (NaN, infinity, negative, huge, denormal, not numbers), missing files,
directories given as files, empty, binary, non-UTF-8 and malformed CSV / JSON / TOML /
HDF5 files, names with path parts or undecodable bytes.

Every bad invocation must: exit non-zero, print exactly one line on stderr (as a
terminal shows it: a progress bar erased with carriage returns is not a line; a Python
warning would be, with a source path in it), no traceback (an exception escaping
``main`` is one), and no absolute path of the repository, the interpreter or the home
directory unless the user gave it. stdout is a strict UTF-8 stream and stderr a
backslash-replacing one, as a UTF-8 terminal has them.

The work itself never starts: the FE solve, the surrogate fit, the precompute job and
the web server are replaced by a tripwire (reaching one means bad input was accepted).
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import os
import sys
import warnings
from pathlib import Path

import pytest
from test_store import record_for

from service.cli import main
from solver.store import CurveStore

REPO = Path(__file__).resolve().parents[1]
LOCAL = [str(REPO), sys.prefix, str(Path.home())]
UNDECODABLE = "\udcff\udcfeid"   # bytes ff fe as Python hands them over from argv
SHOWN_WARNINGS = (DeprecationWarning, PendingDeprecationWarning, ImportWarning,
                  ResourceWarning)  # what Python hides by default (these are not shown)


class WorkStarted(Exception):  # noqa: N818 - a tripwire, not an error of the code
    """The command went past its checks into the expensive work."""


def _tripwire(*args, **kwargs):
    raise WorkStarted("bad input was accepted: the work started")


def run(argv: list[str]) -> tuple[int | None, str, str, BaseException | None]:
    """(exit code, stdout, stderr as shown, escaped exception) of ``balloon argv``."""
    out_bytes, err_bytes = io.BytesIO(), io.BytesIO()
    out = io.TextIOWrapper(out_bytes, encoding="utf-8", errors="strict", write_through=True)
    err = io.TextIOWrapper(err_bytes, encoding="utf-8", errors="backslashreplace",
                           write_through=True)
    escaped: BaseException | None = None
    code: int | None = None
    with (contextlib.redirect_stdout(out), contextlib.redirect_stderr(err),
          warnings.catch_warnings(record=True) as caught):
        warnings.simplefilter("default")
        try:
            code = main(argv)
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else 1
        except BaseException as exc:  # noqa: BLE001 - a traceback in a real run
            escaped = exc
    shown = "".join(warnings.formatwarning(w.message, w.category, w.filename, w.lineno)
                    for w in caught if not issubclass(w.category, SHOWN_WARNINGS))
    return code, out_bytes.getvalue().decode(), err_bytes.getvalue().decode() + shown, escaped


def visible_lines(text: str) -> list[str]:
    """The lines a terminal shows: after the last carriage return of each, non-blank."""
    return [line.rsplit("\r", 1)[-1] for line in text.split("\n")
            if line.rsplit("\r", 1)[-1].strip()]


def refused(argv: list[str]) -> list[str]:
    """What is wrong with how ``balloon argv`` refuses bad input (empty: nothing)."""
    code, _, err, escaped = run(argv)
    problems = []
    if escaped is not None:
        return [f"escaped {type(escaped).__name__}: {str(escaped)[:200]}"]
    if not code:
        problems.append(f"exit code {code!r}")
    lines = visible_lines(err)
    if len(lines) != 1:
        problems.append(f"{len(lines)} lines on stderr: {err[:600]!r}")
    elif not lines[0].startswith("balloon"):
        problems.append(f"stderr is not the command's error line: {lines[0][:200]!r}")
    given = " ".join(argv)
    for word in [*LOCAL, "Traceback", 'File "']:
        if word in err and word not in given:
            problems.append(f"stderr shows {word!r}: {err[:300]!r}")
    return problems


# -- hostile files ------------------------------------------------------------------------

GOOD_CSV = ("curve_id,L_mm,t_mm,body_material,membrane_material,pressure_pa,angle_deg\n"
            + "".join(f"{c},7.1,0.5,pdms_1_10,ecoflex_00_30,{p},{a}\n"
                      for c in ("s1", "s2")
                      for p, a in ((0, 0.1), (400, 1.6), (800, 4.8), (1200, 12.0),
                                   (1600, 30.5))))


def _csv_with(value: str, column: int = 5) -> str:
    lines = GOOD_CSV.splitlines()
    cells = lines[3].split(",")
    cells[column] = value
    lines[3] = ",".join(cells)
    return "\n".join(lines) + "\n"


FILES: dict[str, bytes | str | None] = {   # None: a directory
    "missing.csv": "", "adir": None, "adir.csv": None, "adir.json": None, "adir.h5": None,
    "adir.toml": None, "adir.png": None,
    "empty.csv": b"", "empty.json": b"", "empty.h5": b"", "empty.toml": b"",
    "garbage.csv": bytes(range(256)) * 8, "garbage.json": bytes(range(256)) * 8,
    "garbage.h5": b"\x89HDF\r\n\x1a\n" + bytes(range(256)) * 8,
    "garbage.toml": bytes(range(256)) * 8,
    "latin1.csv": GOOD_CSV.replace("s1", "sp\u00e9cimen").encode("latin-1"),
    "utf16.csv": GOOD_CSV.encode("utf-16"),   # good data: its BOM names the encoding
    "nul.csv": GOOD_CSV.replace("s2", "s\x002").encode(),
    "header-only.csv": GOOD_CSV.splitlines()[0] + "\n",
    "nan.csv": _csv_with("nan"), "inf.csv": _csv_with("inf"), "huge.csv": _csv_with("1e400"),
    "minus.csv": _csv_with("-1e308"), "1e6-pa.csv": _csv_with("1000000"),
    "1e6-pa-first.csv": _csv_with("1000000").replace(",0,0.1\n", ",1000000,0.1\n", 1),
    "bad-L.csv": _csv_with("-7.1", 1),
    "nan-L.csv": _csv_with("NaN", 1), "text-number.csv": _csv_with("abc"),
    "long-cell.csv": _csv_with("x" * 1_000_000, 0),
    "ragged.csv": GOOD_CSV + "s3,7.1\n", "quote.csv": GOOD_CSV + 's3,"7.1\n',
    "not-a-list.json": '{"rows": 5}', "scalar.json": "12", "strings.json": '["a", "b"]',
    "nan.json": '[{"curve_id": "s1", "pressure_pa": NaN}]',
    "deep.json": "[" * 100_000 + "]" * 100_000,
    "deep-object.json": '{"rows": ' + '{"a": ' * 50_000 + "1" + "}" * 50_000 + "}",
    "bigint.json": '[{"pressure_pa": ' + "9" * 5000 + "}]",
    "bigint-emulator.json": '{"format": "balloon-emulator", "x": ' + "9" * 5000 + "}",
    "deep-emulator.json": '{"format": "balloon-emulator", "x": ' + "[" * 100_000,
    "text.h5": "not an hdf5 file\n",
    "nan.toml": 'name = "x"\n[[sweep]]\npairs = [["pdms_1_10", "ecoflex_00_30"]]\n'
                "L_mm = [nan, inf]\nt_mm = 0.5\n",
    "negative.toml": 'name = "x"\n[[sweep]]\npairs = [["pdms_1_10", "ecoflex_00_30"]]\n'
                     "L_mm = -7.1\nt_mm = 0.5\n",
    "huge.toml": 'name = "x"\n[[sweep]]\npairs = [["pdms_1_10", "ecoflex_00_30"]]\n'
                 "L_mm = 1e308\nt_mm = 0.5\n",
    "types.toml": 'name = "x"\n[[sweep]]\npairs = "pdms"\nL_mm = "7.1"\nt_mm = [[0.5]]\n',
    "nonutf8.toml": b'name = "\xff"\n',
    UNDECODABLE + ".csv": GOOD_CSV,
}


# one reading of 1e6 Pa among good ones is dropped with a warning (the baseline's table
# ends near the readings it answers, surrogate/calibration/_reading_checks.py: table_end_pa)
GOOD_FILES = ("utf16.csv", UNDECODABLE + ".csv", "1e6-pa.csv")


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """The hostile files, a small valid database, and the settings of a clean home:
    models in a temporary directory."""
    tmp = tmp_path_factory.mktemp("cli")
    for name, content in FILES.items():
        path = tmp / name
        if name.startswith("missing"):
            continue
        if content is None:
            path.mkdir()
        elif isinstance(content, bytes):
            path.write_bytes(content)
        else:
            path.write_text(content, encoding="utf-8", errors="surrogateescape")
    with CurveStore(tmp / "db.h5", mode="a") as db:
        db.put_many([record_for(L_mm=L) for L in (4.1, 7.1, 9.1, 11.1)])
    (tmp / "models").mkdir()
    (tmp / "models" / "bigsaved.json").write_text('{"format": 1' + "0" * 5000 + "}")
    (tmp / "models" / "deepsaved.json").write_text("[" * 100_000)
    return tmp


@pytest.fixture(autouse=True)
def clean_environment(files, monkeypatch):
    """Settings from a clean environment (models under tmp), and the tripwires."""
    import solver.precompute
    import solver.stepping
    import surrogate
    from service.settings import get_settings

    for name in list(os.environ):
        if name.startswith("BALLOON_"):
            monkeypatch.delenv(name)
    monkeypatch.setenv("BALLOON_MODELS_DIR", str(files / "models"))
    monkeypatch.setattr(solver.stepping, "inflate", _tripwire)
    monkeypatch.setattr(solver.precompute, "precompute", _tripwire)
    monkeypatch.setattr(surrogate, "fit_surrogate", _tripwire)
    monkeypatch.setattr("uvicorn.run", _tripwire)
    get_settings.cache_clear()
    yield
    get_settings.cache_clear()


# -- the invocations ------------------------------------------------------------------------

NUMBERS = ["nan", "inf", "-inf", "-1", "1e308", "-1e308", "1e400", "abc", "", "0x10"]
TINY = "1e-320"   # a denormal: positive, and nothing physical
DESIGN = ["--L-mm", "7.1", "--t-mm", "0.5"]
PAPER = ["--model", "paper"]


def _cases() -> list[tuple[str, list[str]]]:
    """(id, argv) of every bad invocation; "{tmp}" is the files' directory."""
    cases: list[tuple[str, list[str]]] = []

    def add(argv: list[str]) -> None:
        cases.append((" ".join(argv)[:90], argv))

    # argparse's own refusals
    for argv in (["nope"], ["--bogus"], ["predict"], ["db"], ["db", "nope"],
                 ["predict", "--L-mm", "7.1"], ["inverse", "--objective", "best"],
                 ["serve", "--log-level", "loud"], ["solve", "--element", "hex9"]):
        add(argv)
    # predict: the design, the band, the axis, the pump and the inlet
    for flag in ("--L-mm", "--t-mm", "--T-mm", "--b-mm", "--h-mm", "--W-mm",
                 "--body-length-mm", "--chamber-offset-mm", "--level",
                 "--body-stiffness-scale", "--membrane-stiffness-scale"):
        for value in [*NUMBERS, TINY, "0"]:
            design = {**dict(zip(DESIGN[::2], DESIGN[1::2])), flag: value}
            add(["predict", *[w for pair in design.items() for w in pair],
                 "--pressures", "1000", *PAPER])
    for axis in ("--pressures", "--volumes", "--times"):
        for value in ["nan", "inf", "-1", "1e308", "abc", "", "1 nan", "1,inf", "-1e-300"]:
            extra = ["--flow-ul-s", "2.5"] if axis == "--times" else []
            add(["predict", *DESIGN, axis, value, *extra])
    for value in [*NUMBERS, TINY, "0"]:
        add(["predict", *DESIGN, "--times", "1", "--flow-ul-s", value])
        add(["predict", *DESIGN, "--volumes", "5", "--flow-ul-s", value, "--json"])
        add(["predict", *DESIGN, "--pressures", "1000", "--inlet", "--flow-ul-s", "2.5",
             "--viscosity-pa-s", value])
    for triple in (["0", "1000", "nan"], ["0", "1000", "0"], ["0", "1000", "1e9"],
                   ["0", "1000", "2.5"], ["nan", "1000", "5"], ["0", "inf", "5"],
                   ["-1", "1000", "5"], ["0", "1e308", "5"]):
        add(["predict", *DESIGN, "--pressure-range", *triple, *PAPER])
    for extra in (["--inlet", "--flow-ul-s", "2.5", "--channel-mm", "nan", "1", "1"],
                  ["--inlet", "--flow-ul-s", "2.5", "--tubing-mm", "-1", "0.5"],
                  ["--inlet", "--flow-ul-s", "2.5", "--tubing-mm", "10", "0"],
                  ["--tubing-mm", "10", "0.5"],
                  ["--pressures-at", "pump_gauge"],
                  ["--body-material", "nope"], ["--body-material", "../../etc/passwd"],
                  ["--membrane-material", UNDECODABLE],
                  ["--body-material", "nope", "--body-stiffness-scale", "1.0"]):
        add(["predict", *DESIGN, "--pressures", "1000", *extra])
    for model in ("nope", "../../etc/passwd", "{tmp}/missing.json", "{tmp}/adir.json",
                  "{tmp}/garbage.json", "{tmp}/empty.json", "{tmp}/deep.json",
                  "{tmp}/nan.json", "{tmp}/bigint.json", "{tmp}/bigint-emulator.json",
                  "{tmp}/deep-emulator.json", "{tmp}/text.h5", UNDECODABLE,
                  "a" * 5000):
        add(["predict", *DESIGN, "--pressures", "1000", "--model", model])
    for saved in ("bigsaved", "deepsaved"):
        add(["predict", *DESIGN, "--pressures", "1000", "--model", saved])
    add(["predict", *DESIGN, "--pressures", "1000", "--model", "saved1",
         "--models-dir", "{tmp}/missing-dir"])
    add(["predict", *DESIGN, "--pressures", "1000", "--model", "saved1",
         "--models-dir", "{tmp}/garbage.csv"])
    # inverse: one design, and the design search (on the paper's model: fast)
    for value in ["nan", "inf", "-inf", "1e308", "-1e308", "abc", ""]:
        add(["inverse", *DESIGN, "--angles-deg", value, *PAPER])
        add(["inverse", "--pressure-pa", value, "--angle-deg", "45", *PAPER])
        add(["inverse", "--pressure-pa", "1500", "--angle-deg", value, *PAPER])
        add(["inverse", "--kind", "force_at_pressure", "--pressure-pa", "1500",
             "--force-mn", value, *PAPER])
        add(["inverse", "--pressure-pa", "1500", "--angle-deg", "45", "--L-range", value,
             "10", *PAPER])
        add(["inverse", "--pressure-pa", "1500", "--angle-deg", "45", "-n", value, *PAPER])
        add(["inverse", "--pressure-pa", "1500", "--angle-deg", "45", "--level", value,
             *PAPER])
    for value in (TINY, "0", "-1", "nan"):
        add(["inverse", *DESIGN, "--angles-deg", "45", "--flow-ul-s", value])
    for value in ("0", TINY, "-1", "nan", "1e7"):   # a denormal is 0 (hostile round four)
        add(["inverse", "--pressure-pa", value, "--angle-deg", "45", *PAPER])
    for extra in (["--L-range", "5", "4"], ["--L-range", "-1", "5"],
                  ["--t-range", "1e308", "1e308"], ["--body-stiffness-range", "0", "0"],
                  ["--pair", "nope"], ["--pair", "a/b"], ["--pair", "/"],
                  ["--pair", "../x/../y"], ["--pair", UNDECODABLE + "/x"],
                  ["-n", "0"], ["-n", "100000"], ["--kind", "force_at_pressure"]):
        add(["inverse", "--pressure-pa", "1500", "--angle-deg", "45", *extra, *PAPER])
    add(["inverse", "--angle-deg", "45", *PAPER])
    add(["inverse", "--angles-deg", "45", "--L-mm", "7.1", *PAPER])
    # solve: never reaches the FE solve
    for flag in ("--L-mm", "--t-mm", "--T-mm", "--b-mm", "--h-mm", "--W-mm",
                 "--body-length-mm", "--chamber-offset-mm", "--max-angle-deg",
                 "--max-pressure-pa", "--flow-ul-s", "--bulk-ratio"):
        for value in ["nan", "inf", "-1", "1e308", TINY, "abc"]:
            add(["solve", flag, value, "--quiet"])
    for extra in (["--mesh", "-1"], ["--mesh", "1000"], ["--mesh", "1.5"],
                  ["--tip", "spring", "--spring-k-n-per-m", "nan"],
                  ["--spring-k-n-per-m", "-1"], ["--body-material", "nope"],
                  ["--membrane-material", "../x"], ["--body-material", UNDECODABLE],
                  ["--json", "{tmp}/adir"], ["--csv", "{tmp}/missing-dir/x.csv"],
                  ["--plot", "{tmp}/adir.csv"], ["--vtk", "{tmp}/missing-dir/x.vtu"]):
        add(["solve", "--quiet", *extra])
    # fit: never reaches the fit
    for db in ("missing.h5", "adir.h5", "garbage.h5", "empty.h5", "text.h5", "garbage.csv"):
        add(["fit", "--db", "{tmp}/" + db, "-o", "{tmp}/out.json"])
    for extra in (["--level", "nan"], ["--level", "2"], ["--level", "-1"],
                  ["-o", "{tmp}/adir"], ["-o", "{tmp}/missing-dir/s.json"],
                  ["--emulator-output", "{tmp}/adir"], ["--report-dir", "{tmp}/garbage.csv"],
                  ["--band-calibration-db", "{tmp}/db.h5"],     # without --emulator-output
                  *(["--emulator-output", "{tmp}/e.json", "--band-calibration-db",
                     "{tmp}/" + db] for db in ("missing.h5", "adir.h5", "garbage.h5",
                                               "empty.h5", "text.h5", "db.h5"))):
        add(["fit", "--db", "{tmp}/db.h5", "-o", "{tmp}/out.json", *extra])
    # calibrate: hostile data files, then hostile options on good data
    for name in FILES:
        if name.endswith((".csv", ".json")) and name not in GOOD_FILES or name == "adir":
            add(["calibrate", "{tmp}/" + name, "--report", "{tmp}/r.json", *PAPER])
    add(["calibrate", "{tmp}/" + UNDECODABLE + "-missing.csv", "--report", "{tmp}/r.json"])
    good = ["calibrate", "{tmp}/good.csv", "--report", "{tmp}/r.json"]
    for extra in (["--folds", "0"], ["--folds", "1"], ["--folds", "51"], ["--folds", "nan"],
                  ["--save", "../evil"], ["--save", ""], ["--save", "a" * 300],
                  ["--save", "paper"], ["--save", UNDECODABLE], ["--model", "nope"],
                  ["--model", "{tmp}/garbage.json"], ["--model", "{tmp}/adir.json"],
                  ["--report", "{tmp}/adir"], ["--plot", "{tmp}/adir.png"],
                  ["--save", "ok1", "--models-dir", "{tmp}/garbage.csv"]):
        add([*good, *([] if "--model" in extra else PAPER), *extra])
    # db: hostile files and arguments; seal must not touch what it cannot read
    for db in ("missing.h5", "adir.h5", "garbage.h5", "empty.h5", "text.h5", "latin1.csv"):
        for action in (["ls"], ["show"], ["export"], ["seal"]):
            add(["db", *action, "{tmp}/" + db])
    for extra in (["show", "{tmp}/db.h5", "nokey"], ["show", "{tmp}/db.h5", ""],
                  ["show", "{tmp}/db.h5", UNDECODABLE], ["ls", "{tmp}/db.h5", "--where", "L"],
                  ["ls", "{tmp}/db.h5", "--where", "=7.1"],
                  ["export", "{tmp}/db.h5", "nokey"],
                  ["export", "{tmp}/db.h5", "-o", "{tmp}/adir"],
                  ["export", "{tmp}/db.h5", "-o", "{tmp}/missing-dir/x.csv"]):
        add(["db", *extra])
    # precompute: hostile grids (dry runs; the job itself is a tripwire)
    for grid in ("missing.toml", "adir.toml", "empty.toml", "garbage.toml", "nan.toml",
                 "negative.toml", "huge.toml", "types.toml", "nonutf8.toml"):
        add(["precompute", "{tmp}/" + grid, "--db", "{tmp}/new.h5", "--dry-run"])
    for extra in (["--workers", "0"], ["--workers", "-1"], ["--workers", "100000"],
                  ["--db", "{tmp}/adir"], ["--db", "{tmp}/missing-dir/x.h5"],
                  ["--adaptive", "3", "--emulator", "{tmp}/garbage.json"],
                  ["--adaptive", "3", "--emulator", "{tmp}/missing.json"],
                  ["--adaptive", "3", "--db", "{tmp}/missing.h5"],
                  ["--designs-from", "{tmp}/missing.h5"], ["--designs-from", "{tmp}/adir.h5"],
                  ["--designs-from", "{tmp}/garbage.h5"], ["--designs-from", "{tmp}/text.h5"],
                  ["--designs-from", "{tmp}/empty.h5"],
                  ["--designs-from", "{tmp}/new.h5", "--db", "{tmp}/new.h5"],
                  ["--designs-from", "{tmp}/db.h5", "--adaptive", "3"]):
        add(["precompute", str(REPO / "grids" / "default.toml"), "--db", "{tmp}/new.h5",
             "--dry-run", *extra])
    # serve: never starts the server
    for port in ("0", "-1", "65536", "99999999999999999999", "abc", "nan"):
        add(["serve", "--port", port])
    return cases


CASES = _cases()


@pytest.mark.parametrize("argv", [argv for _, argv in CASES], ids=[i for i, _ in CASES])
def test_bad_invocations_are_refused_on_one_line(files, argv):
    (files / "good.csv").write_text(GOOD_CSV)
    argv = [a.replace("{tmp}", str(files)) for a in argv]
    problems = refused(argv)
    assert not problems, f"balloon {' '.join(argv)[:300]}: {problems}"


def test_refusals_change_no_file(files):
    """A refused seal, export or calibration leaves every file as it was (no database
    created from nothing, no hostile file rewritten). The writer's lock sidecar
    (``<db>.lock``, docs/database.md) is taken before the file is read and kept, as
    every writer keeps it: not compared (it made the test depend on which tests ran
    before it)."""
    def contents() -> dict[str, str]:
        return {p.name: hashlib.sha256(p.read_bytes()).hexdigest()
                for p in files.iterdir() if p.is_file() and not p.name.endswith(".lock")}

    before = contents()
    for argv in (["db", "seal", "garbage.h5"], ["db", "seal", "text.h5"],
                 ["db", "seal", "empty.h5"], ["db", "seal", "missing.h5"],
                 ["calibrate", "nan.csv", "--report", "garbage.json", "--model", "paper"],
                 ["precompute", "nan.toml", "--db", "garbage.h5"]):
        run([a if a.startswith("-") or a in ("db", "seal", "calibrate", "precompute", "paper")
             else str(files / a) for a in argv])
    assert contents() == before


GOOD = [  # (id, argv, exit code): answers, some of them past the model's range (null)
    ("predict", ["predict", *DESIGN, "--pressures", "500", "1000", *PAPER], 0),
    ("predict past the FE range", ["predict", *DESIGN, "--pressures", "0", "20000", *PAPER,
                                   "--json"], 0),
    ("predict at the slowest pump", ["predict", *DESIGN, "--volumes", "0", "10000",
                                     "--flow-ul-s", "1e-6", "--json"], 0),
    ("inverse past the FE range", ["inverse", *DESIGN, "--angles-deg", "0.5", "359",
                                   *PAPER, "--json"], 0),
    ("search past the FE range", ["inverse", "--kind", "pressure_budget", "--pressure-pa",
                                  "20001", "--angle-deg", "45", *PAPER], 0),
    *[(f"calibrate {name!r}", ["calibrate", "{tmp}/" + name, "--report", "{tmp}/r.json",
                               *PAPER], 0) for name in GOOD_FILES],
    ("db ls as JSON lines", ["db", "ls", "{tmp}/db.h5", "--json"], 0),
    ("db export as JSON (NaN force)", ["db", "export", "{tmp}/db.h5", "--format", "json"], 0),
]


@pytest.mark.parametrize(("argv", "expected"), [(a, c) for _, a, c in GOOD],
                         ids=[i for i, _, _ in GOOD])
def test_good_invocations_pass_the_same_checks(files, argv, expected):
    """The harness itself, and answers at the edges: the expected exit code, no Python
    warning or traceback on stderr, JSON (lines) without NaN or Infinity."""
    argv = [a.replace("{tmp}", str(files)) for a in argv]
    code, out, err, escaped = run(argv)
    assert escaped is None and code == expected, (code, err, repr(escaped))
    assert not [line for line in visible_lines(err)
                if "Warning" in line or "Traceback" in line or str(REPO) in line], err
    if "--json" in argv or "json" in argv:   # `db ls --json` writes JSON lines
        for doc in out.splitlines() if argv[:2] == ["db", "ls"] else [out]:
            json.loads(doc, parse_constant=_strict_constant)


def _strict_constant(name: str) -> None:
    raise ValueError(f"{name} is not JSON")
