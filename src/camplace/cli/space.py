"""Space files (a scan, a mesh or an OctoMap) -> an editable scene mapping, with the
defaults of a scene built from a scan (camplace.scene.from_scan.scene_from_cloud).

scene_from_cloud reads point clouds only. A mesh or an OctoMap is turned into points
first (mesh: area-weighted samples of its surface; OctoMap: a lattice over its occupied
leaves), written to a temporary PLY, and given to scene_from_cloud; the scene's obstacle
then points at the original file (``mesh:`` / ``octomap:``) with the transform found."""

from __future__ import annotations

import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import typer

from camplace.cli.common import floats
from camplace.core.errors import InputError
from camplace.scene.loaders import MESH_SUFFIXES, OCTOMAP_SUFFIXES, POINT_CLOUD_SUFFIXES, header_lines

MESH_SAMPLE_SPACING_M = 0.03  # one sample per (3 cm)² of mesh surface
MESH_SAMPLES = (20_000, 3_000_000)  # at least / at most
OCTOMAP_LATTICE = 8  # at most this many points per axis in one occupied leaf


PLAN_FORMATS = "{plan formats}"  # in a help text: replaced by the registered plan formats (with_plan_formats)


def with_plan_formats(*commands) -> None:
    """Put the registered plan formats (camplace.scene.formats.formats_text: every
    ``camplace.importers`` entry point) into the help of the commands' arguments whose help
    holds PLAN_FORMATS; called by camplace.cli.app.main, once plugin warnings are lines."""
    import inspect

    from camplace.scene.formats import formats_text

    text = None
    for fn in commands:
        for param in inspect.signature(fn).parameters.values():
            info = param.default
            template = getattr(info, "camplace_help", None) or getattr(info, "help", None)
            if isinstance(template, str) and PLAN_FORMATS in template:
                text = formats_text() if text is None else text
                info.camplace_help = template
                info.help = template.replace(PLAN_FORMATS, text)


def plan_names() -> str:
    """The registered plan formats' names for a message: 'ifc, dxf, image, geojson'."""
    from camplace.scene.formats import IMPORTERS

    return ", ".join(IMPORTERS)


# the options of plans (DXF, plan images, IFC), shared by camplace run and camplace scene import
UNITS_OPT = typer.Option(None, "--units", help="Plan units mm|cm|m|in|ft (default: the file's - DXF $INSUNITS, IFC "
                         "length unit; a DXF that says none is read in the unit its geometry suggests, with a note).")
WALL_HEIGHT_OPT = typer.Option(None, "--wall-height", help="Plan walls: height (m; default the ceiling height).")
CEILING_OPT = typer.Option(None, "--ceiling-height", help="Plans: ceiling height (m; default 3, IFC: the storey's).")
SCALE_OPT = typer.Option(None, "--scale", help="Plan images and PDFs: metres per pixel, or the drawing scale 1:N "
                         "(e.g. 1:100; a PDF's page size, or the dpi a raster file records, turns it into metres "
                         "per pixel); default: read from the dimension lines by OCR, said in a note.")
PAGE_OPT = typer.Option(None, "--page", help="PDF plans: the page to read (1-based; default 1).")
REF_OPT = typer.Option(None, "--ref", help="Plan images: two points 'x1,y1,x2,y2,DIST' (pixels, metres) for the scale.")
STOREY_OPT = typer.Option(None, "--storey", help="IFC: the IfcBuildingStorey name (default: the storey a user plans, "
                          "most rooms, never a roof or foundation level); plan images: plan-N, the N-th plan on a "
                          "sheet of several side by side (default: the one with most rooms); DXF: plan-N or the "
                          "level a title names, e.g. 'First floor' (default: the plan with most walls); 'all' or "
                          "'A,B': every storey with rooms, or those named, as one building (one budget, one run; "
                          "scene import: one scene with storeys:).")
WALL_LAYERS_OPT = typer.Option(None, "--wall-layers", help="DXF: wall layer patterns, comma-separated fnmatch, "
                               "case-insensitive, replacing the defaults (default: layers named like walls in the "
                               "common conventions and languages - A-WALL, WALL, WAND, MUR, MURO, PARED, ... - else "
                               "the layers whose lines pair like wall faces; the summary says which were taken).")
WALL_CLASSES_OPT = typer.Option(None, "--wall-classes", help="IFC: classes whose elements are walls, comma-separated "
                                "(e.g. IfcBeam,IfcPlate), beside IfcWall and the elements shaped like walls (tall, "
                                "thin, standing on the floor, closing rooms); the summary says which were taken.")
LAYER_HEIGHT_OPT = typer.Option(None, "--layer-height", help="DXF: LAYER=M, the height (m) of the furniture blocks on "
                                "layers matching LAYER; repeat for several.")
DOORS_OPT = typer.Option(None, "--doors", help="IFC, DXF: open (default; doors do not occlude) or closed.")
GLASS_OPT = typer.Option(None, "--glass", help="IFC: opaque (default; windows occlude) or transparent.")
THRESHOLD_OPT = typer.Option(None, "--threshold", help="Plan images: the ink's grey level 1-255 (pixels darker than it "
                             "in their brightest channel are ink; default: Otsu's split of the image).")
MAX_OPENING_OPT = typer.Option(None, "--max-opening", help="Plan images: the widest door or window gap (m) bridged to "
                               "close a room (default 1.8).")
MIN_ROOM_OPT = typer.Option(None, "--min-room-area", help="Plan images: the smallest enclosed area (m²) that is a "
                            "room (default 1).")
NO_OCR_OPT = typer.Option(False, "--no-ocr", help="Plan images: no OCR (rooms named room-1..n; give --scale or --ref).")
PLAN_FLAGS = {"units": "--units", "wall_height": "--wall-height", "ceiling_height": "--ceiling-height",
              "scale": "--scale", "ref": "--ref", "storey": "--storey", "wall_layers": "--wall-layers",
              "wall_classes": "--wall-classes", "layer_height": "--layer-height", "doors": "--doors",
              "glass": "--glass", "threshold": "--threshold",
              "max_opening": "--max-opening", "min_room_area": "--min-room-area", "no_ocr": "--no-ocr",
              "page": "--page"}

@dataclass(frozen=True)
class ImportOptions:
    """The options of building a scene from a space file (CLI text, parsed by kwargs())."""

    up: str = "+z"
    level_floor: bool = True
    crop: str | None = None
    downsample: float = 0.02
    heights: str = "0.5,1.0,1.5"
    coverage: int = 2
    wall_mounts: float | None = None
    viewpoint: list[str] = field(default_factory=list)
    # plans (DXF, images, IFC: camplace.scene.importers)
    units: str | None = None
    wall_height: float | None = None
    ceiling_height: float | None = None
    scale: str | None = None
    ref: str | None = None
    storey: str | None = None
    wall_layers: str | None = None
    wall_classes: str | None = None
    layer_height: list[str] | None = None
    doors: str | None = None
    glass: str | None = None
    threshold: float | None = None
    max_opening: float | None = None
    min_room_area: float | None = None
    no_ocr: bool = False
    page: int | None = None

    def plan_kwargs(self, budget: int | None) -> dict:
        """camplace.scene.importers.import_plan keyword arguments (None: the importer's default)."""
        for flag, v in (("--wall-height", self.wall_height), ("--ceiling-height", self.ceiling_height)):
            if v is not None and not v > 0:
                raise InputError(f"{flag}: expected a positive number, got {v}")
        return dict(units=self.units, wall_height=self.wall_height, ceiling_height=self.ceiling_height,
                    scale=self.scale,  # metres per pixel or 1:N, read by the image importer (image_read)
                    ref=floats(self.ref, "--ref", 5) if self.ref else None, storey=self.storey, page=self.page,
                    heights=floats(self.heights, "--heights"), coverage=self.coverage, budget=budget,
                    wall_layers=tuple(p.strip() for p in self.wall_layers.split(",") if p.strip())
                    if self.wall_layers else None, wall_classes=self.wall_classes or None,
                    furniture_heights=layer_heights(self.layer_height),
                    doors=self.doors, glass=self.glass, threshold=self.threshold, max_opening=self.max_opening,
                    min_room_area=self.min_room_area, ocr=False if self.no_ocr else None)

    def kwargs(self, budget: int | None) -> dict:
        """scene_from_cloud keyword arguments (InputError naming the flag on bad text)."""
        if self.up not in ("+x", "-x", "+y", "-y", "+z", "-z"):
            raise InputError(f"--up: expected one of +x -x +y -y +z -z, got '{self.up}'")
        box = floats(self.crop, "--crop", 6) if self.crop else None
        return dict(level_floor=self.level_floor, up=self.up, crop=(box[:3], box[3:]) if box else None,
                    downsample=self.downsample or None, heights=floats(self.heights, "--heights"),
                    coverage=self.coverage, budget=budget if budget is not None else 20,
                    wall_mount_height=self.wall_mounts,
                    viewpoints=[floats(v, "--viewpoint", 3) for v in self.viewpoint] or None)


def key_values(items: list[str] | None, flag: str, cast, ok, expected: str) -> dict:
    """{KEY: cast(VALUE)} of a repeated flag's KEY=VALUE items; an item without a key, or
    whose value cast refuses or ``ok`` rejects, is an InputError naming ``flag`` and ``expected``."""
    out = {}
    for item in items or []:
        key, sep, value = item.rpartition("=")
        try:
            v = cast(value)
        except ValueError:
            v = None
        if not sep or not key.strip() or v is None or not ok(v):
            raise InputError(f"{flag}: expected {expected}, got '{item}'")
        out[key.strip()] = v
    return out


def layer_heights(items: list[str] | None) -> dict[str, float] | None:
    """{'LAYER': metres} of --layer-height LAYER=M items (None when none given)."""
    out = key_values(items, "--layer-height", float, lambda h: h > 0, "LAYER=M with a positive height")
    return out or None


def plan_import_options(kind: str | None, **given) -> ImportOptions:
    """ImportOptions of the plan options ``given`` (units, wall_height, ...; None = not
    given) for a scene of ``kind`` (space_kind); InputError when a plan option is given
    for anything but a plan."""
    for k, v in given.items():
        if v and kind != "plan":
            raise InputError(f"{PLAN_FLAGS[k]}: belongs to plans ({plan_names()})")
    return ImportOptions(**given)


def _ply_has_faces(path: Path) -> bool:
    """True when the PLY header declares a non-empty 'face' element (a mesh, not a scan)."""
    with open(path, "rb") as f:
        raw = f.read(65536)
    for line, _ in header_lines(raw):
        words = line.split()
        if words[:2] == ["element", "face"] and len(words) > 2 and words[2].isdigit():
            return int(words[2]) > 0
        if line == "end_header":
            break
    return False


def space_kind(path: str | Path) -> str | None:
    """'point_cloud', 'mesh', 'octomap' or 'plan' (a registered plan format) by the file's
    suffix (a .ply with faces is a mesh); None for anything else (a scene file or a
    built-in name)."""
    from camplace.scene.formats import plan_kind

    p = Path(path)
    suf = p.suffix.lower()
    if plan_kind(p) is not None:
        return "plan"
    if suf == ".ply":
        return "mesh" if p.is_file() and _ply_has_faces(p) else "point_cloud"
    if suf in POINT_CLOUD_SUFFIXES:
        return "point_cloud"
    if suf in MESH_SUFFIXES:
        return "mesh"
    if suf in OCTOMAP_SUFFIXES:
        return "octomap"
    return None


def mesh_surface_points(vertices: np.ndarray, faces: np.ndarray, spacing: float = MESH_SAMPLE_SPACING_M,
                        seed: int = 0) -> np.ndarray:
    """(N, 3) points spread over a triangle mesh by area (about one per spacing² m²)."""
    tri = vertices[faces]
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    n = int(np.clip(area.sum() / spacing**2, *MESH_SAMPLES))
    rng = np.random.default_rng(seed)
    f = rng.choice(len(faces), size=n, p=area / area.sum()) if area.sum() > 0 else rng.integers(0, len(faces), n)
    u, v = rng.random(n), rng.random(n)
    flip = u + v > 1
    u[flip], v[flip] = 1 - u[flip], 1 - v[flip]
    t = tri[f]
    return t[:, 0] + u[:, None] * (t[:, 1] - t[:, 0]) + v[:, None] * (t[:, 2] - t[:, 0])


def octomap_points(lo: np.ndarray, size: np.ndarray, resolution: float) -> np.ndarray:
    """(N, 3) points on a lattice over occupied leaves (min corners lo (L, 3), edges size
    (L,) m): one per resolution-cell, at most OCTOMAP_LATTICE per axis of a leaf."""
    out = []
    for s in np.unique(size):
        k = int(np.clip(round(s / resolution), 1, OCTOMAP_LATTICE))
        g = (np.arange(k) + 0.5) * (s / k)
        offs = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3)
        out.append((lo[size == s][:, None, :] + offs[None]).reshape(-1, 3))
    return np.concatenate(out) if out else np.zeros((0, 3))


def _points_of(path: Path, kind: str) -> np.ndarray:
    if kind == "mesh":
        from camplace.scene.loaders.mesh import load_mesh

        m = load_mesh(path)
        return mesh_surface_points(m.vertices, m.faces)
    from camplace.scene.loaders.octomap import load_octomap

    om = load_octomap(path)
    if len(om.occupied_lo) == 0:
        raise InputError(f"{path}: the OctoMap has no occupied leaves")
    return octomap_points(om.occupied_lo, om.occupied_size, om.resolution)


def _via_points(path: Path, kind: str, kw: dict) -> tuple[dict, dict]:
    """scene_from_cloud on the points of a mesh / OctoMap; the obstacle then names the file."""
    from camplace.scene.from_scan import scene_from_cloud
    from camplace.scene.loaders.pointcloud import write_ply

    if kw.get("viewpoints"):
        raise InputError("--viewpoint: scanner positions belong to scans, not to meshes or OctoMaps")
    if kind == "octomap":
        if kw["up"] != "+z":
            raise InputError("--up: an OctoMap's leaves are axis-aligned; it must be +z up")
        kw = dict(kw, level_floor=False)  # an OctoMap can be moved, not rotated
    pts = _points_of(path, kind)
    with tempfile.TemporaryDirectory(prefix="camplace-import-") as tmp:
        data, rep = scene_from_cloud(str(write_ply(Path(tmp) / f"{path.stem}.ply", pts)), name=path.stem, **kw)
    entry = {"name": "scan", kind: str(path.expanduser().resolve())}
    old = data["obstacles"][0]
    entry.update({k: old[k] for k in ("transform", "crop") if k in old})
    data["obstacles"] = [entry]
    rep = dict(rep, source=kind, sampled_points=len(pts))
    return data, rep


def scene_data_from_file(path: str | Path, opts: ImportOptions, budget: int | None = None
                         ) -> tuple[dict, dict, str]:
    """(scene mapping, report of what was detected, kind) for a space file."""
    from camplace.scene.from_scan import scene_from_cloud
    from camplace.spec.loading import parse_scene

    p = Path(path)
    kind = space_kind(p)
    if kind is None:
        from camplace.scene.formats import formats_text

        raise InputError(f"{p}: not a space file; expected a scan ({', '.join(POINT_CLOUD_SUFFIXES)}), a mesh "
                         f"({', '.join(MESH_SUFFIXES)}), an OctoMap ({', '.join(OCTOMAP_SUFFIXES)}) or a plan: "
                         f"{formats_text()}")
    if not p.is_file():
        raise InputError(f"{p}: file not found" if not p.exists() else f"{p}: is a folder, expected a file")
    if kind == "plan":
        return _plan_data(p, opts, budget)
    kw = opts.kwargs(budget)
    if kind == "point_cloud":
        data, rep = scene_from_cloud(str(p), **kw)
        rep = dict(rep, source=kind)
    else:
        data, rep = _via_points(p, kind, kw)
        parse_scene(data, str(p))  # the scene names the file itself now: check it again
    return data, rep, kind


def _plan_data(p: Path, opts: ImportOptions, budget: int | None) -> tuple[dict, dict, str]:
    """(scene mapping, report, 'plan') of a plan file, checked by the scene schema; the
    report's 'plan' is what the importer understood (camplace.scene.importers.PlanImport)."""
    from shapely.geometry import Polygon

    from camplace.scene.importers import plan_kind, read_plan, validated

    got = read_plan(p, **opts.plan_kwargs(budget))
    data = validated(got.scene, str(p))
    rep = {"source": "plan", "plan": got, "format": plan_kind(p), "walls": sum("prism" in o for o in data["obstacles"]),
           "obstacles": len(data["obstacles"]), "zones": [z["name"] for z in data.get("zones", [])],
           "floor_area_m2": round(Polygon(data["room"]["footprint"]).area, 2), "height_m": data["room"]["height"]}
    return data, rep, "plan"


def describe_import(rep: dict) -> str:
    """One line on what was detected in the space file."""
    if rep.get("source") == "plan":
        return (f"{rep['format']} plan: footprint {rep['floor_area_m2']} m², ceiling {rep['height_m']} m, "
                f"{rep['obstacles']} obstacles, {len(rep['zones'])} rooms ({', '.join(rep['zones'])})")
    what = {"point_cloud": "scan", "mesh": "mesh", "octomap": "OctoMap"}[rep.get("source", "point_cloud")]
    pts = (f"{rep['sampled_points']:,} points sampled, {rep['points']:,} after clean-up" if "sampled_points" in rep
           else f"{rep['points']:,} points after clean-up")
    levelled = any(s.get("step") == "level_floor" for s in rep.get("cleanup", []))
    return (f"{what}: {pts}; floor {'levelled' if levelled else 'moved to z = 0'}, ceiling {rep['height_m']} m above it, "
            f"footprint "
            f"{rep['floor_area_m2']} m² ({rep['footprint_vertices']} corners), {rep['viewpoints']} scanner viewpoint(s)")


def scene_yaml(data: dict, how: str) -> str:
    """The scene mapping as an editable YAML document, with a header comment."""
    import yaml

    return (f"# camplace scene built from a space file ({how}); edit and rerun\n"
            + yaml.safe_dump(data, sort_keys=False, default_flow_style=None))
