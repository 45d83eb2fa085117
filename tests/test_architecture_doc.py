"""docs/architecture.md stays true as the code changes: every module of the three
packages is named there (or its folder, where the document lists a folder as a whole),
and every module file the document names exists."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOC = (ROOT / "docs" / "architecture.md").read_text()
PACKAGES = ("solver", "surrogate", "service")
# folders the document describes as a whole (one row), not module by module
WHOLE_FOLDERS = ("store", "verification", "effects", "commands", "routes", "schemas")


def modules() -> list[Path]:
    return sorted(p for pkg in PACKAGES for p in (ROOT / pkg).rglob("*.py")
                  if p.name != "__init__.py")


def test_every_module_is_named_in_the_architecture_document():
    unnamed = [str(p.relative_to(ROOT)) for p in modules()
               if f"`{p.name}`" not in DOC and f"{p.name}`" not in DOC
               and not (p.parent.name in WHOLE_FOLDERS and f"{p.parent.name}/`" in DOC)]
    assert not unnamed, f"modules docs/architecture.md does not name: {unnamed}"


def test_every_module_the_document_names_exists():
    names = set(re.findall(r"`([A-Za-z_][A-Za-z0-9_]*\.py)`", DOC))
    have = {p.name for pkg in PACKAGES + ("benchmarks",) for p in (ROOT / pkg).rglob("*.py")}
    assert names, "no module named in docs/architecture.md"
    assert not names - have, f"named but not in the code: {sorted(names - have)}"
