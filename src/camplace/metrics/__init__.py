"""camplace.metrics.coverage."""
