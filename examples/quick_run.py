"""The whole pipeline in one call, then a solver on the same problem: the public API.
Run: python examples/quick_run.py
"""

import camplace

r = camplace.run("demo", budget=6, solver="greedy")
print(f"greedy: cost {r.metrics.cost:g}, coverage gap {r.metrics.coverage_gap:.4f}, "
      f"non-triangulatable {r.metrics.non_triangulatable_pct:.1f} %")
tabu = camplace.solve(r.problem, "tabu", seed=0, max_iterations=300)  # same problem, another solver
print(f"tabu:   cost {tabu.objective:g} (status {tabu.status})")
try:
    camplace.solve(r.problem, "mip", coverage_gap=0.1)      # an option mip does not take
except camplace.InputError as err:
    print(f"refused: {err}")
