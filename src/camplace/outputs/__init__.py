"""camplace.outputs."""
