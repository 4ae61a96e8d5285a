"""``geojson``: floor plans as GeoJSON (a plan format added by a plugin, issue 35).

A FeatureCollection of Polygon features in metres (a local plan frame, not longitude and
latitude). Each feature's ``properties.kind`` says what it is: ``room`` (its ``name``
becomes a zone), ``wall`` or ``obstacle`` (a prism from the floor up to ``height`` m, by
default the ceiling), ``outline`` (the building's footprint; default: the bounding box
of every feature). The importer returns a plain scene-file mapping; camplace adds the
targets, cameras, mounts and budget every plan import gets and checks it like a scene file.
"""

from __future__ import annotations

import json
from pathlib import Path

from camplace.core.errors import InputError


def _ring(feature: dict, path: Path, k: int) -> list[list[float]]:
    """The outer ring of a Polygon feature, without the closing point."""
    geom = feature.get("geometry") or {}
    if geom.get("type") != "Polygon" or not geom.get("coordinates"):
        raise InputError(f"{path}: features[{k}]: expected a Polygon geometry, got {geom.get('type')!r}")
    ring = [[float(x), float(y)] for x, y, *_ in geom["coordinates"][0]]
    return ring[:-1] if len(ring) > 1 and ring[0] == ring[-1] else ring


class GeoJSONImporter:
    """The importer object the entry point loads: ``suffixes`` and ``read``."""

    suffixes = (".geojson",)
    label = "GeoJSON floor plans"

    def read(self, path: Path, *, ceiling_height: float | None = None) -> dict:
        """The scene mapping of a GeoJSON plan (``ceiling_height`` m, default 3)."""
        try:
            data = json.loads(Path(path).read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as err:
            raise InputError(f"{path}: not a GeoJSON file ({err})") from None
        if not isinstance(data, dict) or data.get("type") != "FeatureCollection":
            raise InputError(f"{path}: expected a GeoJSON FeatureCollection")
        height = 3.0 if ceiling_height is None else float(ceiling_height)
        rings = {"room": [], "wall": [], "obstacle": [], "outline": []}
        for k, feature in enumerate(data.get("features", [])):
            props = feature.get("properties") or {}
            kind = props.get("kind", "room")
            if kind not in rings:
                raise InputError(f"{path}: features[{k}].properties.kind: expected one of {', '.join(rings)}, "
                                 f"got {kind!r}")
            rings[kind].append((props, _ring(feature, path, k)))
        every = [p for rs in rings.values() for _, r in rs for p in r]
        if not every:
            raise InputError(f"{path}: no polygon features")
        if rings["outline"]:
            footprint = rings["outline"][0][1]
        else:
            xs, ys = [p[0] for p in every], [p[1] for p in every]
            footprint = [[min(xs), min(ys)], [max(xs), min(ys)], [max(xs), max(ys)], [min(xs), max(ys)]]
        obstacles = [{"name": props.get("name") or f"{kind}-{n + 1}",
                      "prism": {"polygon": ring, "z": [0.0, float(props.get("height", height))]}}
                     for kind in ("wall", "obstacle") for n, (props, ring) in enumerate(rings[kind])]
        zones = [{"name": props.get("name") or f"room-{n + 1}", "polygon": ring}
                 for n, (props, ring) in enumerate(rings["room"])]
        return {"name": Path(path).stem, "room": {"footprint": footprint, "height": height},
                "obstacles": obstacles, "zones": zones}


GEOJSON = GeoJSONImporter()
