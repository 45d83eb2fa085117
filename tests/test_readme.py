"""The README's promises: its snippets are the files the live-server tests run, its two
set-up commands are the ones CI and the Dockerfile use, and the CLI it documents exists."""

import re
from pathlib import Path

import pytest

from service.cli import build_parser, main
from service.commands.numbers import help_with_allowed

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()


def _code_blocks(lang: str) -> list[str]:
    return re.findall(rf"```{lang}\n(.*?)```", README, flags=re.S)


@pytest.mark.parametrize("name", ["client.py", "batch.py", "pump.py"])
def test_python_snippets_are_included_verbatim(name):
    text = (ROOT / "docs" / "snippets" / name).read_text().rstrip("\n")
    assert any(block.rstrip("\n") == text for block in _code_blocks("python"))


@pytest.mark.parametrize("name", ["predict.sh", "pump.sh"])
def test_curl_snippet_is_the_tested_one(name):
    text = (ROOT / "docs" / "snippets" / name).read_text()
    command = text[text.index("curl"):].rstrip("\n")
    assert any(command in block for block in _code_blocks("sh"))


def test_setup_commands_match_ci():
    blocks = [b.strip() for b in _code_blocks("sh")]
    serve, test = blocks[0], blocks[1]
    assert serve.endswith("balloon serve")
    assert test.endswith("pytest -q -n 2")  # both cores (pytest-xdist)
    # .ci/run runs each step of the README's test command, in its own venv, quietly
    ci = [ln.strip().replace(" --quiet", "")
          for ln in (ROOT / ".ci" / "run").read_text().splitlines()]
    for step in test.split(" && "):
        assert step.replace(".venv", ".ci-venv") in ci, step
    assert 'if [ "$rc" -eq 5 ]; then' in ci  # pytest's "no tests collected" fails CI


def test_every_documented_subcommand_exists():
    documented = set(re.findall(r"^balloon (\w+)", README, flags=re.M))
    parser = build_parser()
    available = set(parser._subparsers._group_actions[0].choices)  # noqa: SLF001
    assert documented <= available, documented - available


def test_version_and_help(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert capsys.readouterr().out.startswith("balloon ")
    with pytest.raises(SystemExit):
        main(["--help"])
    out = capsys.readouterr().out
    for command in ("solve", "precompute", "db", "fit", "predict", "inverse", "calibrate",
                    "serve"):
        assert command in out


def test_user_mistake_is_one_line_and_exit_2(capsys):
    assert main(["solve", "--t-mm", "-1", "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "t_mm" in err[0] and "allowed" in err[0]


def _subparser(name):
    parser = build_parser()
    return parser._subparsers._group_actions[0].choices[name]  # noqa: SLF001


def test_solve_help_documents_every_option_with_unit_default_and_range():
    units = ("mm", "Pa", "degrees", "ul/s", "N/m", "dimensionless")
    for action in _subparser("solve")._actions:  # noqa: SLF001
        if not action.option_strings or action.dest in ("help", "quiet"):
            continue
        text = help_with_allowed(action, action.help) or ""   # as --help prints it
        assert text, action.dest
        if action.dest in ("json", "csv", "plot", "vtk"):
            continue
        assert "default" in text, action.dest
        if action.type in (float, int):
            assert any(u in text for u in units) or action.dest == "mesh", action.dest
            assert " to " in text, action.dest  # the allowed range
        elif not action.choices:
            assert "pdms_1_10" in text, action.dest  # the allowed materials


def test_the_same_flag_names_across_subcommands():
    for name in ("solve", "predict", "inverse"):
        flags = {s for a in _subparser(name)._actions for s in a.option_strings}  # noqa: SLF001
        assert {"--body-material", "--membrane-material", "--L-mm", "--t-mm"} <= flags, name


def test_one_name_per_csv_column(tmp_path, capsys):
    from test_store import record_for

    from solver.io import CSV_COLUMNS, curve_to_csv
    from solver.store import CurveStore

    record = record_for(L_mm=7.1)
    with CurveStore(tmp_path / "c.h5", mode="a") as db:
        db.put(record)
    assert main(["db", "export", str(tmp_path / "c.h5"), "--format", "csv"]) == 0
    export_header = capsys.readouterr().out.splitlines()[0].split(",")
    curve_to_csv(record.curve, str(tmp_path / "solve.csv"))
    solve_header = (tmp_path / "solve.csv").read_text().splitlines()[0].split(",")
    assert export_header[-len(CSV_COLUMNS):] == solve_header == list(CSV_COLUMNS)
    assert "tip_dx_mm" in solve_header and "tip_x_mm" not in export_header


def _inline_python() -> list[str]:
    return re.findall(r"^In Python: `([^`]+)`", README, flags=re.M)


@pytest.mark.parametrize("code", [
    pytest.param(c, marks=pytest.mark.slow) if "solve(" in c else c for c in _inline_python()])
def test_readme_python_lines_run_as_written(code, capsys):
    exec(compile(code, "README.md", "exec"), {})  # noqa: S102 - the README's own code


def test_readme_has_both_python_lines():
    assert len(_inline_python()) == 2


def test_calibration_doc_block_runs_as_written(tmp_path, monkeypatch, capsys):
    import shutil

    text = (ROOT / "docs" / "calibration.md").read_text()
    block = re.findall(r"```python\n(.*?)```", text, flags=re.S)[0]
    data = tmp_path / "surrogate" / "calibration" / "data"
    data.mkdir(parents=True)
    shutil.copy(ROOT / "surrogate" / "calibration" / "data" / "example_lab.csv", data)
    monkeypatch.chdir(tmp_path)  # the block's relative paths, as from the repo root
    exec(compile(block, "docs/calibration.md", "exec"), {})  # noqa: S102
    assert (tmp_path / "report.png").read_bytes()[:4] == b"\x89PNG"
    assert (tmp_path / "models" / "lab1.json").is_file()


def test_solve_snippet_is_in_the_readme_and_says_when_the_key_is_missing(tmp_path):
    import os
    import subprocess

    snippet = (ROOT / "docs" / "snippets" / "solve.sh").read_text().rstrip("\n")
    assert any(block.rstrip("\n") == snippet for block in _code_blocks("sh"))
    env = {k: v for k, v in os.environ.items() if k != "BALLOON_API_KEY"}
    env["BALLOON_URL"] = "http://127.0.0.1:9"  # nothing listens: it must stop before curl
    r = subprocess.run(["bash", str(ROOT / "docs" / "snippets" / "solve.sh")], env=env,
                       capture_output=True, text=True, timeout=30)
    assert r.returncode != 0 and "set BALLOON_API_KEY" in r.stderr, r
    assert "Traceback" not in r.stderr and r.stdout == ""


def test_readme_says_to_install_httpx_for_the_client_snippets():
    assert "pip install httpx" in README
