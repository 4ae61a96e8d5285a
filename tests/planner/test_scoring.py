"""The planner's live score (camplace.planner.scoring): after any series of edits, the
incremental update gives exactly the metrics of a full recomputation (issue 37)."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from camplace.planner.errors import ApiError
from camplace.planner.scoring import LiveScore, rows_matrix
from camplace.planner.session import Session


def full_metrics(s: Session) -> dict:
    """The session's cameras scored from scratch by placement_metrics (camplace evaluate's scoring)."""
    from camplace.workflows.run import placement_metrics, problem_from_visibility

    vis, sel = s.visibility()
    return placement_metrics(vis, problem_from_visibility(vis, len(sel)), sel).to_dict()


def test_incremental_metrics_equal_a_full_recompute_after_a_series_of_edits(opened):
    s = Session(opened)
    rng = np.random.default_rng(5)
    calls = []
    real = s.live.full
    s.live.full = lambda cams: calls.append(len(cams)) or real(cams)
    changes = [
        lambda c: s.update(c.id, {"yaw_deg": float(rng.uniform(0, 360)), "pitch_deg": float(rng.uniform(20, 60))}),
        lambda c: s.update(c.id, {"position": s.mounts[int(rng.integers(len(s.mounts)))].tolist()}),
        lambda c: s.update(c.id, {"camera": s.lenses[-1].name, "roll_deg": 5.0}),
        lambda c: s.add({"position": s.mounts[int(rng.integers(len(s.mounts)))][:2].tolist(), "yaw_deg": 90.0}),
        lambda c: s.undo(),
        lambda c: s.redo(),
        lambda c: s.update(c.id, {"locked": not c.locked}),
        lambda c: s.delete(next(d for d in s.cams if not d.locked).id),
    ]
    costs = set()
    for k in range(24):
        c = next(d for d in s.cams[int(rng.integers(len(s.cams))):] + s.cams if not d.locked)
        changes[k % len(changes)](c)
        got, want = s.metrics.to_dict(), full_metrics(s)
        got.pop("timings_s"), want.pop("timings_s")
        assert got == want, f"edit {k}"
        costs.add(got["cost"])
    assert len(costs) > 5  # the edits changed the score
    assert calls == []  # every edit was incremental


@dataclass(frozen=True)
class FakeCam:
    """What LiveScore reads of a camera."""

    id: str
    position: np.ndarray
    row: np.ndarray
    privacy: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int32))


class FakeTargets:
    def __init__(self, n: int, rng) -> None:
        self.positions = rng.uniform(0, 10, (n, 3))
        self.gamma = rng.integers(1, 4, n)
        self.weights = rng.choice([0.5, 1.0, 3.0], n)
        self.region_ids = rng.integers(0, 2, n)
        self.region_names = ("a", "b")

    def __len__(self) -> int:
        return len(self.positions)


def fake_cam(rng, k: int, n: int) -> FakeCam:
    return FakeCam(f"C{k}", rng.uniform(0, 10, 3), np.flatnonzero(rng.random(n) < 0.4).astype(np.int32))


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), steps=st.lists(st.integers(0, 3), min_size=1, max_size=12))
def test_live_score_after_any_swaps_equals_a_fresh_one(seed, steps):
    rng = np.random.default_rng(seed)
    n = 60
    targets = FakeTargets(n, rng)
    cams = tuple(fake_cam(rng, k, n) for k in range(6))
    live = LiveScore(targets, None, cams)
    history = [cams]
    for k, step in enumerate(steps):
        if step == 0 and cams:  # a camera turned: same id, new row
            j = int(rng.integers(len(cams)))
            cams = cams[:j] + (replace(fake_cam(rng, 0, n), id=cams[j].id),) + cams[j + 1:]
        elif step == 1:  # added
            cams = cams + (fake_cam(rng, 100 + k, n),)
        elif step == 2 and cams:  # deleted
            j = int(rng.integers(len(cams)))
            cams = cams[:j] + cams[j + 1:]
        else:  # back to an earlier state (undo)
            cams = history[int(rng.integers(len(history)))]
        history.append(cams)
        live.change(cams)
        fresh = LiveScore(targets, None, cams)
        assert np.array_equal(live.cov, fresh.cov) and np.array_equal(live.well, fresh.well)
        assert live.metrics() == fresh.metrics()
        V = rows_matrix([c.row for c in cams], n)
        assert np.array_equal(live.cov, np.asarray(V.sum(0)).ravel())


def test_rows_matrix_of_no_rows_is_empty():
    V = rows_matrix([], 7)
    assert V.shape == (0, 7) and V.nnz == 0


@pytest.mark.parametrize("gone", [0, 3])
def test_many_swaps_rescore_from_scratch(gone):
    rng = np.random.default_rng(gone)
    targets = FakeTargets(30, rng)
    cams = tuple(fake_cam(rng, k, 30) for k in range(8))
    live = LiveScore(targets, None, cams)
    calls = []
    real = live.full
    live.full = lambda c: calls.append(1) or real(c)
    live.change(cams[:8 - gone] + tuple(fake_cam(rng, 50 + k, 30) for k in range(gone)))
    assert calls == ([1] if gone == 3 else [])  # 6 swapped of 8 > a quarter: from scratch
    assert np.array_equal(live.well, LiveScore(targets, None, live.cams).well)


def test_privacy_report_from_cached_rows_equals_a_fresh_raycast(tmp_path):
    """A scene with a privacy zone: the report from each camera's privacy row is privacy_report's."""
    from test_session import SITE

    from camplace.planner.opening import open_start
    from camplace.spec.loading import parse_scene
    from camplace.visibility.privacy import privacy_report

    s = Session(open_start(parse_scene(SITE), root=tmp_path))
    assert s.guard is not None
    done = 0
    for k, yaw in enumerate((0.0, 90.0, 180.0, 270.0) * 2):
        try:
            s.update(s.cams[k // 4].id, {"yaw_deg": yaw, "pitch_deg": 60.0})
        except ApiError:  # a pose that sees the office is refused (the state stays)
            continue
        done += 1
        vis, sel = s.visibility()
        want = privacy_report(s.guard, vis.candidates, sel, [c.id for c in s.cams])
        assert s.metrics.privacy == want and want["points"] > 0
    assert done >= 2
