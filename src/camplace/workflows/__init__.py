"""camplace.workflows."""
