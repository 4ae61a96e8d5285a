"""camplace.core."""
