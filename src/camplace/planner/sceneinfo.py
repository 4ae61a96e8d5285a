"""GET /api/scene: the static data the page draws (room, obstacles, zones, mounts, lenses)."""

from __future__ import annotations

import numpy as np

from camplace.planner.storeys import storeys_payload

def _poly(points) -> list:
    return np.round(np.asarray(points, float), 4).tolist()


def budget_solvers() -> list[str]:
    """The registered solvers that fill a camera budget (POST /api/optimize), greedy first."""
    from camplace.solvers import SOLVERS

    names = sorted(n for n, x in SOLVERS.items() if not x.tags.ignores_camera_budget)
    return sorted(names, key=lambda n: n != "greedy")


def scene_payload(session) -> dict:
    """The /api/scene object (see docs/planner.md) of a camplace.planner.session.Session."""
    from camplace.outputs.plan_data import site_areas

    sc = session.scene
    occ = sc.occupancy
    lo = np.asarray(occ.origin, float)
    hi = lo + np.array(occ.shape) * occ.resolution
    fp = np.asarray(sc.footprint, float)
    bounds = [[float(fp[:, 0].min()), float(fp[:, 1].min()), 0.0],
              [float(fp[:, 0].max()), float(fp[:, 1].max()), float(sc.height)]]
    obstacles = [{"name": name, "polygon": _poly([[b0[0], b0[1]], [b1[0], b0[1]], [b1[0], b1[1]], [b0[0], b1[1]]]),
                  "zmin": float(b0[2]), "zmax": float(b1[2])} for name, (b0, b1) in sc.boxes.items()]
    obstacles += [{"name": name, "polygon": _poly(poly), "zmin": float(z0), "zmax": float(z1)}
                  for name, (poly, z0, z1) in sc.prisms.items()]
    areas = site_areas(sc)
    tg = session.targets
    return {"name": sc.name, "bounds": bounds, "grid_bounds": [lo.tolist(), hi.tolist()], "footprint": _poly(fp),
            "height": float(sc.height), "obstacles": obstacles,
            "zones": [{"name": n, "polygon": _poly(p)} for kind, n, p in areas if kind == "zone"],
            "privacy": [{"name": n, "polygon": _poly(p)} for kind, n, p in areas if kind == "privacy"],
            "mount_rules": [{"kind": kind, "name": n, "polygon": _poly(p)} for kind, n, p in areas
                            if kind in ("forbid", "allow")],
            "mounts": np.round(session.mounts, 4).tolist(),
            "camera_types": [{"name": c.name, "hfov_deg": float(c.fov_deg[0]), "vfov_deg": float(c.fov_deg[1]),
                              "max_range_m": float(c.max_range), "cost": float(c.cost), "model": c.model}
                             for c in session.lenses],
            "budget": int(session.budget), "working_height_m": float(session.height),
            "targets_xy": np.round(tg.positions[session.floor, :2], 4).tolist(),
            "targets_gamma": tg.gamma[session.floor].astype(int).tolist(),
            "coverage_required": int(tg.gamma[session.floor].max()) if len(session.floor) else 0,
            "solvers": budget_solvers(),
            "target_z_m": float(tg.positions[session.floor[0], 2]) if len(session.floor) else None,
            "target_cell_m": float(sc.spec.voxel_size) * session.floor_step,
            **storeys_payload(sc, session.height, session.floor, tg, session.mounts)}
