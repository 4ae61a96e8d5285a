"""camplace.cameras.models."""
