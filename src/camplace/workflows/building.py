"""Whole buildings (issue 33): every storey in one scene, one budget, one V.

A building is a scene with ``storeys:`` (camplace.spec.schema.Storey); camplace.scene.build
stacks the storeys at their elevations in one occupancy grid, and targets and candidates
are every storey's, raised to building z. Solvers, refinement and bounds see one
PlacementProblem; this module adds what is the building's own: the per-storey camera
limits (as limit groups of the problem), the storey of each camera and target, the
per-storey metrics, and the building scene mapping assembled from imported storeys.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from camplace.core.errors import InputError
from camplace.problem.gains import shortfall_cost
from camplace.problem.model import PlacementProblem
from camplace.scene.build import Scene, storey_index

SLAB_M = 0.2  # the slab kept between a storey's ceiling and the next floor when a plan gives no ceiling below it


def storey_names(sc: Scene) -> list[str]:
    """The storeys of a building scene, lowest first ([] for one room)."""
    return [st.name for st in sc.storeys]


def storey_of(sc: Scene, positions: np.ndarray) -> np.ndarray:
    """(N,) int64 storey index (into sc.storeys) of points (N, 3) in building z; zeros for one room."""
    p = np.asarray(positions, np.float64).reshape(-1, 3)
    if not sc.storeys:
        return np.zeros(len(p), np.int64)
    return storey_index(sc.storeys, p[:, 2])


def with_storey_limits(problem: PlacementProblem, sc: Scene, positions: np.ndarray) -> PlacementProblem:
    """``problem`` with at most ``storeys.NAME.budget`` cameras on each storey that has one
    (limit groups: type_ids = the candidate's storey, type_limits = the budgets); unchanged
    without per-storey budgets. Camera-type limits (mount_rules.max_per_type) and storey
    budgets together are refused: the problem holds one partition of limits."""
    limits = {k: int(st.budget) for k, st in enumerate(sc.storeys) if st.budget is not None}
    if not limits:
        return problem
    if problem.has_type_limits:
        raise InputError("storeys: per-storey budgets and mount_rules.max_per_type cannot be combined yet; "
                         "expected one of them")
    return replace(problem, type_ids=storey_of(sc, positions), type_limits=limits)


def storey_metrics(sc: Scene, problem: PlacementProblem, selected: np.ndarray, camera_positions: np.ndarray,
                   target_positions: np.ndarray) -> list[dict]:
    """Per storey: {storey, elevation_m, top_m, budget, cameras, targets, cost, coverage_gap,
    covered_share} of a selection (targets (N_p, 3) and selected cameras (k, 3) in building z;
    coverage from every camera of the building, so a view across an open floor counts)."""
    cov = problem.coverage(np.asarray(selected, np.int64))
    t_st = storey_of(sc, target_positions)
    c_st = storey_of(sc, camera_positions)
    out = []
    for k, st in enumerate(sc.storeys):
        m = t_st == k
        g, w = problem.gamma[m], problem.weights[m]
        norm = shortfall_cost(g, w, np.zeros(len(g), np.int64))
        cost = shortfall_cost(g, w, cov[m])
        out.append({"storey": st.name, "elevation_m": round(st.elevation, 4), "top_m": round(st.top, 4),
                    "budget": st.budget, "cameras": int(np.sum(c_st == k)), "targets": int(m.sum()),
                    "cost": float(cost), "coverage_gap": float(cost / norm) if norm > 0 else 0.0,
                    "covered_share": float(np.mean(cov[m] >= g)) if m.any() else 1.0})
    return out


def building_scene(name: str, storeys: list[tuple[str, dict, float, list]], budget: int | None = None,
                   notes: list[str] | None = None) -> dict:
    """The scene mapping of a building from imported storeys [(storey name, scene mapping
    (floor at z = 0, as a plan import makes it), floor elevation m, floor openings)], lowest
    first or not: the shared keys (cameras, targets, mounts, grids, placement) from the first
    storey, each storey's room, obstacles and zones under ``storeys:``. A storey whose
    ceiling would reach the next floor is lowered to SLAB_M below it; of two storeys less
    than MIN_STOREY_M apart (a split level, a storey drawn twice) the one with fewer rooms is
    left out, with a line in ``notes``."""
    if not storeys:
        raise InputError(f"{name}: no storey to plan")
    order = _distinct_levels(sorted(storeys, key=lambda s: s[2]), notes)
    first = order[0][1]
    data = {k: first[k] for k in ("voxel_size", "occupancy_resolution", "cameras", "targets", "mounts",
                                  "placement", "mount_rules", "free_space") if k in first}
    data["name"] = name
    if budget is not None:
        data["placement"] = {**data.get("placement", {}), "budget": int(budget)}
    out: dict = {}
    for k, (st_name, scene, elev, openings) in enumerate(order):
        room = dict(scene["room"])
        if k + 1 < len(order):
            gap = order[k + 1][2] - elev
            if room["height"] > gap - SLAB_M:
                room["height"] = round(float(max(gap - SLAB_M, 0.5 * gap)), 4)
        entry = {"elevation": float(elev), "room": room, "obstacles": _clip_obstacles(scene.get("obstacles", []),
                                                                                       room["height"]),
                 "zones": scene.get("zones", [])}
        for key in ("targets", "mounts"):
            if scene.get(key) is not None and scene[key] != first.get(key):
                entry[key] = scene[key]
        if openings:
            entry["floor_openings"] = [[[float(v) for v in p] for p in o] for o in openings]
        out[st_name] = entry
    data["storeys"] = out
    return data


MIN_STOREY_M = 2.0  # storeys closer than this cannot both hold people under their own ceiling


def _distinct_levels(order: list, notes: list[str] | None) -> list:
    """``order`` (by elevation) without the storeys that stand less than MIN_STOREY_M above
    the one kept below them (the one with more zones stays)."""
    out: list = []
    for st in order:
        if out and st[2] - out[-1][2] < MIN_STOREY_M:
            keep, drop = (st, out[-1]) if len(st[1].get("zones", [])) > len(out[-1][1].get("zones", [])) else (
                out[-1], st)
            out[-1] = keep
            if notes is not None:
                notes.append(f"storey '{drop[0]}' (floor at {drop[2]:g} m) is less than {MIN_STOREY_M:g} m from "
                             f"'{keep[0]}' ({keep[2]:g} m): planned as '{keep[0]}' alone")
            continue
        out.append(st)
    return out


def _clip_obstacles(obstacles: list[dict], height: float) -> list[dict]:
    """Obstacles cut at a storey's (lowered) ceiling; those entirely above it dropped."""
    out = []
    for ob in obstacles:
        ob = dict(ob)
        if "prism" in ob:
            z0, z1 = ob["prism"]["z"]
            if z0 >= height:
                continue
            ob["prism"] = {**ob["prism"], "z": [z0, min(z1, height)]}
        elif "box" in ob:
            lo, hi = ob["box"]["min"], ob["box"]["max"]
            if lo[2] >= height:
                continue
            ob["box"] = {"min": lo, "max": [hi[0], hi[1], min(hi[2], height)]}
        out.append(ob)
    return out


def align_plans(found: list[tuple[str, object, float]]) -> list[tuple[str, object, float]]:
    """Plans drawn side by side on one sheet [(storey, PlanImport, elevation)]: each plan's
    scene mapping (and floor openings) moved in plan so the lower-left corner of its
    footprint's bounding box meets the first plan's (a note says so)."""
    def corner(got) -> np.ndarray:
        return np.asarray(got.scene["room"]["footprint"], float).min(0)

    ref = corner(found[0][1])
    out = []
    for name, got, elev in found:
        d = ref - corner(got)
        if np.any(np.abs(d) > 1e-9):
            got.scene = _moved(got.scene, d)
            got.floor_openings = _moved(got.floor_openings, d, "polygons")
            got.notes.append(f"storey '{name}' moved by ({d[0]:.2f}, {d[1]:.2f}) m to stand on the first plan "
                             f"(plans side by side on one sheet are aligned on their lower-left corner)")
        out.append((name, got, elev))
    return out


_POINT_LISTS = ("footprint", "polygon")
_POLYGON_LISTS = ("holes", "floor_openings", "forbid", "allow", "polygons")


def _moved(obj, d: np.ndarray, kind: str | None = None):
    """A scene mapping (or part of one) moved by d (2,) m in plan: footprints, polygons,
    holes, boxes (x, y of min / max), wall segments; everything else as is."""
    def pts(ps):
        return [[round(float(p[0] + d[0]), 4), round(float(p[1] + d[1]), 4), *p[2:]] for p in ps]

    if kind == "points":
        return pts(obj)
    if kind == "polygons":
        return [pts(p) for p in obj]
    if isinstance(obj, dict):
        out = {}
        for k, v in obj.items():
            if k in _POINT_LISTS and isinstance(v, list):
                out[k] = pts(v)
            elif k in _POLYGON_LISTS and isinstance(v, list):
                out[k] = [pts(p) for p in v]
            elif k == "walls" and isinstance(v, list):
                out[k] = [pts(seg) for seg in v]
            elif k == "box" and isinstance(v, dict) and "min" in v:
                out[k] = {"min": pts([v["min"]])[0], "max": pts([v["max"]])[0]}
            else:
                out[k] = _moved(v, d)
        return out
    if isinstance(obj, list):
        return [_moved(v, d) for v in obj]
    return obj


def storey_groups(sc: Scene) -> list[list[int]]:
    """The storeys (indices, lowest first) that can see each other, grouped: a storey with
    floor openings joins the storey below; storeys with a solid slab between them are apart."""
    groups: list[list[int]] = []
    for k, st in enumerate(sc.storeys):
        if groups and st.openings:
            groups[-1].append(k)
        else:
            groups.append([k])
    return groups


def building_visibility(engine, sc: Scene, targets, candidates, **options):
    """V of a building, one storey group at a time (storey_groups): a camera never sees
    through a solid slab, so the blocks between groups are zero and are not raycast
    (camplace.visibility.engine.compute_visibility on each group's candidates and targets;
    ``options``: its executor, cache_dir, progress). The same V as one call on the whole
    building, in a fraction of the sight-line tests when floors are closed."""
    import scipy.sparse as sp

    from camplace.visibility.engine import Visibility, compute_visibility

    groups = storey_groups(sc)
    if len(groups) <= 1:  # one room, or storeys all open to each other
        return compute_visibility(engine, sc.occupancy, targets, candidates, **options)
    t_st, c_st = storey_of(sc, targets.positions), storey_of(sc, candidates.positions)
    rows, cols, info = [], [], {"storey_groups": [[sc.storeys[k].name for k in g] for g in groups]}
    for g in groups:
        r, c = np.flatnonzero(np.isin(c_st, g)), np.flatnonzero(np.isin(t_st, g))
        if not len(r) or not len(c):
            continue
        part = compute_visibility(engine, sc.occupancy, _take_targets(targets, c), candidates.subset(r), **options)
        coo = part.V.tocoo()
        rows.append(r[coo.row])
        cols.append(c[coo.col])
        for key, v in part.info.items():
            if isinstance(v, (int, float)) and not isinstance(v, bool):
                info[key] = info.get(key, 0) + v
            else:
                info.setdefault(key, v)
    r, c = (np.concatenate(a) if a else np.zeros(0, np.int64) for a in (rows, cols))
    V = sp.csr_matrix((np.ones(len(r), np.uint8), (r, c)), shape=(len(candidates), len(targets)))
    V.sort_indices()
    info["nnz"] = int(V.nnz)
    return Visibility(V, candidates, targets, engine.mode, info, engine)


def _take_targets(targets, cols: np.ndarray):
    """The targets ``cols`` (indices) only; regions kept whole."""
    return replace(targets, positions=targets.positions[cols], normals=targets.normals[cols],
                   gamma=targets.gamma[cols], weights=targets.weights[cols], region_ids=targets.region_ids[cols])
