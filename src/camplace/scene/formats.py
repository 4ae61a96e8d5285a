"""The plan formats' registry (issue 35): entry points of the group ``camplace.importers``.

Kept apart from camplace.scene.importers (which imports shapely and the readers' helpers)
so that listing the formats - the suffix map, the CLI's help and messages - loads no
reader: camplace's own importers are :class:`PlanFormat` objects whose module is imported
at the first read. What an importer is and returns: camplace.scene.importers.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from pathlib import Path

from camplace.core.errors import InputError
from camplace.core.plugins import Registry

NATIVE_FORMATS = {  # closed or tool-native formats no open library reads: how to get a plan camplace reads
    ".dwg": "a DWG drawing (AutoCAD's own format); save it as DXF (AutoCAD, BricsCAD, DraftSight: Save As DXF; "
            "or the free ODA File Converter), then give the .dxf",
    ".rvt": "a Revit model; export it as IFC (Revit: File > Export > IFC), then give the .ifc",
    ".pln": "an ArchiCAD project; save it as IFC (File > Save As > IFC), then give the .ifc",
    ".skp": "a SketchUp model; export it as IFC or as a mesh (.obj, .glb), then give that file",
    ".3dm": "a Rhino model; export it as a mesh (.obj, .stl, .glb) or as DXF, then give that file",
}
@dataclass(frozen=True)
class PlanFormat:
    """A built-in importer (``camplace.importers`` entry point): its module (``read``,
    ``OPTIONS``, optional ``read_storeys`` / ``storey_elevations``) is imported at the first
    use of an attribute it holds, so listing the formats loads no reader (ifcopenshell)."""

    suffixes: tuple[str, ...]
    module: str
    label: str

    def __getattr__(self, attr: str):
        if attr.startswith("__"):
            raise AttributeError(attr)
        mod = importlib.import_module(self.module)
        if attr == "options":
            return tuple(getattr(mod, "OPTIONS", ()))
        try:
            return getattr(mod, attr)
        except AttributeError:
            raise AttributeError(f"{self.module} has no {attr}") from None


IFC = PlanFormat((".ifc", ".ifczip"), "camplace.scene.importers.ifc", "IFC (BIM) models")
DXF = PlanFormat((".dxf",), "camplace.scene.importers.dxf", "DXF drawings")
IMAGE = PlanFormat((".png", ".jpg", ".jpeg", ".tif", ".tiff", ".webp", ".bmp", ".gif", ".pdf"),
                   "camplace.scene.importers.image", "plan images and PDF pages")


def check_importer(name: str, obj):
    """The importer of the entry point ``name``: ``suffixes`` lowercase strings starting
    with '.', a callable ``read`` (TypeError otherwise)."""
    suffixes = getattr(obj, "suffixes", None)
    if isinstance(suffixes, str) or not suffixes or not all(
            isinstance(x, str) and x.startswith(".") and x == x.lower() and len(x) > 1 for x in suffixes):
        raise TypeError(f"suffixes: expected lowercase suffixes with the dot ('.geojson'), got {suffixes!r}")
    if not isinstance(obj, PlanFormat) and not callable(getattr(obj, "read", None)):  # a PlanFormat reads lazily
        raise TypeError("expected a callable read(path, **options)")
    return obj


IMPORTERS = Registry("camplace.importers", check_importer)


def plan_suffixes() -> dict[str, str]:
    """Suffix -> importer name over every registered importer (a suffix belongs to the
    first that claims it: camplace's own, then plugins in distribution order)."""
    out: dict[str, str] = {}
    for name in IMPORTERS:
        for suffix in IMPORTERS[name].suffixes:
            out.setdefault(suffix, name)
    return out


def formats_text() -> str:
    """The plan formats for messages and help: 'IFC (BIM) models (.ifc, .ifczip), DXF ...'."""
    rows = {}
    for suffix, name in plan_suffixes().items():
        rows.setdefault(name, []).append(suffix)
    return ", ".join(f"{getattr(IMPORTERS[n], 'label', None) or n} ({', '.join(sx)})" for n, sx in rows.items())


def plan_kind(path: str | Path) -> str | None:
    """The name of the importer of the file's suffix ('ifc', 'dxf', 'image' or a plugin's);
    None for anything else (InputError saying how to export it for a tool-native format,
    NATIVE_FORMATS)."""
    suffix = Path(path).suffix.lower()
    if suffix in NATIVE_FORMATS:
        raise InputError(f"{path}: {NATIVE_FORMATS[suffix]}")
    return plan_suffixes().get(suffix)


