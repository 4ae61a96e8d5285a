"""camplace.scene (layer 2): the Scene - build (occupancy grid from a SceneSpec), freespace (free
space carved from scans / OctoMaps), from_scan (floor, ceiling, footprint and a scene
mapping from a scan alone), loaders (point clouds, meshes, OctoMaps)."""
