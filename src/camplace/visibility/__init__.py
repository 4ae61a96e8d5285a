"""camplace.visibility.voxel."""
