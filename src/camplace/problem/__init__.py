"""camplace.problem.model."""
