"""A made-up plugin distribution for the plan-format and output-file registries (issue 35):
a '.rooms' importer returning a plain scene mapping, a writer of count.txt, and broken ones
of both kinds (an importer without suffixes, a writer that raises, one that is no callable)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

PLUGIN = '''
import json
from pathlib import Path


class Rooms:
    suffixes = (".rooms",)

    def read(self, path, *, wall_height=None):
        d = json.loads(Path(path).read_text())
        room = {"footprint": d["outline"], **({"height": d["height"]} if "height" in d else {})}
        return {"room": room, "zones": [{"name": n, "polygon": p} for n, p in d["rooms"].items()]}


class NoSuffix:
    def read(self, path):
        return {}


ROOMS, NO_SUFFIX, NOT_CALLABLE = Rooms(), NoSuffix(), 3


def write_count(out_dir, result):
    path = Path(out_dir) / "count.txt"
    path.write_text(f"{len(result.placement['cameras'])} {result.metrics['cost']}")
    return [path]


def write_fails(out_dir, result):
    raise RuntimeError("disk on fire")
'''

GROUPS = {"camplace.importers": {"rooms": "cp_rooms_plugin:ROOMS", "no-suffix": "cp_rooms_plugin:NO_SUFFIX"},
          "camplace.outputs": {"count": "cp_rooms_plugin:write_count", "fails": "cp_rooms_plugin:write_fails",
                               "not-callable": "cp_rooms_plugin:NOT_CALLABLE"}}
OUTLINE = [[0, 0], [6, 0], [6, 4], [0, 4]]
ROOMS = {"Office": [[0, 0], [3, 0], [3, 4], [0, 4]], "Lab": [[3, 0], [6, 0], [6, 4], [3, 4]]}


def write_rooms(path: Path, outline=OUTLINE, rooms=ROOMS) -> Path:
    """A '.rooms' plan: two 3 m x 4 m rooms side by side in a 6 m x 4 m outline."""
    path.write_text(json.dumps({"outline": outline, "rooms": rooms}))
    return path


def installed(root: Path):
    """Install the made-up distribution into ``root``, put it on sys.path and load both
    registries again; a generator for a fixture, yielding the PluginWarning texts of the
    load (undone after it)."""
    import warnings

    from camplace.outputs.writers import OUTPUTS
    from camplace.scene.formats import IMPORTERS
    from conftest import plugin_dist

    plugin_dist(root, "rooms-plugin", GROUPS, {"cp_rooms_plugin": PLUGIN})
    sys.path.insert(0, str(root))
    IMPORTERS.reload()
    OUTPUTS.reload()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        list(IMPORTERS), list(OUTPUTS)
    try:
        yield [str(w.message) for w in caught]
    finally:
        sys.path.remove(str(root))
        sys.modules.pop("cp_rooms_plugin", None)
        IMPORTERS.reload()
        OUTPUTS.reload()
