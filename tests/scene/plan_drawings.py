"""One plan in the three formats people have (issue 18): the grid building of
camplace.scene.importers.ifc_build drawn as IFC, as an AIA-layered DXF (wall HATCH
solids, door boxes on A-DOOR, rooms on A-AREA named by MTEXT) and as a plan image
(black walls, white door gaps), for the cross-format acceptance tests."""

from __future__ import annotations

from pathlib import Path

from camplace.scene.importers.ifc_build import GridBuilding, _door_box, _walls, write_grid_building

PLAN_PX = 0.02  # m per pixel of the plan image
PLAN_MARGIN_PX = 20  # white pixels around the building


def _openings(b: GridBuilding) -> list[tuple]:
    """(wall lo, wall hi, door lo, door hi) of every wall segment (door None on outer walls), m."""
    W, D = b.nx * b.room[0], b.ny * b.room[1]
    out = []
    for axis, lo, hi in _walls(b):
        a = 1 if axis == "x" else 0
        c = 0.5 * (lo[a] + hi[a])
        inner = 1e-6 < c < (D if axis == "x" else W) - 1e-6
        out.append((lo, hi, *(_door_box(axis, lo, hi, b) if inner else (None, None))))
    return out


def draw_grid_dxf(path: str | Path, b: GridBuilding) -> Path:
    """The grid building as a DXF in mm: walls as HATCH rectangles on A-WALL, doors as
    closed boxes on A-DOOR, rooms as closed polylines on A-AREA with their names."""
    import ezdxf

    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = 4
    msp = doc.modelspace()

    def rect(lo, hi):
        return [(lo[0] * 1000, lo[1] * 1000), (hi[0] * 1000, lo[1] * 1000), (hi[0] * 1000, hi[1] * 1000),
                (lo[0] * 1000, hi[1] * 1000)]

    for lo, hi, dlo, dhi in _openings(b):
        msp.add_hatch(dxfattribs={"layer": "A-WALL"}).paths.add_polyline_path(rect(lo, hi), is_closed=True)
        if dlo is not None:
            msp.add_lwpolyline(rect(dlo, dhi), close=True, dxfattribs={"layer": "A-DOOR"})
    for k, (lo, hi) in enumerate(b.space_boxes()):
        msp.add_lwpolyline(rect(lo, hi), close=True, dxfattribs={"layer": "A-AREA"})
        centre = (500 * (lo[0] + hi[0]), 500 * (lo[1] + hi[1]))
        msp.add_mtext(b.name(k), dxfattribs={"layer": "A-AREA-IDEN", "insert": centre})
    doc.saveas(path)
    return Path(path)


def draw_grid_png(path: str | Path, b: GridBuilding, px: float = PLAN_PX) -> Path:
    """The grid building as a plan image (``px`` m per pixel): black walls, door gaps white."""
    from PIL import Image, ImageDraw

    t = b.wall
    W, D = b.nx * b.room[0] + t, b.ny * b.room[1] + t
    im = Image.new("L", (round(W / px) + 2 * PLAN_MARGIN_PX, round(D / px) + 2 * PLAN_MARGIN_PX), 255)
    d = ImageDraw.Draw(im)

    def rect(lo, hi, fill):
        c0, c1 = (PLAN_MARGIN_PX + round((v + t / 2) / px) for v in (lo[0], hi[0]))
        r0, r1 = (PLAN_MARGIN_PX + round((D - t / 2 - v) / px) for v in (hi[1], lo[1]))
        d.rectangle([c0, r0, c1 - 1, r1 - 1], fill=fill)

    pieces = _openings(b)
    for lo, hi, _, _ in pieces:
        rect(lo, hi, 0)
    for _, _, dlo, dhi in pieces:
        if dlo is not None:
            rect(dlo, dhi, 255)
    im.save(path)
    return Path(path)


def write_plan_formats(folder: Path, b: GridBuilding) -> dict[str, Path]:
    """{'ifc', 'dxf', 'image'} -> the grid building written in that format under ``folder``."""
    return {"ifc": write_grid_building(folder / "plan.ifc", b), "dxf": draw_grid_dxf(folder / "plan.dxf", b),
            "image": draw_grid_png(folder / "plan.png", b)}
