"""The planner session: the cameras of a placement being adjusted by hand, with live metrics.

A session holds the prepared scene (camplace.planner.opening.Opened: scene, targets, the
grid visibility), the run's visibility engine, the cameras (:class:`Cam`: id, pose, type,
locked; each with its visibility row over the targets and its viewshed) and the
per-target coverage counts. A change raycasts only the camera it touches (one-row
``compute_visibility`` on a one-candidate Candidates), updates the coverage by that
row, and rescores from the per-target counts (camplace.planner.scoring.LiveScore: the
figures of camplace.workflows.run.placement_metrics, the scoring of ``camplace evaluate``,
kept up to date from the changed cameras only, so a saved placement evaluates to the
same metrics). Each camera's placement.json object is built once, when it is made.
Every change is undoable (snapshots of the immutable camera tuple). Positions snap to
the nearest allowed mount (the grid candidates' positions) unless ``snap`` is false;
then they must satisfy the mount rules (camplace.cameras.mount_rules), lie in free
space and keep the mount clearance from walls and obstacles. A pose that sees a privacy zone is refused (camplace.visibility.privacy).
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field, replace

import numpy as np
import shapely
from scipy.spatial import cKDTree

from camplace.cameras.candidates import Candidates, location_ids_of, rotation_from_ypr, surface_back
from camplace.cameras.mount_rules import allowed_xy, clear_of_occupied
from camplace.metrics.coverage import Metrics
from camplace.planner.errors import ApiError
from camplace.planner.opening import Opened
from camplace.planner.scoring import LiveScore, rows_matrix
from camplace.planner.statejson import POSITIONAL, CameraObject, dumps
from camplace.planner.storeys import (check_in_storey, floor_z, nearest_layer, same_height, storey_at,
                                      storey_floor_layer, storey_mounts, storey_names, storeys_of, viewshed_height)
from camplace.visibility.engine import Visibility, compute_visibility
from camplace.visibility.registry import get_engine

UNDO_DEPTH = 200  # changes kept for undo
MAX_RASTER_POINTS = 20000  # the coverage raster (targets_xy) is thinned to at most this many points


@dataclass(frozen=True)
class Cam:
    """One camera of the session. position: (3,) m; angles: (3,) yaw, pitch, roll deg;
    lens: index into Session.lenses; row: (k,) int32 sorted target ids it sees; shed:
    its viewshed exterior [[x, y], ...] m at the working height; existing: an existing
    camera of the site (stays where it is); privacy: sorted ids of the privacy points it
    sees; entry: its placement.json object but for ``candidate_id`` / ``location_id``
    (camplace.outputs.write.camera_entries, made once)."""

    id: str
    position: np.ndarray
    angles: np.ndarray
    lens: int
    locked: bool
    existing: bool
    row: np.ndarray
    shed: list
    privacy: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int32))
    entry: dict | None = None

    @property
    def rotation(self) -> np.ndarray:
        return rotation_from_ypr(*self.angles)[0]


def _ring(geom) -> list:
    """The exterior of a viewshed geometry's largest part as [[x, y], ...] (m, 3 decimals)."""
    if geom is None or geom.is_empty:
        return []
    parts = list(getattr(geom, "geoms", [geom]))
    big = max(parts, key=lambda g: g.area)
    return np.round(np.asarray(big.exterior.coords), 3).tolist()


def floor_layer(targets, height: float) -> np.ndarray:
    """Indices of the volume targets in the layer nearest ``height`` m (the coverage raster)."""
    return nearest_layer(targets.positions[:, 2], np.flatnonzero(~targets.is_surface), height)


class Session:
    """The state behind ``camplace serve`` (thread-safe: every call holds ``lock``)."""

    def __init__(self, opened: Opened) -> None:
        from camplace.outputs.plan_data import free_floor
        from camplace.visibility.viewshed import WORKING_HEIGHT
        from camplace.workflows.sites import privacy_guard

        self.opened = opened
        self.scene = opened.scene
        self.vis = opened.vis
        self.targets = opened.vis.targets
        self.lenses = tuple(opened.vis.candidates.cameras)
        self.lens_index = {c.name: k for k, c in enumerate(self.lenses)}
        self.engine = get_engine("voxel")
        self.guard = privacy_guard(self.scene, self.lenses, self.engine)
        self.budget = int(opened.budget)
        self.height = WORKING_HEIGHT
        # the free floor at the working height, per storey of a building (issue 33)
        self.clips = [free_floor(st.scene, WORKING_HEIGHT) for st in storeys_of(self.scene)] or [
            free_floor(self.scene, WORKING_HEIGHT)]
        self.mounts = self._mount_positions()
        self.mount_tree = cKDTree(self.mounts)
        layer = storey_floor_layer(self.targets, self.scene, WORKING_HEIGHT)
        self.floor_step = max(1, int(np.ceil(len(layer) / MAX_RASTER_POINTS)))
        self.floor = layer[::self.floor_step]  # the targets of the page's coverage raster
        self.lock = threading.RLock()
        self.version = 0
        self.timing = {"raycast": 0.0, "viewshed": 0.0, "metrics": 0.0, "total": 0.0}
        self.undo_stack: list[tuple[Cam, ...]] = []  # camera tuples before each change (ids never reused)
        self.redo_stack: list[tuple[Cam, ...]] = []
        self.next_id = 1
        self.busy: str | None = None  # an optimisation job holds the cameras
        self.job = None  # the last camplace.planner.optimize.Job
        self._json: dict[int, tuple] = {}  # id(Cam) -> (Cam, static object, its JSON): camplace.planner.statejson
        cams = []
        given = {str(c["id"]) for c in opened.cameras if c.get("existing") and "id" in c}
        for c in opened.cameras:
            lens = self._lens_of(str(c.get("camera")), "camera")
            pos = np.asarray(c["position"], float)
            ang = np.array([c["yaw_deg"], c["pitch_deg"], c["roll_deg"]], float)
            cid = str(c["id"]) if c.get("existing") and "id" in c else self._fresh_id(given)
            cams.append(self._make(cid, pos, ang, lens, bool(c.get("existing")), bool(c.get("existing"))))
        self.cams: tuple[Cam, ...] = tuple(self._with_privacy(cams))
        self.live = LiveScore(self.targets, self.guard, self.cams)
        self._score()

    # ------------------------------------------------------------------ helpers

    def _mount_positions(self) -> np.ndarray:
        """(M, 3) m: the distinct allowed mount positions (every grid pose's position)."""
        from camplace.cameras.candidates import build_candidates

        cams = {c.name: c for c in self.lenses}
        pos = build_candidates(self.scene, cams).positions
        if not len(pos):
            pos = self.vis.candidates.positions
        return np.unique(np.round(pos, 6), axis=0)

    def _fresh_id(self, taken: set[str] = frozenset()) -> str:
        """C1, C2, ...: the next id never given before and not taken by a loaded camera."""
        taken = set(taken) | {c.id for c in getattr(self, "cams", ())}
        while f"C{self.next_id}" in taken:
            self.next_id += 1
        self.next_id += 1
        return f"C{self.next_id - 1}"

    def _lens_of(self, name, field: str) -> int:
        if not isinstance(name, str) or name not in self.lens_index:
            raise ApiError(f"{field}: unknown camera type {name!r}; expected one of "
                           f"{', '.join(self.lens_index)}", field)
        return self.lens_index[name]

    def _candidates(self, positions: np.ndarray, angles: np.ndarray, lenses: np.ndarray) -> Candidates:
        positions = np.asarray(positions, float).reshape(-1, 3)
        angles = np.asarray(angles, float).reshape(-1, 3)
        return Candidates(np.ascontiguousarray(positions), rotation_from_ypr(angles[:, 0], angles[:, 1], angles[:, 2]),
                          angles.copy(), np.asarray(lenses, np.int32).reshape(-1), location_ids_of(positions),
                          self.lenses)

    def _raycast(self, position: np.ndarray, angles: np.ndarray, lens: int) -> np.ndarray:
        """The sorted target ids one pose sees (one row through the run's engine)."""
        one = self._candidates(position, angles, [lens])
        V = compute_visibility(self.engine, self.scene.occupancy, self.targets, one).V
        return np.sort(V.indices[V.indptr[0]:V.indptr[1]]).astype(np.int32)

    def _viewshed(self, position: np.ndarray, angles: np.ndarray, lens: int) -> list:
        from camplace.visibility.viewshed import viewshed

        vs = viewshed(self.scene.occupancy, self.lenses[lens], position, rotation_from_ypr(*angles)[0],
                      viewshed_height(self.scene, position[2], self.height),
                      clip=self.clips[int(storey_at(self.scene, position[2])[0])])
        return _ring(vs.polygon)

    def _make(self, cid: str, pos: np.ndarray, ang: np.ndarray, lens: int, locked: bool, existing: bool,
              row: np.ndarray | None = None) -> Cam:
        """A camera with its row (raycast here unless given), viewshed and placement.json object."""
        from camplace.outputs.write import camera_entries

        t = time.perf_counter()
        row = self._raycast(pos, ang, lens) if row is None else row
        t1 = time.perf_counter()
        shed = self._viewshed(pos, ang, lens)
        self.timing["raycast"] = 1000.0 * (t1 - t)
        self.timing["viewshed"] = 1000.0 * (time.perf_counter() - t1)
        entry = camera_entries(self._candidates(pos, ang, [lens]), np.zeros(1, np.int64))[0]
        return Cam(cid, pos, ang, lens, locked, existing, row, shed, entry=entry)

    def _with_privacy(self, cams: list[Cam]) -> list[Cam]:
        """``cams`` with their privacy rows (one batch through the guard)."""
        if self.guard is None or not cams:
            return cams
        seen = self.guard.seen_points(self._candidates(np.array([c.position for c in cams]),
                                                       np.array([c.angles for c in cams]), [c.lens for c in cams]))
        return [replace(c, privacy=np.sort(seen.indices[seen.indptr[k]:seen.indptr[k + 1]]).astype(np.int32))
                for k, c in enumerate(cams)]

    @property
    def cov(self) -> np.ndarray:
        """(N_p,) int64: views of each target by the session's cameras."""
        return self.live.cov

    def visibility(self) -> tuple[Visibility, np.ndarray]:
        """The session's cameras as a Visibility (row k = camera k) and the selection (all)."""
        n = len(self.cams)
        cands = self._candidates(np.array([c.position for c in self.cams]).reshape(-1, 3),
                                 np.array([c.angles for c in self.cams]).reshape(-1, 3), [c.lens for c in self.cams])
        V = rows_matrix([c.row for c in self.cams], len(self.targets))
        return Visibility(V, cands, self.targets, self.engine.mode, engine=self.engine), np.arange(n, dtype=np.int64)

    def _score(self) -> None:
        """metrics of the current cameras, as camplace.workflows.evaluate scores them."""
        t = time.perf_counter()
        self.metrics: Metrics = self.live.metrics()
        self.timing["metrics"] = 1000.0 * (time.perf_counter() - t)

    def _index(self, cid: str) -> int:
        for k, c in enumerate(self.cams):
            if c.id == cid:
                return k
        raise ApiError(f"id: no camera {cid!r} (cameras: {', '.join(c.id for c in self.cams) or 'none'})", "id", 404)

    def _idle(self) -> None:
        if self.busy is not None:
            raise ApiError(f"optimize: job {self.busy} is running; cancel it or wait for it to finish", "optimize",
                           409)

    # ------------------------------------------------------------------ rules

    def snap(self, position: np.ndarray, taken: np.ndarray | None = None, storey: str | None = None) -> np.ndarray:
        """The allowed mount nearest ``position`` in plan (then in height), skipping the
        mounts (to 1 mm) in ``taken`` ((K, 3) m: other cameras' positions; one camera per
        location); only those of ``storey`` when named (a building). ApiError('position') when
        every mount is taken."""
        free = np.ones(len(self.mounts), bool) if storey is None else storey_mounts(self.scene, self.mounts, storey)
        if taken is not None and len(taken):  # mounts within 1 mm (each axis) of a taken position: a k-d tree
            near = self.mount_tree.query_ball_point(np.asarray(taken, float).reshape(-1, 3), r=1e-3, p=np.inf)
            free[np.concatenate([np.asarray(n, np.int64) for n in near])] = False
        if not free.any():
            raise ApiError("position: every allowed mount already holds a camera", "position", 409)
        d2 = np.where(free, ((self.mounts[:, :2] - position[:2]) ** 2).sum(1), np.inf)
        near = np.flatnonzero(d2 <= d2.min() + 1e-9)
        best = near[np.argmin(np.abs(self.mounts[near, 2] - position[2]))]
        return self.mounts[best].astype(float).copy()

    def mount_height(self, xy: np.ndarray) -> float:
        """The height of the allowed mount nearest ``xy`` (for positions given as [x, y])."""
        d2 = ((self.mounts[:, :2] - xy[:2]) ** 2).sum(1)
        return float(self.mounts[int(np.argmin(d2)), 2])

    def check_position(self, position: np.ndarray) -> None:
        """ApiError('position') unless the point lies inside the room, inside the mount
        rules' allowed area and in free space."""
        x, y, z = (float(v) for v in position)
        if storeys_of(self.scene):
            check_in_storey(self.scene, position)
        elif not shapely.intersects_xy(self.scene.polygon, x, y):
            raise ApiError(f"position: ({x:.3f}, {y:.3f}) is outside the room's footprint", "position")
        if not 0.0 < z < self.scene.height:
            raise ApiError(f"position: height {z:.3f} m is outside the room (0..{self.scene.height:g} m)", "position")
        if not allowed_xy(self.scene, np.array([[x, y]]))[0]:
            raise ApiError(f"position: ({x:.3f}, {y:.3f}) breaks the scene's mount rules (forbid / allow areas)",
                           "position")
        if self.scene.occupancy.is_occupied(np.array([[x, y, z]]))[0]:
            raise ApiError(f"position: ({x:.3f}, {y:.3f}, {z:.3f}) lies inside an obstacle", "position")
        if not clear_of_occupied(self.scene, np.array([[x, y, z]]), surface_back(self.scene, position))[0]:
            raise ApiError(f"position: ({x:.3f}, {y:.3f}, {z:.3f}) is closer than the mount clearance "
                           f"({self.scene.spec.mount_rules.clearance:g} m, mount_rules.clearance) to a wall or "
                           "obstacle; move it away or let it snap", "position")

    def check_privacy(self, position: np.ndarray, angles: np.ndarray, lens: int, field: str) -> None:
        """ApiError(field) when the pose sees a point of a privacy zone."""
        if self.guard is None:
            return
        seen = self.guard.seen_points(self._candidates(position, angles, [lens]))
        if seen.nnz:
            pts = self.guard.points
            names = sorted({pts.region_names[r] for r in pts.region_ids[np.unique(seen.indices)]})
            raise ApiError(f"{field}: this pose sees the privacy zone(s) {', '.join(names)} (a hard rule); turn or "
                           f"move the camera", field, 409)

    # ------------------------------------------------------------------ changes

    def _commit(self, cams: tuple[Cam, ...], t0: float) -> dict:
        """Make ``cams`` current (previous state onto the undo stack) and rescore."""
        self.undo_stack.append(self.cams)
        del self.undo_stack[:-UNDO_DEPTH]
        self.redo_stack.clear()
        self._apply(cams)
        self.timing["total"] = 1000.0 * (time.perf_counter() - t0)
        return self.state()

    def _apply(self, cams: tuple[Cam, ...]) -> None:
        """Make ``cams`` current; the score follows from the cameras that changed (LiveScore)."""
        self.cams = cams
        self.live.change(cams)
        self.version += 1
        self._score()

    def update(self, cid: str, change: dict) -> dict:
        """PUT /api/cameras/{id}: ``change`` validated by camplace.planner.bodies.camera_change."""
        with self.lock:
            self._idle()
            t0 = time.perf_counter()
            k = self._index(cid)
            cam = self.cams[k]
            locked = change.get("locked", cam.locked)
            pose_keys = [f for f in ("position", "storey", "yaw_deg", "pitch_deg", "roll_deg", "camera") if f in change]
            if pose_keys and (locked or cam.existing):
                why = "an existing camera of the site" if cam.existing else "locked; unlock it first"
                raise ApiError(f"{pose_keys[0]}: camera {cid} is {why}", pose_keys[0], 409)
            if cam.existing and not locked:
                raise ApiError(f"locked: camera {cid} is an existing camera of the site; it stays locked", "locked",
                               409)
            pos = cam.position
            if "storey" in change:  # another floor (issue 33): that storey's mount nearest in plan
                xy = np.asarray(change.get("position", pos), float)[:2]
                pos = self._place(np.r_[xy, same_height(self.scene, pos[2], change["storey"])], True, cam.id,
                                  change["storey"])
            elif "position" in change:
                pos = self._place(change["position"], change.get("snap", True), cam.id)
            ang = cam.angles.copy()
            for j, f in enumerate(("yaw_deg", "pitch_deg", "roll_deg")):
                if f in change:
                    ang[j] = change[f]
            ang[0] %= 360.0
            lens = self._lens_of(change["camera"], "camera") if "camera" in change else cam.lens
            if not pose_keys:
                new = replace(cam, locked=bool(locked))
                self.timing.update(raycast=0.0, viewshed=0.0)
                return self._commit(self.cams[:k] + (new,) + self.cams[k + 1:], t0)
            self.check_privacy(pos, ang, lens, pose_keys[0])
            new = self._make(cam.id, pos, ang, lens, bool(locked), cam.existing)
            return self._commit(self.cams[:k] + (new,) + self.cams[k + 1:], t0)

    def _place(self, position: np.ndarray, snap: bool, moving: str | None = None,
               storey: str | None = None) -> np.ndarray:
        """Where a camera goes: ``position`` snapped to a free allowed mount (a building: of
        ``storey``, else of the storey at its z) or checked as it is."""
        pos = np.asarray(position, float)
        if len(pos) == 2:
            pos = np.r_[pos, self.mount_height(pos) if storey is None else floor_z(self.scene, storey)]
        if snap:
            others = [c.position for c in self.cams if c.id != moving]
            if storey is None and storeys_of(self.scene):
                storey = storey_names(self.scene, [pos[2]])[0]
            return self.snap(pos, np.array(others, float).reshape(-1, 3), storey)
        self.check_position(pos)
        return pos

    def add(self, body: dict) -> dict:
        """POST /api/cameras: a new camera (fresh id) at ``position`` (snapped by default)."""
        with self.lock:
            self._idle()
            t0 = time.perf_counter()
            pos = self._place(body["position"], body.get("snap", True), storey=body.get("storey"))
            ang = np.array([body.get("yaw_deg", 0.0), body.get("pitch_deg", 45.0), body.get("roll_deg", 0.0)], float)
            ang[0] %= 360.0
            lens = self._lens_of(body["camera"], "camera") if "camera" in body else 0
            self.check_privacy(pos, ang, lens, "position")
            new = self._make(self._fresh_id(), pos, ang, lens, bool(body.get("locked", False)), False)
            return self._commit(self.cams + (new,), t0)

    def delete(self, cid: str) -> dict:
        """DELETE /api/cameras/{id} (an existing or locked camera is refused)."""
        with self.lock:
            self._idle()
            t0 = time.perf_counter()
            k = self._index(cid)
            cam = self.cams[k]
            if cam.locked or cam.existing:
                raise ApiError(f"id: camera {cid} is {'an existing camera' if cam.existing else 'locked'}; unlock "
                               f"it before deleting it", "id", 409)
            self.timing.update(raycast=0.0, viewshed=0.0)
            return self._commit(self.cams[:k] + self.cams[k + 1:], t0)

    def grid_cam(self, position: np.ndarray, angles: np.ndarray, lens: int, row: np.ndarray) -> Cam:
        """A new unlocked camera at a grid pose whose row is already known (its viewshed
        computed here; its privacy row in replace_unlocked)."""
        return self._make(self._fresh_id(), position, angles, lens, False, False, row)

    def replace_unlocked(self, new_cams: list[Cam], t0: float) -> None:
        """The result of an optimisation: the locked cameras kept, the others replaced (one undo step)."""
        with self.lock:
            new_cams = self._with_privacy(list(new_cams))
            self._commit(tuple(c for c in self.cams if c.locked) + tuple(new_cams), t0)

    def undo(self) -> dict:
        return self._step(self.undo_stack, self.redo_stack, "undo")

    def redo(self) -> dict:
        return self._step(self.redo_stack, self.undo_stack, "redo")

    def _step(self, source: list, target: list, name: str) -> dict:
        with self.lock:
            self._idle()
            t0 = time.perf_counter()
            if not source:
                raise ApiError(f"{name}: nothing to {name}", name, 409)
            cams = source.pop()
            target.append(self.cams)
            self.timing.update(raycast=0.0, viewshed=0.0)
            self._apply(cams)
            self.timing["total"] = 1000.0 * (time.perf_counter() - t0)
            return self.state()

    # ------------------------------------------------------------------ views

    def camera_objects(self) -> list[dict]:
        """placement.json camera objects (camplace.outputs.write.camera_entries, each made once
        with its camera) + id, locked, existing, viewshed; ``candidate_id`` is the camera's
        row, ``location_id`` numbers the positions of all cameras."""
        loc = location_ids_of(np.array([c.position for c in self.cams]).reshape(-1, 3))
        hits = {id(c): self._json.get(id(c)) for c in self.cams}
        cache = {id(c): h if h is not None and h[0] is c else (c, *self._static(c)) for c, h in
                 zip(self.cams, hits.values())}
        self._json = cache  # only the current cameras' encodings are kept
        return [CameraObject(k, loc[k], *cache[id(c)][1:]) for k, c in enumerate(self.cams)]

    def _static(self, c: Cam) -> tuple[dict, str]:
        """A camera's state object but for its positional keys, and its JSON (made once per camera)."""
        obj = {key: v for key, v in c.entry.items() if key not in POSITIONAL}
        obj.update(id=c.id, locked=c.locked, existing=c.existing, viewshed=c.shed, targets_seen=len(c.row))
        if storeys_of(self.scene):
            obj["storey"] = storey_names(self.scene, [c.position[2]])[0]
        return obj, dumps(obj)

    def state(self) -> dict:
        """GET /api/state (see /api in docs/planner.md)."""
        with self.lock:
            m = self.metrics.to_dict()
            zones = []
            for name, fig in m["regions"].items():
                idx = np.flatnonzero(np.asarray(self.targets.region_ids) ==
                                     list(self.targets.region_names).index(name))
                full = float(np.mean(self.cov[idx] >= self.targets.gamma[idx])) if len(idx) else 1.0
                zones.append({"name": name, "coverage": full, "gap": fig["coverage_gap"], **fig})
            fl = self.floor
            return {"version": self.version, "cameras": self.camera_objects(), "metrics": m, "zones": zones,
                    "coverage_floor": np.minimum(self.cov[fl], self.targets.gamma[fl]).astype(int).tolist(),
                    "n_cameras": len(self.cams), "budget": self.budget, "busy": self.busy,
                    "can_undo": bool(self.undo_stack), "can_redo": bool(self.redo_stack),
                    "timing_ms": {k: round(v, 2) for k, v in self.timing.items()}}
