"""Pixel mode at stride 1 on standard-store: CPU time per candidate on every 35th candidate,
extrapolated to all candidates on 2 cores. Run: python benchmarks/pixel_speed.py"""
import time, sys
import numpy as np
sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parents[1] / "tests"))
from conftest import builtin_inputs
from camplace.visibility.engine import compute_visibility
from camplace.visibility.registry import get_engine
sc, t, c = builtin_inputs("standard-store")
keep = np.zeros(len(c), bool); keep[::35] = True
sub = c.subset(keep)
eng = get_engine("pixel", stride=1, probe=1.0)
compute_visibility(eng, sc.occupancy, t, sub.subset(np.arange(len(sub)) < 2))  # compile
t0, w0 = time.process_time(), time.perf_counter()
v = compute_visibility(eng, sc.occupancy, t, sub)
cpu, wall = time.process_time() - t0, time.perf_counter() - w0
print(f"{len(sub)} cands nnz {v.V.nnz} cpu {cpu:.1f}s wall {wall:.1f}s -> cpu/cand {cpu/len(sub):.3f}s, all {len(c)} on 2 cores: {cpu/len(sub)*len(c)/2/60:.1f} min")
