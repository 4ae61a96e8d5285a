"""The rules of the house (docs/design.md), checked on the source tree itself.

- imports point down the pipeline's layers (LAYERS), never up, and never in a circle,
  not even inside a function (every ``import`` in the AST counts);
- solvers see only the problem: camplace.solvers imports camplace.core, camplace.problem
  and itself, never another stage (executors and memory release are in core/);
- no module over 500 lines;
- no library string names a CLI flag (only ``camplace.cli`` words errors for the
  command line).
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

SRC = Path(__file__).resolve().parents[2] / "src"
LAYERS = ["core", "spec", "scene", "targets", "cameras", "visibility", "problem", "metrics", "solvers", "improve",
          "outputs", "workflows", "planner", "cli"]
MAX_LINES = 500


def _modname(p: Path) -> str:
    parts = list(p.relative_to(SRC).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _modules() -> dict[str, Path]:
    return {_modname(p): p for p in sorted((SRC / "camplace").rglob("*.py"))}


def import_graph() -> dict[str, set[str]]:
    """module -> camplace modules it imports (``from pkg import sub`` counts as pkg.sub)."""
    mods = _modules()
    edges: dict[str, set[str]] = {}
    for m, p in mods.items():
        out: set[str] = set()
        for node in ast.walk(ast.parse(p.read_text())):
            if isinstance(node, ast.Import):
                out.update(a.name for a in node.names if a.name.startswith("camplace"))
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and (node.module or "").startswith("camplace"):
                for a in node.names:
                    sub = f"{node.module}.{a.name}"
                    out.add(sub if sub in mods else node.module)
        edges[m] = {o for o in out if o in mods and o != m}
    return edges


def _layer(m: str) -> int:
    parts = m.split(".")
    return LAYERS.index(parts[1]) if len(parts) > 1 and parts[1] in LAYERS else -1


def test_every_module_sits_in_a_layer():
    loose = [m for m in _modules() if m != "camplace" and _layer(m) < 0]
    assert not loose, f"modules outside the pipeline's packages: {loose}"


def test_imports_point_down():
    up = sorted(f"{m} -> {o}" for m, os in import_graph().items() for o in os
                if _layer(m) >= 0 and _layer(o) > _layer(m))
    assert not up, "imports that point up the pipeline:\n" + "\n".join(up)


SOLVER_SEES = {"core", "problem", "solvers"}


def test_solvers_import_only_problem_and_core():
    bad = sorted(f"{m} -> {o}" for m, os in import_graph().items() if m.startswith("camplace.solvers")
                 for o in os if o.split(".")[1] not in SOLVER_SEES)
    assert not bad, "solvers that reach into a stage other than problem/:\n" + "\n".join(bad)


def test_no_import_cycles():
    edges = import_graph()
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    cycles: list[list[str]] = []
    counter = [0]

    def visit(v: str) -> None:  # Tarjan's strongly connected components
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(edges.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                cycles.append(sorted(comp))

    for v in sorted(edges):
        if v not in index:
            visit(v)
    assert not cycles, f"import cycles: {cycles}"


def test_no_module_over_500_lines():
    long = {m: n for m, p in _modules().items() if (n := len(p.read_text().splitlines())) > MAX_LINES}
    assert not long, f"modules over {MAX_LINES} lines: {long}"


FLAG = re.compile(r"(?<![\w-])--[a-z][a-z0-9]*(?:-[a-z0-9]+)*")


def test_library_strings_name_no_cli_flag():
    hits = []
    for m, p in _modules().items():
        if m.startswith("camplace.cli"):
            continue
        tree = ast.parse(p.read_text())
        docstrings = {id(n.body[0].value) for n in ast.walk(tree)
                      if isinstance(n, (ast.Module, ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef))
                      and n.body and isinstance(n.body[0], ast.Expr) and isinstance(n.body[0].value, ast.Constant)}
        for node in ast.walk(tree):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docstrings:
                for flag in FLAG.findall(node.value):
                    hits.append(f"{m}:{node.lineno}: {flag}")
    assert not hits, "library strings that name CLI flags (word them in camplace.cli):\n" + "\n".join(hits)


def test_package_docstrings_and_the_design_table_agree_on_the_layers():
    """Each package's ``__init__`` docstring opens with 'camplace.<pkg> (layer N)' and
    docs/design.md's layer table gives the same N: the numbers cannot drift apart."""
    table = (SRC.parent / "docs" / "design.md").read_text()
    rows = dict((pkg, int(n)) for n, pkg in re.findall(r"^\| (\d+) \| `(\w+)/` \|", table, re.M))
    assert rows == {pkg: n for n, pkg in enumerate(LAYERS)}, rows
    wrong = []
    for n, pkg in enumerate(LAYERS):
        doc = ast.get_docstring(ast.parse((SRC / "camplace" / pkg / "__init__.py").read_text())) or ""
        if not doc.startswith(f"camplace.{pkg} (layer {n})"):
            wrong.append(f"{pkg}: {doc[:60]!r}")
    assert not wrong, "package docstrings that do not open with 'camplace.<pkg> (layer N)':\n" + "\n".join(wrong)


def test_test_modules_have_unique_basenames():
    """The tests are collected without packages (rootdir imports): two test modules with one
    basename stop the whole collection ('import file mismatch'), as twice this session."""
    names: dict[str, list[str]] = {}
    for p in sorted((Path(__file__).resolve().parents[1]).rglob("test_*.py")):
        names.setdefault(p.name, []).append(str(p.parent.name))
    assert not {n: d for n, d in names.items() if len(d) > 1}
