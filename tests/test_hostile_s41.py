"""The forty-first session's hostile-input audit: what a careless or hostile user met that
the schema-driven fuzzers (tests/test_cli_fuzz.py, tests/test_service_fuzz.py) did not
send -- Ctrl-C landing inside h5py, a scaled material id given a second scale, a
directory or a dangling link where a file goes, the same flag twice in an answer.

Each test failed on the code before its fix (commit messages say which).
"""

from __future__ import annotations

import hashlib
import signal
import sys
from pathlib import Path

import pytest
from test_cli_fuzz import GOOD_CSV, run, visible_lines
from test_store import record_for

from solver.store import CurveStore

H5PY_ATTRIBUTE_CALLBACK = "iter_cb"      # h5py/_hl/attrs.py: AttributeManager.__iter__
WEAKREF_CALLBACK = ("remove", "weakref.py")  # WeakValueDictionary's entry remover


def _small_db(tmp_path: Path) -> Path:
    db = tmp_path / "db.h5"
    with CurveStore(db, mode="a") as store:
        store.put_many([record_for(L_mm=L) for L in (4.1, 7.1, 9.1)])
    return db


def _interrupted_at(argv: list[str], hit) -> tuple[list[str], tuple]:
    """``balloon argv`` with Ctrl-C's KeyboardInterrupt raised the first time a Python
    function that ``hit(code)`` picks is entered (where a real SIGINT lands when it
    arrives during h5py's C code calling back into Python). (where it fired, result)."""
    fired: list[str] = []

    def tracer(frame, event, arg):
        if event == "call" and not fired and hit(frame.f_code):
            fired.append(f"{frame.f_code.co_filename}:{frame.f_code.co_name}")
            raise KeyboardInterrupt
        return None

    sys.settrace(tracer)
    try:
        result = run(argv)
    finally:
        sys.settrace(None)
    return fired, result


@pytest.mark.parametrize("action", [["seal"], ["show"], ["export", "--format", "json"]])
def test_ctrl_c_inside_h5py_is_an_interruption_not_a_traceback(tmp_path, action):
    """h5py turns a KeyboardInterrupt raised in its attribute callback into
    ``SystemError: <cyfunction FastRLock.__exit__> returned a result with an exception
    set``: `balloon db seal` interrupted at 25 s of 31 printed that traceback (with the
    site-packages paths) and exited 1. It is the user's Ctrl-C: one line, exit 130, the
    database as it was."""
    db = _small_db(tmp_path)
    before = hashlib.sha256(db.read_bytes()).hexdigest()
    fired, (code, _, err, escaped) = _interrupted_at(
        ["db", *action, str(db)], lambda c: c.co_name == H5PY_ATTRIBUTE_CALLBACK)
    assert fired, "the interrupt never fired: h5py no longer calls back here"
    assert escaped is None, f"escaped {type(escaped).__name__}: {escaped}"
    assert (code, visible_lines(err)) == (130, ["balloon: interrupted"]), err
    assert hashlib.sha256(db.read_bytes()).hexdigest() == before
    with CurveStore(db) as store:
        assert len(store) == 3


@pytest.fixture
def terminal_ctrl_c():
    """SIGINT raising KeyboardInterrupt, as in a terminal (a test worker may ignore it)."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


@pytest.mark.parametrize("redelivery_s", [None, 5.0], ids=["as-shipped", "slow-thread"])
def test_ctrl_c_in_a_weakref_callback_still_stops_the_command(tmp_path, terminal_ctrl_c,
                                                              monkeypatch, redelivery_s):
    """A KeyboardInterrupt raised in a weak-reference callback (h5py's objects dying) is
    "ignored" by Python: it printed "Exception ignored in: <function
    WeakValueDictionary.__init__.<locals>.remove ...> Traceback ... KeyboardInterrupt",
    then the seal went on and exited 0 as if Ctrl-C had not been pressed.

    slow-thread: the interrupt handed back from a thread (service/commands/interrupts.py)
    came after the seal had printed "sealed (3 records)" on a loaded CI machine (two
    lines, exit 130); the seal now stops at the end of its store block at the latest."""
    if redelivery_s is not None:
        from service.commands import interrupts
        monkeypatch.setattr(interrupts, "REDELIVERY_DELAY_S", redelivery_s)
    db = _small_db(tmp_path)
    def in_the_seal(code) -> bool:   # a weak reference dying inside CurveStore.seal
        if (code.co_name, Path(code.co_filename).name) != WEAKREF_CALLBACK:
            return False
        frame = sys._getframe(1)
        while frame is not None:
            if frame.f_code.co_name == "seal" and frame.f_code.co_filename.endswith("hdf5.py"):
                return True
            frame = frame.f_back
        return False

    fired, (code, _, err, escaped) = _interrupted_at(["db", "seal", str(db)], in_the_seal)
    assert fired, "the interrupt never fired: no weak reference died during the seal"
    assert escaped is None, f"escaped {type(escaped).__name__}: {escaped}"
    assert (code, visible_lines(err)) == (130, ["balloon: interrupted"]), err
    with CurveStore(db) as store:
        assert len(store) == 3


def test_an_answer_names_each_flag_once():
    """The exponential model's inverse past both the family's FE angle (97.5 deg for the
    standard design's family) and its volume relation's (90.3 deg) flagged
    ``past_fe_range`` twice: ``"flags": ["angle_beyond_fe", "past_fe_range",
    "past_fe_range"]`` (POST /v1/inverse/pressure, model "exponential", 91 and 120 deg).
    Flags are machine-readable names: each once, its messages all kept."""
    from service.settings import DATA_DIR
    from solver import Design
    from surrogate import open_surrogate

    model = open_surrogate(str(DATA_DIR / "surrogate.json"))
    answer = model.inverse(Design(L_mm=7.1, t_mm=0.5), [45, 91, 120])
    flags = answer.validity["flags"]
    assert sorted(flags) == sorted(set(flags)), flags
    assert "past_fe_range" in flags
    assert any("no volume above" in m for m in answer.validity["messages"])


@pytest.mark.parametrize("command", [["predict", "--pressures", "1000"],
                                     ["inverse", "--angles-deg", "30"]])
def test_a_scaled_material_with_a_stiffness_scale_is_named_as_such(command):
    """``--body-material pdms_1_10*2 --body-stiffness-scale 0.5`` was refused as
    "unknown material 'pdms_1_10*2' (allowed: pdms_1_10, pdms_1_15, ecoflex_00_30)",
    though the same id alone is taken (README: the id <preset>*<scale> wherever a preset
    id is taken) and the list was a copy of the presets' table. The refusal says the id
    is scaled already and how to give the scale once; the presets come from the table."""
    from solver.materials import MATERIALS

    argv = [command[0], "--L-mm", "7.1", "--t-mm", "0.5", *command[1:], "--model", "paper",
            "--body-material", "pdms_1_10*2", "--body-stiffness-scale", "0.5"]
    code, _, err, escaped = run(argv)
    assert escaped is None and code == 2
    (line,) = visible_lines(err)
    assert line.startswith("balloon: error: --body-material: 'pdms_1_10*2' is already "
                           "scaled"), line
    assert "unknown" not in line and "--body-stiffness-scale" in line
    assert all(preset in line for preset in MATERIALS)
    code, out, err, escaped = run(argv[:-4])     # the scaled id alone: answered
    assert (code, escaped) == (0, None), err


@pytest.mark.parametrize("loader", ["emulator", "surrogate"])
def test_a_model_file_is_read_within_a_bound(tmp_path, monkeypatch, loader):
    """``balloon precompute GRID --db DB --adaptive 2 --emulator /dev/zero`` read
    /dev/zero to the end: memory without bound, then a MemoryError traceback. A model
    file is read like the grid and the measured data (solver/bounded_read.py): past its
    bound (here lowered to 1 kB so the test reads little) it is refused at ``model``."""
    import surrogate.emulator.file as emulator_file
    import surrogate.exponential.file as surrogate_file
    import surrogate.model_file
    from solver.errors import InputError

    monkeypatch.setattr(surrogate.model_file, "MAX_MODEL_FILE_BYTES", 1024)
    big = tmp_path / "big.json"
    big.write_text('{"format": "balloon-emulator", "pad": "' + "x" * 4096 + '"}')
    load = (emulator_file.load_emulator if loader == "emulator"
            else surrogate_file.load_surrogate)
    with pytest.raises(InputError) as caught:
        load(big)
    assert caught.value.field == "model"
    assert "big.json: larger than" in str(caught.value), str(caught.value)
    assert str(tmp_path) not in str(caught.value)


def test_a_directory_given_as_the_emulator_is_named_with_its_option(tmp_path):
    """``--emulator adir.json`` (a directory) said "model: adir.json: cannot be read
    (IsADirectoryError)": no option, no allowed form, a Python class name."""
    (tmp_path / "adir.json").mkdir()
    grid = Path(__file__).resolve().parents[1] / "grids" / "default.toml"
    code, _, err, escaped = run(["precompute", str(grid), "--db", str(tmp_path / "n.h5"),
                                 "--dry-run", "--adaptive", "2", "--emulator",
                                 str(tmp_path / "adir.json")])
    assert escaped is None and code == 2
    (line,) = visible_lines(err)
    assert line.startswith("balloon: error: --emulator: ") and "directory" in line, line
    assert "IsADirectoryError" not in line and "allowed:" in line


@pytest.mark.parametrize("where", ["adir.json", "adir"])
def test_a_directory_given_as_the_model_is_called_a_directory(tmp_path, where):
    """``balloon predict --model DIR/`` (or a directory named like a model file) said
    "file not found" of a directory that is there."""
    (tmp_path / where).mkdir()
    code, _, err, escaped = run(["predict", "--L-mm", "7.1", "--t-mm", "0.5", "--pressures",
                                 "1000", "--model", f"{tmp_path / where}/"])
    assert escaped is None and code == 2
    (line,) = visible_lines(err)
    assert line.startswith("balloon: error: --model: ") and ": is a directory" in line, line


@pytest.mark.parametrize("command", [["db", "ls"], ["db", "export"], ["fit", "-o", "o.json"]])
def test_a_dangling_link_is_named_as_given(tmp_path, monkeypatch, command):
    """``balloon db ls dangling.h5`` (a symbolic link to a file that is gone) said "no
    curve database at /work/.../nowhere.h5; create one with `balloon precompute GRID.toml
    --db /work/.../nowhere.h5`": the link's absolute target, a local path the user never
    typed. The message names the path as given."""
    monkeypatch.chdir(tmp_path)
    Path("dangling.h5").symlink_to("nowhere.h5")
    argv = [*command, "dangling.h5"] if command[0] == "db" else [*command, "--db",
                                                                   "dangling.h5"]
    code, _, err, escaped = run(argv)
    assert escaped is None and code == 2
    (line,) = visible_lines(err)
    assert "no curve database at dangling.h5" in line, line
    assert str(tmp_path) not in line and "nowhere" not in line


GRID_WITH_MATERIAL = ('pairs = [["{id}", "ecoflex_00_30"]]\nL_mm = 7.1\nt_mm = 0.5\n'
                      '[materials."{id}"]\nmu_kpa = [1.0]\nalpha = [2.0]\n')


def test_a_grid_material_cannot_pass_for_a_scaled_preset(tmp_path):
    """A grid's ``[materials."pdms_1_10*2"]`` with other constants was taken: its records
    were stored under the id that everywhere else means PDMS 1:10 with every mu doubled
    (``GET /v1/curves?body_material=pdms_1_10*2`` listed them as such), while POST
    /v1/solve refuses the same inline material. One id, one set of parameters."""
    from solver.errors import InputError
    from solver.precompute.grid import load_grid

    grid = tmp_path / "g.toml"
    grid.write_text(GRID_WITH_MATERIAL.format(id="pdms_1_10*2"))
    with pytest.raises(InputError) as caught:
        load_grid(grid)
    assert "reuses the scaled preset id 'pdms_1_10*2'" in str(caught.value)
    assert caught.value.field.startswith("materials.")


@pytest.mark.parametrize("material_id", ["\x1b[31mred", "", "../../x", "a b", "x" * 65])
def test_a_grid_material_id_is_a_name(tmp_path, material_id):
    """A grid's custom material id was any text -- an escape sequence (which `balloon db
    ls` then printed raw, recolouring the terminal), an empty string, '../../x' --
    stored in the database as the material's id, though the service takes only names
    (service/schemas/common.py) and cannot even filter by the stored one."""
    from solver.errors import InputError
    from solver.precompute.grid import load_grid

    grid = tmp_path / "g.toml"
    grid.write_text(GRID_WITH_MATERIAL.format(id=material_id.replace("\x1b", "\\u001b")))
    with pytest.raises(InputError) as caught:
        load_grid(grid)
    assert caught.value.field.startswith("materials"), caught.value
    assert "letters, digits" in str(caught.value)


@pytest.mark.parametrize("command", [["db", "export", "{src}", "--format", "csv", "-o"],
                                     ["db", "export", "{src}", "--format", "json", "-o"],
                                     ["calibrate", "{csv}", "--model", "paper", "--report"]])
def test_an_output_never_replaces_another_curve_database(tmp_path, command):
    """``balloon db export a.h5 -o b.h5`` with b.h5 a curve database replaced it with
    CSV ("exported 2 records"): the check for an HDF5 file looked for the signature at
    byte 0, where every database the store writes carries its seal (the HDF5 signature
    follows at byte 512). Refused at the option, b.h5 unchanged."""
    src = _small_db(tmp_path)
    other = tmp_path / "other.h5"
    with CurveStore(other, mode="a") as store:
        store.put_many([record_for(L_mm=5.0)])
    before = other.read_bytes()
    (tmp_path / "data.csv").write_text(GOOD_CSV)
    argv = [w.replace("{src}", str(src)).replace("{csv}", str(tmp_path / "data.csv"))
            for w in command] + [str(other)]
    code, _, err, escaped = run(argv)
    assert escaped is None and code == 2, err
    (line,) = visible_lines(err)
    assert "HDF5 file" in line and ("--output" in line or "--report" in line), line
    assert other.read_bytes() == before


@pytest.mark.parametrize("suffix", [".lock", ".job.lock"])
def test_an_output_never_replaces_a_database_lock(tmp_path, suffix):
    """``balloon db export a.h5 -o b.h5.lock`` replaced b.h5's writer lock with a new
    file: a writer holding the old one keeps its lock on a file no one else opens, and
    the next writer locks the new one -- two writers at once, and one's records lost
    when the other publishes."""
    src = _small_db(tmp_path)
    other = tmp_path / "other.h5"
    with CurveStore(other, mode="a") as store:
        store.put_many([record_for(L_mm=5.0)])
    lock = tmp_path / f"other.h5{suffix}"
    lock.touch()
    before = lock.read_bytes(), lock.stat().st_ino
    code, _, err, escaped = run(["db", "export", str(src), "--format", "csv", "-o",
                                 str(lock)])
    assert escaped is None and code == 2, err
    (line,) = visible_lines(err)
    assert "lock" in line and "other.h5" in line, line
    assert (lock.read_bytes(), lock.stat().st_ino) == before


def test_a_gauge_reading_no_field_value_can_meet_names_the_flow():
    """Pump-gauge pressures through an inlet whose drop R Q exceeds every reading
    pressures_pa takes (at most 20 kPa) were refused with "allowed: >= 4574845.7 Pa at
    the pump gauge" -- a range the field itself refuses. The refusal names the flow rate
    and the largest one this inlet allows (R Q = 20 kPa)."""
    from service.pump import AXES, PumpQuestion, predict_answer
    from solver import Design
    from solver.errors import InputError
    from surrogate import paper_surrogate
    from surrogate.hydraulics import Inlet

    inlet = Inlet(viscosity_pa_s=1.0, tubing_length_mm=100.0, tubing_bore_mm=0.5)
    top = AXES["pressures_pa"][1]
    question = PumpQuestion(pressures_pa=[500.0, top], flow_ul_s=50.0, inlet=inlet,
                            pressures_at="pump_gauge")
    with pytest.raises(InputError) as caught:
        predict_answer(paper_surrogate(), Design(), question, "paper", 0.95)
    assert caught.value.field == "flow_ul_s", caught.value
    q_max = top / inlet.resistance_pa_per_ul_s
    assert f"{q_max:.4g}" in caught.value.allowed, caught.value.allowed
    # a drop the field's range can exceed: the readings' range is stated whole
    slow = PumpQuestion(pressures_pa=[10.0], flow_ul_s=0.5 * q_max, inlet=inlet,
                        pressures_at="pump_gauge")
    with pytest.raises(InputError) as caught:
        predict_answer(paper_surrogate(), Design(), slow, "paper", 0.95)
    assert caught.value.field == "pressures_pa"
    assert caught.value.allowed.endswith(f"<= pressures_pa <= {top:g} Pa at the pump gauge")


@pytest.mark.parametrize("scale", ["0", "-2", "1e400", "nan"])
def test_a_preset_scaled_by_no_positive_number_states_the_scales_range(scale, shipped_client):
    """``pdms_1_10*0`` (or x1e400, x-2, xnan) was refused as "unknown material
    'pdms_1_10*0' (did you mean 'pdms_1_10'?)": the preset is known, the scale is what is
    wrong. The refusal names the field and the scales a layer may have (0.01-100,
    ``STIFFNESS_SCALE_LIMITS``), on the CLI (with a stiffness scale given too: scaled
    twice, as above) and over HTTP; an inline material with such an id poses as a scaled
    preset and is refused as one."""
    material = f"pdms_1_10*{scale}"
    code, _, err, escaped = run(["predict", "--L-mm", "7.1", "--t-mm", "0.5",
                                 "--pressures", "1000", "--body-material", material])
    assert escaped is None and code == 2
    (line,) = visible_lines(err)
    assert line.startswith("balloon: error: --body-material: "), line
    assert "unknown" not in line and "0.01 <= scale <= 100" in line, line
    code, _, err, escaped = run(["predict", "--L-mm", "7.1", "--t-mm", "0.5", "--pressures",
                                 "1000", "--body-material", material,
                                 "--body-stiffness-scale", "1.2"])
    (line,) = visible_lines(err)
    assert escaped is None and code == 2 and "would scale it twice" in line, line
    r = shipped_client.post("/v1/predict", json={
        "design": {"L_mm": 7.1, "t_mm": 0.5, "body_material": material},
        "pressures_pa": [1000]})
    assert r.status_code == 422, r.text
    (error,) = r.json()["errors"]
    # (the schema's own pattern takes no sign or NaN: "is not of this form", at the field)
    assert error["field"] == "design.body_material" and "unknown" not in error["message"]
    assert "0.01 <= scale <= 100" in error["allowed"] or "not of this form" in \
        error["message"], error
    r = shipped_client.post("/v1/predict", json={
        "design": {"L_mm": 7.1, "t_mm": 0.5,
                   "body_material": {"id": material, "mu_kpa": [20.0], "alpha": [3.0]}},
        "pressures_pa": [1000]})
    assert r.status_code == 422 and r.json()["errors"][0]["field"] == \
        "design.body_material.id", r.text


def test_a_cli_refusal_names_the_options_not_the_request_fields():
    """``balloon predict --model paper --volumes 10`` was refused "(allowed: pressures_pa;
    ...)", the HTTP request's field, where the CLI's option is ``--pressures``; ``--times``
    without a flow rate said "times_s needs the pump's flow rate". Both now name the
    options (``PUMP_FLAGS``)."""
    for argv, flag, said in (
            (["--model", "paper", "--volumes", "10", "20"], "--volumes", "allowed: --pressures"),
            (["--times", "1", "2"], "--flow-ul-s", "--times needs the pump's flow rate")):
        code, _, err, escaped = run(["predict", "--L-mm", "7.1", "--t-mm", "0.5", *argv])
        assert escaped is None and code == 2
        (line,) = visible_lines(err)
        assert line.startswith(f"balloon: error: {flag}: ") and said in line, line
        assert "pressures_pa" not in line and "times_s" not in line, line
