"""Every ``camplace.x.y`` that the docs and the README name exists (a module, or a name in one):
a moved or renamed piece of code cannot leave the documentation pointing at nothing."""

from __future__ import annotations

import importlib
import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
DOCS = sorted((REPO / "docs").glob("*.md")) + [REPO / "README.md"]
ENTRY_POINT_GROUPS = {"camplace.solvers", "camplace.engines", "camplace.importers", "camplace.outputs"}  # plugin groups (pyproject.toml), not modules
NAME = re.compile(r"(camplace(?:\.[A-Za-z_][A-Za-z0-9_]*)+)")


def resolves(dotted: str) -> bool:
    parts = dotted.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        try:
            for a in parts[i:]:
                obj = getattr(obj, a)
        except AttributeError:
            return False
        return True
    return False


@pytest.mark.parametrize("doc", DOCS, ids=[p.name for p in DOCS])
def test_docs_name_only_code_that_exists(doc):
    names = sorted({n.rstrip(".") for n in NAME.findall(doc.read_text())} - ENTRY_POINT_GROUPS)
    missing = [n for n in names if not resolves(n)]
    assert not missing, f"{doc.name} names code that does not exist: {missing}"


def test_every_registered_solver_and_engine_is_documented():
    """A built-in solver or engine (camplace's entry points) that the docs do not name
    cannot be merged: docs/solvers.md and the scene file's solver list name every solver,
    docs/engines.md every engine."""
    from camplace.solvers import SOLVERS
    from camplace.visibility import ENGINES

    solvers_md = (REPO / "docs" / "solvers.md").read_text()
    scene_md = (REPO / "docs" / "scene-file.md").read_text()
    engines_md = (REPO / "docs" / "engines.md").read_text()
    own = [n for n in SOLVERS if SOLVERS.distribution(n) == "camplace"]
    assert len(own) >= 15
    missing = [n for n in own if f"`{n}`" not in solvers_md or f"`{n}`" not in scene_md]
    assert not missing, f"solvers not named in docs/solvers.md and docs/scene-file.md: {missing}"
    missing = [m for m in ENGINES if ENGINES.distribution(m) == "camplace" and f"`{m}`" not in engines_md]
    assert not missing, f"engines not named in docs/engines.md: {missing}"


def test_every_registered_plan_format_and_output_is_documented():
    """camplace's own importers are rows of docs/plans.md's formats table, its own output
    writers are named in docs/output-contract.md (issue 35)."""
    from camplace.outputs.writers import OUTPUTS
    from camplace.scene.formats import IMPORTERS

    plans_md = (REPO / "docs" / "plans.md").read_text()
    contract_md = (REPO / "docs" / "output-contract.md").read_text()
    missing = [n for n in IMPORTERS if IMPORTERS.distribution(n) == "camplace" and f"| `{n}` |" not in plans_md]
    assert not missing, f"plan formats not in docs/plans.md's table: {missing}"
    missing = [n for n in OUTPUTS if OUTPUTS.distribution(n) == "camplace" and f"`{n}`" not in contract_md]
    assert not missing, f"output writers not named in docs/output-contract.md: {missing}"
