"""camplace.problem (layer 6): the placement problem, all that a solver sees.

model (``PlacementProblem``: V, Γ, weights, camera budget, locations, prices and money
budget, per-type limits, optional positions; the exact reductions), gains (the shortfall
cost and the gain of one more view, numpy and numba side by side), triangulation (the
well-triangulated pair test the triangulation-aware greedy counts with), offset (a
sub-problem with the other cameras' coverage as an offset), feasibility (targets that
cannot reach their coverage), instance (problems saved as ``visibility.npz``)."""
