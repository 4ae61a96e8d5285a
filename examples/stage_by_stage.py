"""camplace stage by stage on the built-in demo room: every stage is a plain function
returning a dataclass, one package per stage (docs/design.md). Run: python examples/stage_by_stage.py
"""

from camplace.cameras.candidates import build_candidates
from camplace.cameras.models import camera_from_spec
from camplace.metrics.coverage import compute_metrics
from camplace.scene.build import build_scene
from camplace.solvers import solve
from camplace.spec.builtin import resolve_scene
from camplace.targets.build import build_targets
from camplace.visibility.engine import compute_visibility, drop_blind_candidates
from camplace.visibility.registry import get_engine
from camplace.workflows.run import problem_from_visibility

spec, _, _ = resolve_scene("demo")
scene = build_scene(spec)                                   # occupancy grid (walls, floor, ceiling, boxes)
targets = build_targets(scene)                              # N_p points with Γ, normals, regions
cands = build_candidates(scene, {c.name: camera_from_spec(c) for c in spec.cameras})
engine = get_engine("voxel")                                # or "pixel" (the paper's per-pixel rays)
vis = drop_blind_candidates(compute_visibility(engine, scene.occupancy, targets, cands))  # sparse V
problem = problem_from_visibility(vis, budget=6)
placement = solve(problem, "greedy")
metrics = compute_metrics(problem, placement.selected, targets.region_ids, targets.region_names)
print(f"V {vis.V.shape[0]} x {vis.V.shape[1]} ({vis.V.nnz} pairs); {len(placement.selected)} cameras, "
      f"cost {placement.objective:g}, coverage gap {metrics.coverage_gap:.4f}")
