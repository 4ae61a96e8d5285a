"""Shared fixtures: small hand-made scenes and one cached run of the built-in demo."""

from __future__ import annotations

from pathlib import Path

import sys

import numpy as np
import pytest

from camplace.spec.loading import parse_scene

REPO = Path(__file__).resolve().parents[1]
SHARED = REPO.parent / "shared"


def box_room(obstacles=(), targets=None, mounts=None, footprint=None, height=3.0, voxel=0.25, cameras=None):
    """A scene spec for hand-checked geometry tests (defaults: 4 m x 4 m x 3 m room)."""
    return parse_scene({
        "name": "test-room",
        "voxel_size": voxel,
        "occupancy_resolution": 0.05,
        "room": {"footprint": footprint or [[0, 0], [4, 0], [4, 4], [0, 4]], "height": height},
        "obstacles": list(obstacles),
        "targets": targets or [{"name": "walkable", "kind": "volume", "heights": [1.0], "coverage": 1}],
        "cameras": cameras or [{"name": "cam", "resolution": [640, 480], "fov_deg": [90, 70], "max_range": 10.0}],
        "mounts": mounts or [{"kind": "ceiling_grid", "camera": "cam", "spacing": 1.0,
                              "yaw_deg": [0], "pitch_deg": [45]}],
    })


def two_storeys(upper: float = 3.5):
    """A generated two-storey building (issue 33): Ground 8 m x 6 m, 'Level 1' 6 m x 6 m at
    ``upper`` m with a 1 m x 1 m floor opening at (2..3, 2..3) and a desk box; both 3 m tall,
    2 cameras each (storey budgets), one layer of 0.5 m targets at 1 m, occupancy 0.1 m."""
    cam = [{"name": "cam", "resolution": [640, 480], "fov_deg": [90, 70], "max_range": 10.0}]
    return parse_scene({
        "name": "two-storeys", "voxel_size": 0.5, "occupancy_resolution": 0.1, "cameras": cam,
        "targets": [{"name": "floor", "kind": "volume", "heights": [1.0], "coverage": 1}],
        "mounts": [{"kind": "ceiling_grid", "camera": "cam", "spacing": 2.0, "yaw_deg": [0, 180], "pitch_deg": [45]}],
        "storeys": {
            "Ground": {"elevation": 0.0, "room": {"footprint": [[0, 0], [8, 0], [8, 6], [0, 6]], "height": 3.0},
                       "budget": 2},
            "Level 1": {"elevation": upper, "room": {"footprint": [[0, 0], [6, 0], [6, 6], [0, 6]], "height": 3.0},
                        "floor_openings": [[[2, 2], [3, 2], [3, 3], [2, 3]]], "budget": 2,
                        "obstacles": [{"name": "desk", "box": {"min": [4, 4, 0], "max": [5, 5, 1.0]}}]},
        },
    })


def builtin_inputs(name: str):
    """(scene, targets, candidates) of a built-in scene, before visibility."""
    from camplace.spec.builtin import resolve_scene
    from camplace.cameras.models import camera_from_spec
    from camplace.cameras.candidates import build_candidates
    from camplace.scene.build import build_scene
    from camplace.targets.build import build_targets

    spec, _, _ = resolve_scene(name)
    sc = build_scene(spec)
    t = build_targets(sc)
    c = build_candidates(sc, {x.name: camera_from_spec(x) for x in spec.cameras})
    return sc, t, c


def same_csr(a, b) -> None:
    """Assert two CSR matrices are identical bit for bit (shape, dtype, indptr, indices, data)."""
    assert a.shape == b.shape and a.dtype == b.dtype
    assert np.array_equal(a.indptr, b.indptr) and np.array_equal(a.indices, b.indices)
    assert np.array_equal(a.data, b.data)


@pytest.fixture(scope="session")
def demo_inputs():
    """(scene, targets, candidates) of the built-in demo (built once per test session)."""
    return builtin_inputs("demo")


@pytest.fixture(scope="session")
def demo_run():
    """The whole pipeline on the built-in demo scene (run once per test session)."""
    from camplace.workflows.run import run

    return run("demo")


@pytest.fixture(scope="session")
def demo_out(tmp_path_factory, demo_run):
    """The demo run's output folder (contract files)."""
    from camplace.outputs.write import write_outputs

    out = tmp_path_factory.mktemp("demo-out")
    r = demo_run
    write_outputs(out, r.scene.name, r.visibility, r.placement, r.problem.budget, r.metrics, r.timings_s)
    return out


@pytest.fixture(scope="module")
def demo_dir(tmp_path_factory, demo_run):
    """The demo run's contract files (grid placement, no report) in a folder of this module's
    own (the planner tests save into it)."""
    from camplace.outputs.write import write_outputs

    out = tmp_path_factory.mktemp("planner-demo")
    r = demo_run
    write_outputs(out, r.scene.name, r.visibility, r.placement, r.problem.budget, r.metrics, r.timings_s,
                  scene=r.scene, report=False)
    return out


@pytest.fixture(scope="module")
def opened(demo_dir):
    """camplace.planner.opening.open_start on :func:`demo_dir`."""
    from camplace.planner.opening import open_start

    return open_start(demo_dir)


def small_random_problem(seed: int, n_g: int = 9, n_p: int = 10, budget: int = 3, n_loc: int = 5,
                         density: float = 0.4, weighted: bool = False):
    """A random PlacementProblem small enough for brute force (bound tests)."""
    import numpy as np
    import scipy.sparse as sp

    from camplace.problem.model import PlacementProblem

    rng = np.random.default_rng(seed)
    V = sp.csr_matrix((rng.random((n_g, n_p)) < density).astype(np.uint8))
    gamma = rng.integers(0, 4, n_p)
    w = rng.uniform(0.2, 3.0, n_p) if weighted else np.ones(n_p)
    loc = rng.integers(0, n_loc, n_g)
    return PlacementProblem(V, gamma, w, budget, loc)


def small_problems():
    """Hypothesis strategy over small_random_problem (up to 9 candidates, 10 targets)."""
    from hypothesis import strategies as st

    return st.builds(small_random_problem, seed=st.integers(0, 10**6), n_g=st.integers(1, 9),
                     n_p=st.integers(1, 10), budget=st.integers(0, 4), n_loc=st.integers(1, 6),
                     density=st.floats(0.1, 0.8), weighted=st.booleans())


# A tiny valid scene (bad-input, config and fuzz tests mutate copies of it) and the CLI in-process.
BASE = {
    "name": "tiny",
    "voxel_size": 0.5,
    "occupancy_resolution": 0.1,
    "room": {"footprint": [[0, 0], [3, 0], [3, 3], [0, 3]], "height": 3.0},
    "obstacles": [{"name": "crate", "box": {"min": [1.0, 1.0, 0.0], "max": [2.0, 2.0, 1.0]}}],
    "targets": [{"name": "walk", "kind": "volume", "heights": [1.5], "coverage": 1}],
    "cameras": [{"name": "cam", "resolution": [640, 480], "fov_deg": [90, 70], "max_range": 10.0}],
    "mounts": [{"kind": "ceiling_grid", "camera": "cam", "spacing": 1.0,
                "yaw_deg": {"start": 0, "stop": 180, "step": 180}, "pitch_deg": [45]}],
    "placement": {"budget": 2, "solver": "greedy"},
}


def run_cli(args, monkeypatch, capsys) -> tuple[int, str]:
    """camplace.cli.main() with argv = ['camplace', *args] -> (exit code, stdout + stderr)."""
    monkeypatch.setattr(sys, "argv", ["camplace", *map(str, args)])
    from camplace.cli import main

    code = 0
    try:
        main()
    except SystemExit as e:
        code = e.code if isinstance(e.code, int) else (0 if e.code is None else 1)
    cap = capsys.readouterr()
    return code, cap.out + cap.err




def import_and_evaluate(plan: Path, placement: Path, folder: Path, monkeypatch, capsys) -> Path:
    """camplace scene import PLAN, then camplace evaluate of ``placement`` on that scene (no
    plan set) into ``folder``/ev; both must succeed -> the evaluation's folder."""
    scene = folder / f"{plan.stem}.yaml"
    for args in (["scene", "import", plan, "--out", scene],
                 ["evaluate", scene, placement, "--out", folder / "ev", "--no-plan"]):
        code, text = run_cli(args, monkeypatch, capsys)
        assert code == 0, text
    return folder / "ev"


def plugin_dist(root: Path, name: str, groups: dict[str, dict[str, str]], modules: dict[str, str]) -> None:
    """A distribution ``name`` installed in ``root`` (a dist-info with entry_points.txt:
    group -> {entry point: 'module:attr'}) with ``modules`` (module name -> source text);
    put ``root`` on sys.path and reload the registries to see it."""
    import textwrap

    info = root / f"{name.replace('-', '_')}-0.1.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: 0.1\n")
    text = "".join(f"[{g}]\n" + "".join(f"{k} = {v}\n" for k, v in eps.items()) for g, eps in groups.items())
    (info / "entry_points.txt").write_text(text)
    for mod, src in modules.items():
        (root / f"{mod}.py").write_text(textwrap.dedent(src))


def read_or_one_line(read, path):
    """``read(path)``'s result, or None when it raised InputError with one line naming the
    file (the bad-file contract); any other exception propagates and fails the test."""
    from camplace.core.errors import InputError

    try:
        return read(path)
    except InputError as err:
        msg = str(err)
        assert str(path) in msg and "\n" not in msg, msg
        return None
