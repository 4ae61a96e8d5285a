"""Server-side time of one planner change (move / rotate / type) on standard-store or at site scale.

    python benchmarks/planner_speed.py [--changes 50] [--scene standard-store]
    camplace run warehouse:10000 --out out/wh
    python benchmarks/planner_speed.py --scene warehouse:10000 --run out/wh --changes 150
    python benchmarks/planner_speed.py --scene warehouse:1000 --run out/wh1k --cache ~/.cache/camplace --changes 0

Runs the scene once (grid, its own budget and solver) into a temporary run folder, or
opens the run folder ``--run`` (as ``camplace serve RUN --scene SCENE`` does:
camplace.planner), then sends ``changes`` PUT
/api/cameras/{id} requests through starlette's TestClient, cycling over move (to another
allowed mount), rotate (yaw + pitch) and type (the camera type set again: a full
re-raycast). Prints, per kind and overall, the median and p95 of the server's own
``timing_ms`` (raycast, viewshed, metrics, total) and of the HTTP round trip (the total
plus JSON encoding of the full state, in process). Targets: total <= 200 ms (issue 20); a turn
(the ``rotate`` row) <= 200 ms median on warehouse:10000 and <= 100 ms on standard-store (issue 37).
"""

from __future__ import annotations

import argparse
import pickle
import tempfile
import time
from pathlib import Path

import numpy as np


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--changes", type=int, default=50)
    ap.add_argument("--scene", default="standard-store")
    ap.add_argument("--run", default=None, help="an existing run folder of --scene (skips the run)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--opened", default=None,
                    help="a pickle of the opened start: loaded when it exists, else written (a site's V takes minutes)")
    ap.add_argument("--cache", default=None,
                    help="the visibility cache the run filled (as camplace serve --cache): the open reads V from it")
    args = ap.parse_args()
    from starlette.testclient import TestClient

    from camplace.outputs.write import write_outputs
    from camplace.planner.app import create_app
    from camplace.planner.opening import open_start
    from camplace.planner.session import Session
    from camplace.workflows.run import run

    t = time.perf_counter()
    if args.opened and Path(args.opened).is_file():
        opened = pickle.loads(Path(args.opened).read_bytes())
    else:
        if args.run is None:
            r = run(args.scene)
            out = Path(tempfile.mkdtemp(prefix="planner-speed-"))
            write_outputs(out, r.scene.name, r.visibility, r.placement, r.problem.budget, r.metrics, r.timings_s,
                          scene=r.scene, report=False)
        else:
            out = Path(args.run)
        t_open = time.perf_counter()
        opened = open_start(out, scene=args.scene, cache_dir=args.cache)
        print(f"open: {time.perf_counter() - t_open:.2f} s ({opened.vis.info.get('cached_chunks', 0)} of "
              f"{opened.vis.info.get('chunks')} visibility chunks from the cache)")
        if args.opened:
            Path(args.opened).write_bytes(pickle.dumps(opened))
    session = Session(opened)
    print(f"{args.scene}: {len(session.cams)} cameras, {len(session.targets)} targets, "
          f"{len(session.mounts)} mounts; run + open {time.perf_counter() - t:.1f} s")
    client = TestClient(create_app(session, "t", port=8765), base_url="http://127.0.0.1:8765",
                        headers={"X-Camplace-Token": "t"})
    rng = np.random.default_rng(args.seed)
    kinds = ("move", "rotate", "type")
    rows: dict[str, list[dict]] = {k: [] for k in kinds}
    client.put(f"/api/cameras/{session.cams[0].id}", json={"yaw_deg": 1.0})  # warm: numba kernels loaded
    for n in range(args.changes):
        kind = kinds[n % 3]
        cam = session.cams[int(rng.integers(len(session.cams)))]
        if kind == "move":
            body = {"position": session.mounts[int(rng.integers(len(session.mounts)))].tolist()}
        elif kind == "rotate":
            body = {"yaw_deg": float(rng.uniform(0, 360)), "pitch_deg": float(rng.uniform(20, 60))}
        else:
            body = {"camera": session.lenses[n % len(session.lenses)].name}
        t0 = time.perf_counter()
        resp = client.put(f"/api/cameras/{cam.id}", json=body)
        rt = 1000.0 * (time.perf_counter() - t0)
        assert resp.status_code == 200, resp.text
        rows[kind].append(dict(resp.json()["timing_ms"], round_trip=rt))
    allrows = [x for k in kinds for x in rows[k]]
    print(f"{'kind':8} {'n':>3} " + " ".join(f"{c:>18}" for c in ("raycast", "viewshed", "metrics", "total",
                                                                    "round_trip")))
    for name, rs in [*rows.items(), ("all", allrows)]:
        cells = []
        for c in ("raycast", "viewshed", "metrics", "total", "round_trip"):
            v = np.array([x[c] for x in rs]) if rs else np.full(1, np.nan)
            cells.append(f"{np.median(v):7.1f} / {np.percentile(v, 95):7.1f}")
        print(f"{name:8} {len(rs):>3} " + " ".join(f"{c:>18}" for c in cells))
    print("(ms, median / p95)")


if __name__ == "__main__":
    main()
