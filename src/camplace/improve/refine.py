"""Pose refinement: move each selected camera off the grid to lower the true cost.

After the discrete solve, each selected camera is moved continuously - its position on
its mount surface within half a grid spacing of its grid point, yaw / pitch / roll within
half an angle step, a varifocal lens's focal length within the lens's range (issue 27) -
by a derivative-free compass (pattern) search. Each poll raycasts only the camera that
moves (the <= 10 trial poses of one poll), against the scene occupancy and targets,
through the engine that computed V with its parameters (``Visibility.engine``: voxel or
pixel mode, probe rule), so every row added to V follows V's own rule. The coverage of the other
cameras is kept, so a trial costs one raycast and an O(row) cost delta:

    cost(c_o + r) = cost(c_o) - Σ_{j in r} g_j,  g_j = w_j (max(Γ_j - c_oj, 0)² - max(Γ_j - c_oj - 1, 0)²)

where c_o is the coverage by the other cameras and r the trial pose's row. A move is
accepted only if the true cost drops. Sweeps over the cameras repeat until no move helps
or the time limit is reached.

The refined poses are appended to V as new rows (``append_candidates``): a new position
is a new location, a position equal (to 1 mm) to an existing one reuses its location id.
So the output keeps the contract - every camera is a row of the written V - and the
reported cost is recomputed from V.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import Callable

import numpy as np
import scipy.sparse as sp
import shapely

from camplace.cameras.candidates import Candidates, focal_models, rotation_from_ypr
from camplace.cameras.mount_rules import CEILING_BACK, occupied_distance, restrict_region
from camplace.spec.schema import Mount, SceneSpec, angle_values
from camplace.problem import gains
from camplace.problem.model import PlacementProblem, type_ids_of
from camplace.scene.build import OccupancyGrid, Scene, storey_index
from camplace.solvers.base import Placement
from camplace.targets.build import Targets
from camplace.visibility.engine import Visibility, VisibilityEngine, raycast_rows
from camplace.visibility.registry import engine_of

Progress = Callable[[str, int, int], None]
# A pose guard: (poses (K, 6) x, y, z, yaw, pitch, roll; camera ids (K,)) -> (K,) bool, True = allowed
# (camplace.visibility.privacy.PrivacyGuard: the pose sees no privacy point)
PoseGuard = Callable[[np.ndarray, np.ndarray], np.ndarray]
# A row map: (the poses as Candidates (K), raycast V rows (K, N_p)) -> the problem's rows of those
# poses (K, N_p') (None: the raycast rows themselves; a crowd-aware run: the rows with the
# poses' views of the people in the same crowd samples, camplace.workflows.crowd)
RowMap = Callable[[Candidates, sp.csr_matrix], sp.csr_matrix]
HALF = 0.499  # stay strictly inside half a step so neighbouring grid points never meet
WALL_Z_STEP, WALL_Z_LOW, WALL_Z_TOP = 1.0, 1.0, 0.1  # m: a crowd-aware run's wall cameras move in height (issue 36)
FOCAL = 6  # column of the focal length (mm) in a refined pose (x, y, z, yaw, pitch, roll, focal_mm); issue 27


# --------------------------------------------------------------------------- helpers


def angle_step(a) -> float:
    """Smallest spacing between the distinct values of a mount angle spec (0 if single)."""
    v = np.unique(np.asarray(angle_values(a), float))
    if len(v) < 2:
        return 0.0
    return float(np.min(np.diff(v)))


@dataclass(frozen=True)
class PoseBox:
    """Where one camera may move: centre pose (x, y, z, yaw, pitch, roll) and half
    ranges (hx, hy, 0, hyaw, hpitch, hroll) in metres / degrees; ``region`` is the mount
    surface's allowed footprint (shapely geometry) at height z; ``clearance``: the metres a
    moved position keeps from every wall and obstacle (``mount_rules.clearance``)."""

    centre: np.ndarray
    half: np.ndarray
    region: object
    clearance: float = 0.0


def mount_of(spec: SceneSpec, camera_name: str, z: float) -> Mount | None:
    """The mount that produces a camera of this type at this height (None if none)."""
    for m in spec.mounts:
        if camera_name not in m.camera_names:
            continue
        kind = getattr(m, "kind", "ceiling_grid")
        mz = float(m.height) if kind == "wall" else spec.room.height - m.offset_below_ceiling
        if abs(mz - z) < 1e-6:
            return m
    return None


def pose_box(scene: Scene, candidates: Candidates, i: int, fraction: float = HALF) -> PoseBox:
    """The search box of candidate i: ``fraction`` of its mount's grid spacing and angle
    steps around it. Wall-mount cameras stay at their wall point and only turn; a pose
    not from any mount may only turn, by 15° / 7.5°. The pitch steps are those of the mount's
    pitches and of the candidates' ``info['extra_pitches']`` (a crowd-aware run's steep views);
    in such a run a wall camera may also move up or down its wall by ``fraction`` of
    WALL_Z_STEP (between WALL_Z_LOW above the floor and WALL_Z_TOP below the ceiling)."""
    cam = candidates.cameras[int(candidates.camera_ids[i])]
    p = candidates.positions[i]
    centre = np.r_[p, candidates.angles_deg[i]]
    if scene.storeys:  # a building: the mounts and rules of the storey the camera hangs in
        scene = scene.storeys[int(storey_index(scene.storeys, p[2:3])[0])]
        p = p - [0.0, 0.0, scene.elevation]
        scene = scene.scene
    m = mount_of(scene.spec, cam.name, float(p[2]))
    if m is None:
        half = np.array([0, 0, 0, 30.0, 15.0, 0.0]) * fraction
        region = scene.polygon
    else:
        s = 0.0 if getattr(m, "kind", "ceiling_grid") == "wall" else float(m.spacing)  # wall cameras only turn
        pitches = angle_values(m.pitch_deg) + list(candidates.info.get("extra_pitches", []))  # + a crowd's steep views
        half = np.array([s, s, 0.0, angle_step(m.yaw_deg), angle_step(pitches), angle_step(m.roll_deg)]) * fraction
        if s == 0.0 and "extra_pitches" in candidates.info:  # a crowd-aware run: a wall camera may move up or down
            half[2] = max(0.0, min(WALL_Z_STEP * fraction, scene.height - WALL_Z_TOP - p[2], p[2] - WALL_Z_LOW))
        region = scene.polygon.buffer(-m.wall_clearance) if m.wall_clearance > 0 else scene.polygon
    rules = scene.spec.mount_rules
    if rules.active:  # mount rules bound the search (camplace.cameras.mount_rules): explicit points only turn
        region = restrict_region(scene, region)
        if rules.points is not None:
            half[:3] = 0.0
    return PoseBox(centre, half, region, float(rules.clearance))


def single_pose_candidates(template: Candidates, camera_id: int, poses: np.ndarray) -> Candidates:
    """Candidates for trial poses (K, 6) x, y, z, yaw, pitch, roll of one camera type, or
    (K, 7) with the focal length (mm) a lens as sold is set to (camplace.cameras.candidates.focal_models)."""
    poses = np.atleast_2d(np.asarray(poses, float))
    rot = rotation_from_ypr(poses[:, 3], poses[:, 4], poses[:, 5])
    cams, ids = template.cameras, np.full(len(poses), camera_id, np.int32)
    if poses.shape[1] > FOCAL:
        cams, ids = focal_models(cams, ids, poses[:, FOCAL])
    return Candidates(poses[:, :3].copy(), rot, poses[:, 3:FOCAL].copy(), ids, np.arange(len(poses), dtype=np.int64),
                      cams)


def raycast_poses(engine: VisibilityEngine, occupancy: OccupancyGrid, targets: Targets, template: Candidates,
                  camera_id: int, poses: np.ndarray) -> sp.csr_matrix:
    """V rows (K, N_p) of trial poses (K, 6) or (K, 7) (single_pose_candidates), raycast afresh by ``engine``."""
    return raycast_rows(engine, occupancy, targets, single_pose_candidates(template, camera_id, poses))


def focal_box(camera, fraction: float = HALF) -> np.ndarray:
    """(4,) focal length (mm) of a camera in refinement: current value, first step half, lowest,
    highest. A varifocal lens moves within its whole range, starting with ``fraction`` of its
    grid's mean focal step; any other camera keeps its focal length (half 0)."""
    lens, f = camera.lens, float(camera.focal_mm or 0.0)
    if lens is None or not lens.varifocal:
        return np.array([f, 0.0, f, f])
    step = (lens.focal_max_mm - lens.focal_min_mm) / max(lens.steps - 1, 1)
    return np.array([f, step * fraction, lens.focal_min_mm, lens.focal_max_mm])


def append_candidates(vis: Visibility, occupancy: OccupancyGrid, poses: np.ndarray,
                      camera_ids: np.ndarray) -> tuple[Visibility, np.ndarray]:
    """Raycast new poses (K, 6), or (K, 7) with a focal length (mm; camplace.cameras.candidates.focal_models
    adds its camera settings), by V's own engine and append them to V as rows; returns the new Visibility and
    the row ids (K,) of the new poses. Location rule: a position equal (to 1 mm) to an
    existing one reuses that location id, a new position is a new location."""
    poses = np.atleast_2d(np.asarray(poses, float))
    cands = vis.candidates
    camera_ids = np.asarray(camera_ids, np.int32)
    cams = cands.cameras
    if poses.shape[1] > FOCAL and len(poses):
        cams, camera_ids = focal_models(cams, camera_ids, poses[:, FOCAL])
    rot = rotation_from_ypr(poses[:, 3], poses[:, 4], poses[:, 5])
    angles = poses[:, 3:FOCAL].copy()
    angles[:, 0] %= 360.0
    new = Candidates(poses[:, :3].copy(), rot, angles, camera_ids, np.zeros(len(poses), np.int64), cams)
    rows = raycast_rows(engine_of(vis), occupancy, vis.targets, new)
    key_of = {tuple(k): int(l) for k, l in zip(np.round(cands.positions * 1000).astype(np.int64).tolist(),
                                                 cands.location_ids.tolist())}
    next_id = int(cands.location_ids.max()) + 1 if len(cands) else 0
    loc = np.empty(len(poses), np.int64)
    for n, k in enumerate(np.round(poses[:, :3] * 1000).astype(np.int64).tolist()):
        k = tuple(k)
        if k not in key_of:
            key_of[k] = next_id
            next_id += 1
        loc[n] = key_of[k]
    merged = replace(cands, positions=np.r_[cands.positions, new.positions],
                     rotations=np.r_[cands.rotations, new.rotations],
                     angles_deg=np.r_[cands.angles_deg, new.angles_deg],
                     camera_ids=np.r_[cands.camera_ids, camera_ids].astype(np.int32),
                     location_ids=np.r_[cands.location_ids, loc], cameras=cams)
    V = sp.vstack([vis.V, rows.astype(np.uint8)], format="csr")
    V.sort_indices()
    info = dict(vis.info, appended=int(vis.info.get("appended", 0)) + len(poses))
    first = vis.V.shape[0]
    return replace(vis, V=V, candidates=merged, info=info), np.arange(first, first + len(poses), dtype=np.int64)


def extend_problem(problem: PlacementProblem, vis: Visibility, row_map: RowMap | None = None) -> PlacementProblem:
    """The same problem over an extended V (new rows: prices and types from their camera type;
    with ``row_map``, the problem's rows of the appended poses come through it)."""
    V = vis.V
    if row_map is not None:
        n = problem.n_candidates
        new = vis.candidates.subset(np.arange(n, vis.V.shape[0]))
        V = sp.vstack([problem.V, row_map(new, vis.V[n:])], format="csr")
    costs = np.array([vis.candidates.cameras[c].cost for c in vis.candidates.camera_ids], np.float64)
    types = None if problem.type_ids is None else _appended_groups(problem, vis.candidates)
    return replace(problem, V=V, location_ids=vis.candidates.location_ids, camera_costs=costs, type_ids=types)


def _appended_groups(problem: PlacementProblem, cands: Candidates) -> np.ndarray:
    """(N_g',) int64 limit group of every row of the extended candidates: the problem's for
    its rows; an appended pose takes the group of the nearest original pose of its camera
    type (refined and adaptive poses stay near their origin, on its storey; issue 33)."""
    from scipy.spatial import cKDTree

    n = problem.n_candidates
    old = np.asarray(problem.type_ids, np.int64)
    out = np.r_[old, np.full(len(cands) - n, -1, np.int64)]
    types = type_ids_of(cands.camera_ids, [c.name for c in cands.cameras])
    for t in np.unique(types[n:]):
        src = np.flatnonzero(types[:n] == t)
        new = n + np.flatnonzero(types[n:] == t)
        if len(src):
            out[new] = old[src[cKDTree(cands.positions[src]).query(cands.positions[new])[1]]]
    return out


def target_gains(problem: PlacementProblem, cov_other: np.ndarray) -> np.ndarray:
    """(N_p,) g_j: cost drop from one more view of target j, given the others' coverage
    (camplace.problem.gains.target_gains of the problem's Γ and weights)."""
    return gains.target_gains(problem.gamma, problem.weights, cov_other)


def _row_sums(rows: sp.csr_matrix, g: np.ndarray) -> np.ndarray:
    return np.asarray(rows @ g).ravel() if rows.shape[0] else np.zeros(0)


# --------------------------------------------------------------------------- search


PoseScore = Callable[[sp.csr_matrix, np.ndarray, np.ndarray], np.ndarray]  # (rows (K, N_p), g, cov_other) -> (K,)


@dataclass(frozen=True)
class RefineResult:
    """visibility: V with the refined poses appended; placement: the refined selection on
    the extended problem (rows of that V); problem: the extended problem."""

    visibility: Visibility
    problem: PlacementProblem
    placement: Placement
    grid_cost: float
    refined_cost: float
    info: dict = field(default_factory=dict)


class _PolledRows:
    """The problem rows (of ``n_cols`` columns) of the trial poses raycast so far, by camera
    and pose (its bytes).

    A compass search polls the same poses again: the way back after a move, and every pose
    of a camera whose own pose stayed while its neighbours' moves changed its gains (the
    demo's refinement: 10,936 trial poses, 5,008 distinct). A pose gives the same row
    whenever it is raycast, so a remembered row changes nothing but the time. At most
    ``max_entries`` V entries are kept (then all but the current poll's are forgotten)."""

    def __init__(self, n_cols: int, max_entries: int = 20_000_000):
        self.n_cols, self.max_entries = n_cols, max_entries
        self.rows: dict[tuple[int, bytes], tuple[np.ndarray, np.ndarray]] = {}
        self.entries = 0

    def get(self, k: int, trial: np.ndarray, cast: Callable[[np.ndarray], sp.csr_matrix]) -> tuple[sp.csr_matrix, int]:
        """(rows (K, n_cols) of trial poses (K, 7) of camera k, how many were raycast): ``cast``
        gives the rows of the poses not seen before."""
        keys = [(k, p.tobytes()) for p in trial]
        new = [n for n, key in enumerate(keys) if key not in self.rows]
        if new:
            R = cast(trial[new])
            if self.entries + R.nnz > self.max_entries:  # forget all but this poll's poses seen before
                self.rows = {key: self.rows[key] for key in keys if key in self.rows}
                self.entries = sum(len(ix) for ix, _ in self.rows.values())
            for r, n in enumerate(new):
                self.rows[keys[n]] = (R.indices[R.indptr[r]:R.indptr[r + 1]], R.data[R.indptr[r]:R.indptr[r + 1]])
            self.entries += R.nnz
        got = [self.rows[key] for key in keys]
        indptr = np.r_[0, np.cumsum([len(ix) for ix, _ in got])]
        return sp.csr_matrix((np.concatenate([d for _, d in got]), np.concatenate([ix for ix, _ in got]), indptr),
                             shape=(len(keys), self.n_cols)), len(new)


def _valid_positions(box: PoseBox, occupancy: OccupancyGrid, poses: np.ndarray) -> np.ndarray:
    if len(poses) == 0:
        return np.zeros(0, bool)
    moved = np.any(np.abs(poses[:, :2] - box.centre[:2]) > 1e-9, axis=1)  # only ceiling-grid cameras move in plan
    # a camera that stays at its grid position only turns (or zooms): that position is valid as is (a wall
    # camera sits on the boundary of the region, which contains_xy would refuse); one that only moves up or
    # down its wall (a crowd-aware run) needs a free cell there
    up_down = ~moved & (np.abs(poses[:, 2] - box.centre[2]) > 1e-9)
    ok = ~moved | (shapely.contains_xy(box.region, poses[:, 0], poses[:, 1]) & ~occupancy.is_occupied(poses[:, :3]))
    ok[up_down] = ~occupancy.is_occupied(poses[up_down, :3])
    moved &= ok
    if box.clearance > 0 and moved.any():
        ok[moved] = occupied_distance(occupancy, poses[moved, :3], CEILING_BACK, box.clearance) >= box.clearance - 1e-6
    return ok


def refine_poses(scene: Scene, vis: Visibility, problem: PlacementProblem, selected: np.ndarray,
                 time_limit_s: float | None = 60.0, levels: int = 4, max_sweeps: int = 50,
                 progress: Progress | None = None,
                 guard: PoseGuard | None = None,
                 row_map: RowMap | None = None,
                 should_stop: Callable[[], bool] | None = None,
                 pose_score: PoseScore | None = None) -> tuple[np.ndarray, np.ndarray, list[sp.csr_matrix], dict]:
    """Compass search over each selected camera's pose (see module doc).

    Returns (poses (k, 7) x, y, z, yaw, pitch, roll, focal_mm; moved (k,) bool; rows: the k
    V rows of the final poses; info). Step sizes start at half the box half-range and halve
    ``levels`` times; a sweep visits every camera once; sweeps repeat while one helps. A
    varifocal lens's focal length is one more variable (``focal_box``; issue 27).
    ``guard`` rejects trial poses before they are raycast (e.g. poses that see a privacy zone).
    ``should_stop()`` is polled before each poll of trial poses (stopped 'interrupted': the
    poses reached so far are kept, each of them an accepted improvement). ``pose_score(R, g,
    cov_other)``: what a pose with row R is worth (default R @ g, the cost drop; e.g.
    camplace.improve.people.PeopleCountObjective.pose_scores)."""
    t0 = time.perf_counter()
    deadline = None if time_limit_s is None else t0 + float(time_limit_s)
    sel = np.asarray(selected, np.int64)
    cands = vis.candidates
    engine = engine_of(vis)
    boxes = [pose_box(scene, cands, int(i)) for i in sel]
    fbox = np.array([focal_box(cands.cameras[int(cands.camera_ids[i])]) for i in sel]).reshape(len(sel), 4)
    poses = np.c_[np.array([b.centre for b in boxes], float).reshape(len(sel), 6), fbox[:, 0]]
    rows = [problem.V[int(i)] for i in sel]
    moved = np.zeros(len(sel), bool)
    cov = problem.coverage(sel)
    trials = accepted = sweeps = raycast = 0
    polled = _PolledRows(problem.V.shape[1])
    stopped = "converged"
    for sweep in range(max_sweeps):
        sweeps += 1
        improved_any = False
        for k, i in enumerate(sel):
            if deadline is not None and time.perf_counter() > deadline:
                stopped = "time_limit"
                break
            if should_stop is not None and should_stop():
                stopped = "interrupted"
                break
            box = boxes[k]
            cid = int(cands.camera_ids[i])
            half = np.r_[box.half, fbox[k, 1]]
            lo, hi = np.r_[box.centre - box.half, fbox[k, 2]], np.r_[box.centre + box.half, fbox[k, 3]]
            if not (half > 0).any():
                continue
            r = rows[k]
            cov_o = cov.copy()
            cov_o[r.indices] -= 1
            g = target_gains(problem, cov_o)

            def admit(trial: np.ndarray, box=box, k=k, cid=cid) -> np.ndarray:
                ok = _valid_positions(box, scene.occupancy, trial) & _free_of_others(poses, k, trial)
                if guard is not None and ok.any():
                    ok[ok] = _guarded(guard, cands, cid, trial[ok])
                return ok

            score = None if pose_score is None else (lambda R, g=g, cov_o=cov_o: pose_score(R, g, cov_o))
            poses[k], rows[k], _, c = compass(
                poses[k], r, float(g[r.indices].sum()) if score is None else float(score(r)[0]), half, lo, hi, g,
                levels, admit,
                lambda t, k=k, cid=cid: polled.get(k, t, lambda u: _trial_rows(engine, scene, vis, cid, u, row_map)),
                lambda: (deadline is not None and time.perf_counter() > deadline) or (
                    should_stop is not None and should_stop()), score)
            trials, raycast, accepted = trials + c["trials"], raycast + c["raycast"], accepted + c["accepted"]
            if c["accepted"]:
                moved[k] = improved_any = True
            cov = cov_o
            cov[rows[k].indices] += 1
            if progress:
                progress("refine", k + 1, len(sel))
        if stopped in ("time_limit", "interrupted") or not improved_any:
            break
    info = {"trials": trials, "raycast": raycast, "accepted_moves": accepted, "sweeps": sweeps, "stopped": stopped,
            "seconds": time.perf_counter() - t0}
    return poses, moved, rows, info


def compass(pose: np.ndarray, row: sp.csr_matrix, cur: float, half: np.ndarray, lo: np.ndarray, hi: np.ndarray,
            g: np.ndarray, levels: int, admit: Callable[[np.ndarray], np.ndarray],
            rows_of: Callable[[np.ndarray], tuple[sp.csr_matrix, int]],
            halt: Callable[[], bool],
            score: Callable[[sp.csr_matrix], np.ndarray] | None = None) -> tuple[np.ndarray, sp.csr_matrix, float, dict]:
    """Compass search of one camera's pose (7,) within [lo, hi] (see module doc): polls of ±step
    along each coordinate with half > 0 (steps from half / 2, halved ``levels`` times), the poses
    ``admit`` keeps, scored by their rows (``rows_of(trial)`` -> (rows, how many raycast)) against
    the target gains ``g`` (N_p,); a poll's best pose is taken while it beats ``cur`` (the score
    Σ g of ``row``; ``score(rows)`` -> (K,) scores them instead, e.g. a crowd-aware run's count).
    Returns (pose, row, score, dict(trials, raycast, accepted)); ``halt()`` ends it."""
    dims = np.flatnonzero(half > 0)
    step = half / 2.0
    n = {"trials": 0, "raycast": 0, "accepted": 0}
    for _ in range(levels):
        while not halt():
            trial = []
            for d in dims:
                for sgn in (1.0, -1.0):
                    p = pose.copy()
                    p[d] = np.clip(p[d] + sgn * step[d], lo[d], hi[d])
                    if abs(p[d] - pose[d]) > 1e-9:
                        trial.append(p)
            if not trial:
                break
            trial = np.array(trial)
            trial = trial[admit(trial)]
            if len(trial) == 0:
                break
            R, cast = rows_of(trial)
            n["trials"] += len(trial)
            n["raycast"] += cast
            s = _row_sums(R, g) if score is None else score(R)
            b = int(np.argmax(s))
            if s[b] > cur + 1e-9:
                pose, row, cur = trial[b], R[b], float(s[b])
                n["accepted"] += 1
                continue
            break
        step = step / 2.0
    return pose, row, cur, n


def _free_of_others(poses: np.ndarray, k: int, trial: np.ndarray) -> np.ndarray:
    """(K,) bool: the trial positions not at (to 1 mm) another camera's current position (m);
    two cameras there would share a location. A box re-centred on a refined pose (a second
    refinement, camplace.improve.quality) can reach a neighbour's position."""
    others = np.round(np.delete(poses[:, :3], k, axis=0) * 1000).astype(np.int64)
    mine = np.round(trial[:, :3] * 1000).astype(np.int64)
    return ~(mine[:, None, :] == others[None, :, :]).all(-1).any(1)


def _trial_rows(engine: VisibilityEngine, scene: Scene, vis: Visibility, cid: int, trial: np.ndarray,
                row_map: RowMap | None) -> sp.csr_matrix:
    """The problem's rows of trial poses (K, 7) of camera type ``cid``: raycast by ``engine``, then
    (with ``row_map``) scored as the problem's rows (e.g. on the same crowd samples)."""
    cands = single_pose_candidates(vis.candidates, cid, trial)
    R = raycast_rows(engine, scene.occupancy, vis.targets, cands)
    return R if row_map is None else row_map(cands, R)


def _guarded(guard: PoseGuard, cands: Candidates, cid: int, trial: np.ndarray) -> np.ndarray:
    """guard(poses (K, 6), camera ids) of trial poses (K, 7); with the cameras tuple when a trial
    changes a focal length (camplace.visibility.privacy.PrivacyGuard takes it)."""
    cams, ids = focal_models(cands.cameras, np.full(len(trial), cid, np.int32), trial[:, FOCAL])
    return guard(trial[:, :FOCAL], ids) if len(cams) == len(cands.cameras) else guard(trial[:, :FOCAL], ids,
                                                                                       cameras=cams)


def refine_placement(scene: Scene, vis: Visibility, problem: PlacementProblem, placement: Placement,
                     time_limit_s: float | None = 60.0, progress: Progress | None = None,
                     **search_options) -> RefineResult:
    """Refine the placement's poses and append the moved ones to V (see module doc);
    ``search_options``: refine_poses' (levels, max_sweeps, guard, should_stop).

    The returned placement selects, for every camera, its refined row (a new row of V when
    it moved, its grid row otherwise); its objective is recomputed from the extended V."""
    t0 = time.perf_counter()
    sel = np.asarray(placement.selected, np.int64)
    grid_cost = problem.cost(sel)
    poses, moved, _, info = refine_poses(scene, vis, problem, sel, time_limit_s, progress=progress, **search_options)
    vis2, new_ids = append_candidates(vis, scene.occupancy, poses[moved], vis.candidates.camera_ids[sel[moved]])
    prob2 = extend_problem(problem, vis2, search_options.get("row_map"))
    final = sel.copy()
    final[moved] = new_ids
    final = np.sort(final)
    prob2.check_feasible(final)
    cost = prob2.cost(final)
    info = dict(info, grid_cost=grid_cost, refined_cost=cost, moved=int(moved.sum()), grid_solver=placement.solver)
    p2 = Placement(final, cost, None, "heuristic", f"{placement.solver}+refine",
                   placement.seconds + time.perf_counter() - t0, dict(placement.info, refine=info))
    return RefineResult(vis2, prob2, p2, grid_cost, cost, info)


__all__ = ["PoseBox", "RefineResult", "angle_step", "append_candidates", "compass", "extend_problem", "pose_box",
           "raycast_poses", "refine_placement", "refine_poses", "target_gains"]
