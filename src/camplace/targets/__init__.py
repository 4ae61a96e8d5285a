"""camplace.targets.build."""
