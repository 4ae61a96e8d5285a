"""plan.dxf (ezdxf): the floor plan for CAD, in metres (1 drawing unit = 1 m).

Layers: CAMPLACE-WALLS (footprint and box obstacle outlines, obstacle names; prism
obstacles such as imported walls as the outlines of their plan cut at the working
height, camplace.outputs.walls), CAMPLACE-ZONES
(the scene's volume zones: their polygons, closed, with their names; target regions of
``targets:`` as the outline of their targets at the working height), CAMPLACE-ZONES-PRIVACY
(privacy zones), CAMPLACE-MOUNT-FORBID / CAMPLACE-MOUNT-ALLOW (mount_rules polygons),
CAMPLACE-FOV (each camera's viewshed at the working height), CAMPLACE-DORI-<LEVEL> (each
camera's DORI bands, hatched), CAMPLACE-CAMERAS / CAMPLACE-CAMERAS-EXISTING (one INSERT of
the block CAMPLACE_CAMERA per new / existing camera at its position, rotated to its yaw,
with attributes ID, TYPE, HEIGHT, YAW, PITCH, STATUS).

Frame: the scene frame, or with ``PlanData.input_from_scene`` (write_outputs(frame='input'))
the input file's: every plan point (x, y) is mapped as (x, y, working height) through the
4x4 transform and its z dropped (for a transform about the vertical axis that is exactly
its xy part); camera insertion points are the cameras' 3D positions in that frame, YAW /
PITCH / HEIGHT that frame's (as placement.json's with frame 'input'). A transform that
scales (a file in mm) makes the drawing unitless in the file's units.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from camplace.core.files import atomic_write_bytes
from camplace.outputs.plan_data import PlanData, camera_id
from camplace.outputs.walls import plan_cut, rings, scene_walls
from camplace.visibility.viewshed import DORI_LEVELS

BLOCK = "CAMPLACE_CAMERA"
LAYERS = {"CAMPLACE-WALLS": 7, "CAMPLACE-ZONES": 3, "CAMPLACE-ZONES-PRIVACY": 6, "CAMPLACE-MOUNT-FORBID": 1,
          "CAMPLACE-MOUNT-ALLOW": 3, "CAMPLACE-FOV": 5, "CAMPLACE-CAMERAS": 1, "CAMPLACE-CAMERAS-EXISTING": 6,
          **{f"CAMPLACE-DORI-{name.upper()}": c for (name, _), c in zip(DORI_LEVELS, (51, 40, 30, 10))}}
AREA_LAYERS = {"zone": "CAMPLACE-ZONES", "privacy": "CAMPLACE-ZONES-PRIVACY", "forbid": "CAMPLACE-MOUNT-FORBID",
               "allow": "CAMPLACE-MOUNT-ALLOW"}
ATTRIBS = ("ID", "TYPE", "HEIGHT", "YAW", "PITCH", "STATUS")


class PlanFrame:
    """Scene-frame plan points to the drawing's: T (4x4, p_out = T @ [p, 1]; identity when
    None); plan points are taken at height h (m) and their z dropped."""

    def __init__(self, T: np.ndarray | None, h: float):
        self.T = np.eye(4) if T is None else np.asarray(T, np.float64)
        self.h = float(h)
        self.k = float(np.cbrt(np.linalg.det(self.T[:3, :3])))  # drawing units per metre

    def xy(self, pts) -> list[tuple[float, float]]:
        """(K, 2) scene plan points (m) -> K drawing points."""
        p = np.asarray(pts, np.float64).reshape(-1, 2)
        q = np.column_stack([p, np.full(len(p), self.h)]) @ self.T[:3, :3].T + self.T[:3, 3]
        return [(float(a), float(b)) for a, b in q[:, :2]]

    def cameras(self, cameras: list[dict]) -> list[tuple[tuple, float, tuple[float, float, float]]]:
        """Per camera: (insertion point (3,), symbol rotation deg, (height, yaw, pitch) of its frame)."""
        from camplace.cameras.candidates import ypr_from_rotation
        from camplace.scene.frames import map_poses

        if np.array_equal(self.T, np.eye(4)):  # the scene frame: placement.json's own numbers
            return [(tuple(float(v) for v in c["position"]), float(c["yaw_deg"]),
                     (float(c["position"][2]), float(c["yaw_deg"]), float(c["pitch_deg"]))) for c in cameras]
        if not cameras:
            return []
        pos, rot = map_poses(self.T, [c["position"] for c in cameras], [c["rotation"] for c in cameras])
        ang = ypr_from_rotation(rot)
        out = []
        for c, p, a in zip(cameras, pos, ang):
            y = np.radians(c["yaw_deg"])
            fwd = self.xy([c["position"][:2], np.asarray(c["position"][:2]) + [np.cos(y), np.sin(y)]])
            turn = float(np.degrees(np.arctan2(fwd[1][1] - fwd[0][1], fwd[1][0] - fwd[0][0])))
            out.append((tuple(float(v) for v in p), turn, (float(p[2]), float(a[0]), float(a[1]))))
        return out


def _rings(geom):
    """Exterior and interior rings ((K, 2) arrays) of every polygon of a shapely geometry."""
    return rings(geom)


def _camera_block(doc) -> None:
    """The camera symbol: a 0.15 m circle and a wedge along +x (the INSERT's rotation = yaw)."""
    blk = doc.blocks.new(name=BLOCK)
    blk.add_circle((0, 0), 0.15, dxfattribs={"layer": "0"})
    blk.add_lwpolyline([(0, 0.08), (0.4, 0), (0, -0.08)], close=True, dxfattribs={"layer": "0"})
    for k, tag in enumerate(ATTRIBS):
        blk.add_attdef(tag, (0.2, 0.2 + 0.12 * k), dxfattribs={"height": 0.1, "layer": "0"})


def plan_dxf(data: PlanData) -> str:
    """The DXF document (R2010) as text; repeatable runs (data.dated None) carry ezdxf's fixed
    dates and GUIDs, so identical inputs give identical files."""
    return dxf_text(_plan_doc, data, data.dated is None)


def dxf_text(make_doc, data, fixed_meta: bool) -> str:
    """The text of the DXF document ``make_doc(data)``; ``fixed_meta``: ezdxf's fixed dates
    and GUIDs (repeatable runs)."""
    import ezdxf

    fixed = ezdxf.options.write_fixed_meta_data_for_testing
    ezdxf.options.write_fixed_meta_data_for_testing = fixed_meta
    try:
        buf = io.StringIO()
        make_doc(data).write(buf)
        return buf.getvalue()
    finally:
        ezdxf.options.write_fixed_meta_data_for_testing = fixed


def new_doc(data: PlanData, layers: dict[str, int]):
    """(an R2010 document with ``layers`` (name -> colour) and the camera block, its
    PlanFrame); units metres unless the frame scales."""
    import ezdxf

    doc = ezdxf.new("R2010", setup=False)
    f = PlanFrame(data.input_from_scene, data.height)
    doc.units = ezdxf.units.M if abs(f.k - 1.0) < 1e-9 else 0
    for name, colour in layers.items():
        doc.layers.add(name, color=colour)
    _camera_block(doc)
    return doc, f


def _plan_doc(data: PlanData):
    doc, f = new_doc(data, LAYERS)
    draw_plan(doc.modelspace(), f, data)
    return doc


def draw_plan(msp, f: PlanFrame, data: PlanData) -> None:
    """Every entity of the plan of ``data`` into the modelspace ``msp`` (on the LAYERS)."""
    walls = {"layer": "CAMPLACE-WALLS"}
    msp.add_lwpolyline(f.xy(data.scene.footprint), close=True, dxfattribs=walls)
    for name, (b0, b1) in data.scene.boxes.items():
        msp.add_lwpolyline(f.xy([(b0[0], b0[1]), (b1[0], b0[1]), (b1[0], b1[1]), (b0[0], b1[1])]), close=True,
                           dxfattribs=walls)
        _text(msp, f, f"{name} ({b1[2]:.2f} m)", ((b0[0] + b1[0]) / 2, (b0[1] + b1[1]) / 2), 0.15, walls, True)
    _walls(msp, f, data)
    _zones(msp, f, data)
    for vs in data.shed:
        for ext, holes in _rings(vs.polygon):
            msp.add_lwpolyline(f.xy(ext), close=True, dxfattribs={"layer": "CAMPLACE-FOV"})
        for name, _ in DORI_LEVELS:
            layer = f"CAMPLACE-DORI-{name.upper()}"
            for ext, holes in _rings(vs.bands.get(name)):
                hatch = msp.add_hatch(color=LAYERS[layer], dxfattribs={"layer": layer})
                hatch.paths.add_polyline_path(f.xy(ext), is_closed=True, flags=1)
                for h in holes:
                    hatch.paths.add_polyline_path(f.xy(h), is_closed=True, flags=0)
    for c, mark, (at, turn, (z, yaw, pitch)) in zip(data.cameras, data.marks, f.cameras(data.cameras)):
        layer = "CAMPLACE-CAMERAS-EXISTING" if c.get("existing") else "CAMPLACE-CAMERAS"
        ref = msp.add_blockref(BLOCK, at, dxfattribs={"layer": layer, "rotation": turn, "xscale": f.k,
                                                      "yscale": f.k, "zscale": f.k})
        ref.add_auto_attribs({"ID": camera_id(c), "TYPE": str(c["camera"]), "HEIGHT": f"{z:.3f}",
                              "YAW": f"{yaw:.2f}", "PITCH": f"{pitch:.2f}",
                              "STATUS": "existing" if c.get("existing") else "new"})
        _text(msp, f, mark, (c["position"][0] - 0.45, c["position"][1] + 0.2), 0.2, {"layer": layer})


def _walls(msp, f: PlanFrame, data: PlanData) -> None:
    """The prism obstacles (imported walls, ...) on CAMPLACE-WALLS: per provenance label,
    the outline (rings, holes too) of those crossing the working height or below it."""
    cut, below = plan_cut(scene_walls(data.scene), data.height)
    for geom in [*cut.values(), *below.values()]:
        for ext, holes in _rings(geom):
            for ring in [ext, *holes]:
                msp.add_lwpolyline(f.xy(ring[:-1]), close=True, dxfattribs={"layer": "CAMPLACE-WALLS"})


def _text(msp, f: PlanFrame, text: str, xy, height: float, attribs: dict, centred: bool = False) -> None:
    """A TEXT of ``height`` m at scene plan point xy (mapped by f)."""
    import ezdxf

    t = msp.add_text(text, height=height * f.k, dxfattribs=attribs)
    if centred:
        t.set_placement(f.xy([xy])[0], align=ezdxf.enums.TextEntityAlignment.MIDDLE_CENTER)
    else:
        t.set_placement(f.xy([xy])[0])


def _zones(msp, f: PlanFrame, data: PlanData) -> None:
    """The scene's areas (PlanData.areas: zones, privacy zones, mount rules) as closed polylines
    with their names; regions of ``targets:`` as the outline of their targets at the working
    height (or their nearest layer)."""
    import shapely

    drawn = set()
    for kind, name, corners in data.areas:
        layer = {"layer": AREA_LAYERS[kind]}
        msp.add_lwpolyline(f.xy(corners), close=True, dxfattribs=layer)
        _text(msp, f, name, shapely.Polygon(corners).representative_point().coords[0], 0.2, layer)
        drawn.add(name)
    t = data.targets
    vol = ~np.asarray(t.is_surface, bool)
    cell = float(data.scene.spec.voxel_size)
    for r, name in enumerate(t.region_names):
        m = vol & (t.region_ids == r)
        if not m.any() or str(name) in drawn or (data.storey and str(name).removeprefix(f"{data.storey}/") in drawn):
            continue  # a storey's region 'Level 1/Kitchen' is its zone 'Kitchen', drawn above
        zs = np.unique(np.round(t.positions[m, 2], 6))
        z = zs[np.argmin(np.abs(zs - data.height))]
        p = t.positions[m & (np.abs(t.positions[:, 2] - z) < 1e-6)]
        geom = cells_outline(p[:, :2], cell)
        for ext, holes in _rings(geom.simplify(1e-6)):
            for ring in [ext, *holes]:
                msp.add_lwpolyline(f.xy(ring), close=True, dxfattribs={"layer": "CAMPLACE-ZONES"})
        _text(msp, f, str(name), geom.representative_point().coords[0], 0.2, {"layer": "CAMPLACE-ZONES"})


def cells_outline(xy: np.ndarray, cell: float):
    """The union of the square cells (side ``cell`` m) centred at ``xy`` (n, 2) m, as a shapely
    geometry. Centres on one regular grid: each shared edge computed once from integer indices
    (exactly equal on both sides), then GEOS's coverage union (≈ 10× faster than union_all on
    30,000 cells; issue 37); off-grid centres: union_all of the squares."""
    import shapely

    o = xy.min(0)
    i = np.round((xy - o) / cell).astype(np.int64)
    if np.abs(o + i * cell - xy).max(initial=0.0) > 1e-6 * cell:
        h = cell / 2
        return shapely.union_all(shapely.box(xy[:, 0] - h, xy[:, 1] - h, xy[:, 0] + h, xy[:, 1] + h))
    lo, hi = o + (i - 0.5) * cell, o + (i + 0.5) * cell
    return shapely.coverage_union_all(shapely.box(lo[:, 0], lo[:, 1], hi[:, 0], hi[:, 1]))


def write_plan_dxf(path: str | Path, data: PlanData) -> Path:
    return atomic_write_bytes(Path(path), plan_dxf(data).encode("utf-8"))


def storey_layer(storey: str, layer: str) -> str:
    """A storey's name for one of LAYERS: 'CAMPLACE-CAMERAS' on storey 'Level 1' is
    'Level 1-CAMERAS' (characters a DXF layer name cannot hold become '_')."""
    safe = "".join("_" if ch in '<>/\\":;?*|=`,' else ch for ch in storey).strip() or "storey"
    return f"{safe}-{layer.removeprefix('CAMPLACE-')}"


def building_dxf(storeys: list[PlanData]) -> str:
    """plan.dxf of a building: each storey's plan (PlanData of camplace.outputs.plan_storeys,
    local z) on its own layer set (storey_layer) and drawn at its elevation: every entity's
    z is the storey floor's, cameras at their building z (in the drawing's frame)."""
    return dxf_text(_building_doc, storeys, storeys[0].dated is None)


def _building_doc(storeys: list[PlanData]):
    floors = {st["name"]: float(st["elevation_m"]) for st in storeys[0].placement.get("storeys", [])}
    layers = {storey_layer(d.storey, name): colour for d in storeys for name, colour in LAYERS.items()}
    doc, f0 = new_doc(storeys[0], layers)
    msp = doc.modelspace()
    for data in storeys:
        lift = np.eye(4)
        lift[2, 3] = floors.get(data.storey, 0.0)
        f = PlanFrame(f0.T @ lift, data.height)  # the storey's local z up to the building's
        z_floor = float((f.T @ [0.0, 0.0, 0.0, 1.0])[2])
        start = len(msp)
        draw_plan(msp, f, data)
        for e in list(msp)[start:]:
            e.dxf.layer = storey_layer(data.storey, e.dxf.layer)
            if e.dxftype() == "INSERT":  # placed at the camera's own z already
                for a in e.attribs:
                    a.dxf.layer = e.dxf.layer
            else:
                e.translate(0.0, 0.0, z_floor)
    return doc


def write_building_dxf(path: str | Path, storeys: list[PlanData]) -> Path:
    return atomic_write_bytes(Path(path), building_dxf(storeys).encode("utf-8"))
