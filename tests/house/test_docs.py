"""Every ``camplace.x.y`` that the docs and the README name exists (a module, or a name in one):
a moved or renamed piece of code cannot leave the documentation pointing at nothing."""

from __future__ import annotations

import importlib
import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
DOCS = sorted((REPO / "docs").glob("*.md")) + [REPO / "README.md"]
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
    names = sorted({n.rstrip(".") for n in NAME.findall(doc.read_text())})
    missing = [n for n in names if not resolves(n)]
    assert not missing, f"{doc.name} names code that does not exist: {missing}"
