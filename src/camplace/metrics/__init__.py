"""camplace.metrics (layer 7): scores of any selection - coverage (``Metrics``,
``compute_metrics``: cost, coverage gap of paper eq. 8, non-triangulatable share, per
region) and triangulation (the well-triangulated share)."""
