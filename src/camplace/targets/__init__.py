"""camplace.targets (layer 3): build (the Targets of a scene: volume grids and surface points, with
coverage Γ, weights, normals and regions)."""
