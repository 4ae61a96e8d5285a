"""plan.dxf (ezdxf): the floor plan for CAD, in the scene frame's metres (1 drawing unit = 1 m).

Layers: CAMPLACE-WALLS (footprint and obstacle outlines, obstacle names), CAMPLACE-ZONES
(target regions: the outline of each volume region's targets at the working height,
with its name), CAMPLACE-FOV (each camera's viewshed at the working height),
CAMPLACE-DORI-<LEVEL> (each camera's DORI bands, hatched), CAMPLACE-CAMERAS (one
INSERT of the block CAMPLACE_CAMERA per camera at its plan position, rotated to its yaw,
with attributes ID, TYPE, HEIGHT, YAW, PITCH). Where the scene came from a file with
another frame, the poses are the scene frame's (placement.json's input_from_scene maps them).
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from camplace.core.files import atomic_write_bytes
from camplace.outputs.plan_data import PlanData
from camplace.visibility.viewshed import DORI_LEVELS

BLOCK = "CAMPLACE_CAMERA"
LAYERS = {"CAMPLACE-WALLS": 7, "CAMPLACE-ZONES": 3, "CAMPLACE-FOV": 5, "CAMPLACE-CAMERAS": 1,
          **{f"CAMPLACE-DORI-{name.upper()}": c for (name, _), c in zip(DORI_LEVELS, (51, 40, 30, 10))}}
ATTRIBS = ("ID", "TYPE", "HEIGHT", "YAW", "PITCH")


def _rings(geom):
    """Exterior and interior rings ((K, 2) arrays) of every polygon of a shapely geometry."""
    for poly in getattr(geom, "geoms", [geom]):
        if poly.is_empty or poly.geom_type != "Polygon":
            continue
        yield np.asarray(poly.exterior.coords)[:, :2], [np.asarray(r.coords)[:, :2] for r in poly.interiors]


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
    import ezdxf

    fixed = ezdxf.options.write_fixed_meta_data_for_testing
    ezdxf.options.write_fixed_meta_data_for_testing = data.dated is None
    try:
        buf = io.StringIO()
        _plan_doc(data).write(buf)
        return buf.getvalue()
    finally:
        ezdxf.options.write_fixed_meta_data_for_testing = fixed


def _plan_doc(data: PlanData):
    import ezdxf

    doc = ezdxf.new("R2010", setup=False)
    doc.units = ezdxf.units.M
    for name, colour in LAYERS.items():
        doc.layers.add(name, color=colour)
    _camera_block(doc)
    msp = doc.modelspace()
    walls = {"layer": "CAMPLACE-WALLS"}
    msp.add_lwpolyline(np.asarray(data.scene.footprint, float).tolist(), close=True, dxfattribs=walls)
    for name, (b0, b1) in data.scene.boxes.items():
        msp.add_lwpolyline([(b0[0], b0[1]), (b1[0], b0[1]), (b1[0], b1[1]), (b0[0], b1[1])], close=True,
                           dxfattribs=walls)
        msp.add_text(f"{name} ({b1[2]:.2f} m)", height=0.15, dxfattribs=walls).set_placement(
            ((b0[0] + b1[0]) / 2, (b0[1] + b1[1]) / 2), align=ezdxf.enums.TextEntityAlignment.MIDDLE_CENTER)
    _zones(msp, data)
    for c, mark, vs in zip(data.cameras, data.marks, data.shed):
        for ext, holes in _rings(vs.polygon):
            msp.add_lwpolyline(ext.tolist(), close=True, dxfattribs={"layer": "CAMPLACE-FOV"})
        for name, _ in DORI_LEVELS:
            layer = f"CAMPLACE-DORI-{name.upper()}"
            for ext, holes in _rings(vs.bands.get(name)):
                hatch = msp.add_hatch(color=LAYERS[layer], dxfattribs={"layer": layer})
                hatch.paths.add_polyline_path(ext.tolist(), is_closed=True, flags=1)
                for h in holes:
                    hatch.paths.add_polyline_path(h.tolist(), is_closed=True, flags=0)
        x, y, z = c["position"]
        ref = msp.add_blockref(BLOCK, (x, y, z), dxfattribs={"layer": "CAMPLACE-CAMERAS",
                                                            "rotation": float(c["yaw_deg"])})
        ref.add_auto_attribs({"ID": str(c.get("source_id", c["candidate_id"])), "TYPE": str(c["camera"]),
                              "HEIGHT": f"{z:.3f}", "YAW": f"{c['yaw_deg']:.2f}", "PITCH": f"{c['pitch_deg']:.2f}"})
        msp.add_text(mark, height=0.2, dxfattribs={"layer": "CAMPLACE-CAMERAS"}).set_placement((x - 0.45, y + 0.2))
    return doc


def _zones(msp, data: PlanData) -> None:
    """Each volume region's targets at the working height (or its nearest layer) as outlines."""
    import shapely

    t = data.targets
    vol = ~np.asarray(t.is_surface, bool)
    half = float(data.scene.spec.voxel_size) / 2
    for r, name in enumerate(t.region_names):
        m = vol & (t.region_ids == r)
        if not m.any():
            continue
        zs = np.unique(np.round(t.positions[m, 2], 6))
        z = zs[np.argmin(np.abs(zs - data.height))]
        p = t.positions[m & (np.abs(t.positions[:, 2] - z) < 1e-6)]
        geom = shapely.union_all(shapely.box(p[:, 0] - half, p[:, 1] - half, p[:, 0] + half, p[:, 1] + half))
        for ext, holes in _rings(geom.simplify(1e-6)):
            for ring in [ext, *holes]:
                msp.add_lwpolyline(ring.tolist(), close=True, dxfattribs={"layer": "CAMPLACE-ZONES"})
        c = np.asarray(geom.representative_point().coords)[0]
        msp.add_text(str(name), height=0.2, dxfattribs={"layer": "CAMPLACE-ZONES"}).set_placement(tuple(c))


def write_plan_dxf(path: str | Path, data: PlanData) -> Path:
    return atomic_write_bytes(Path(path), plan_dxf(data).encode("utf-8"))
