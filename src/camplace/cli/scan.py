"""``camplace scan``: a synthetic scan of a box scene, or the scene as a mesh / OctoMap."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer
from rich.markup import escape

from camplace.cli.common import console, state


def scan(scene: str = typer.Argument(..., help="Built-in scene name or YAML file with box obstacles."),
         out: Path = typer.Option(..., "--out", help="Output: .ply, .pcd, .xyz, .csv, .las or .laz (point cloud); "
                                                     ".obj, .stl, .glb, .off (mesh of the boxes); .bt or .ot (OctoMap)."),
         noise: float = typer.Option(0.01, "--noise", min=0.0, help="Range noise (standard deviation, m)."),
         step: float = typer.Option(0.4, "--step", min=0.05, help="Angular step of the scanner (degrees)."),
         viewpoints: Optional[int] = typer.Option(None, "--viewpoints", min=1,
                                                  help="Scanner positions (default: enough to see 99 % of the floor)."),
         height: float = typer.Option(1.6, "--height", help="Scanner height above the floor (m)."),
         seed: int = typer.Option(0, "--seed", help="Noise seed.")) -> None:
    """Write a synthetic scan of a box scene (rays from a few viewpoints, range noise,
    occlusion), or export the scene as a mesh / OctoMap - test data with no outside files."""
    from camplace.scene.build import build_scene
    from camplace.scene.loaders.pointcloud import write_point_cloud
    from camplace.spec.builtin import resolve_scene
    from camplace.workflows.scan import export_mesh, export_octomap, scan_cli_summary, scan_scene

    spec, base, src = resolve_scene(scene)
    sc = build_scene(spec, base, src)
    suf = out.suffix.lower()
    if suf in (".obj", ".stl", ".glb", ".off"):
        export_mesh(sc, out)
        what = "mesh of the occluding boxes"
    elif suf in (".bt", ".ot"):
        export_octomap(sc, out)
        what = f"OctoMap of the occupancy grid ({sc.occupancy.resolution} m)"
    else:
        cloud = scan_scene(sc, n_viewpoints=viewpoints, height=height, step_deg=step, noise=noise, seed=seed)
        write_point_cloud(out, cloud.points, cloud.viewpoints)
        what = scan_cli_summary(cloud)
    if state["quiet"]:
        typer.echo(str(out))
    else:
        console.print(f"wrote {escape(str(out))}: {what}")
