"""camplace.spec."""
