"""camplace.improve."""
