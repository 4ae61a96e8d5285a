"""``camplace compare-visibility``: agreement of voxel and pixel visibility on a scene."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer
from rich.console import Console
from rich.table import Table

from camplace.cli.common import RichProgress, progress_bars


def _table(a) -> Table:
    t = Table(title=f"voxel vs pixel visibility - {a.scene} (stride {a.stride}, probe {a.probe:g})", show_header=False)
    t.add_row("V entries", f"voxel {a.nnz_voxel}, pixel {a.nnz_pixel}, shared {a.shared}")
    t.add_row("agreement", f"Jaccard {100 * a.jaccard:.2f} %, voxel in pixel {100 * a.voxel_in_pixel:.2f} %, "
                           f"pixel in voxel {100 * a.pixel_in_voxel:.2f} %")
    for name, r in a.regions.items():
        t.add_row(f"  region {name}", f"Jaccard {100 * r['jaccard']:.2f} % ({r['nnz_voxel']} / {r['nnz_pixel']})")
    for solved, row in a.gap.items():
        t.add_row(f"gap, {a.solver} on {solved} V", ", ".join(f"scored on {k}: {v:.4f}" for k, v in row.items()))
    t.add_row("time (s)", f"voxel {a.seconds['voxel']:.2f}, pixel {a.seconds['pixel']:.2f} "
                          f"({a.rays} rays, {a.rays_per_s / 1e6:.2f} M rays/s)")
    return t


def compare_visibility_cmd(
        scene: str = typer.Argument(..., help="Scene YAML file or built-in name."),
        stride: Optional[int] = typer.Option(None, "--stride", help="Pixel mode: one ray per STRIDE x STRIDE pixels "
                                                                    "(default: camplace.visibility.pixel.DEFAULT_STRIDE)."),
        probe: float = typer.Option(0.0, "--probe", help="Pixel mode probe: 0 = target centre in a ray's footprint "
                                                         "(like voxel mode), 1 = any part of the voxel (the paper)."),
        budget: Optional[int] = typer.Option(None, "--budget", help="N_s for the coverage-gap comparison (default: the scene's)."),
        json_out: Optional[Path] = typer.Option(None, "--json", help="Also write the figures to this JSON file.")) -> None:
    """Agreement of voxel and pixel visibility: shared V entries and the effect on the coverage gap."""
    from camplace.core.files import atomic_write_json
    from camplace.workflows.compare import compare_visibility

    with progress_bars() as prog:
        a = compare_visibility(scene, stride=stride, probe=probe, budget=budget, progress=RichProgress(prog))
    if json_out is not None:
        atomic_write_json(json_out, a.to_dict())
    Console().print(_table(a))
