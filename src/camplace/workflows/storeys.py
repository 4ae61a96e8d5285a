"""Folder- and file-safe names of a building's storeys (the per-storey preview files of a
building import, camplace.cli.scene_import)."""

from __future__ import annotations

import re


def storey_slugs(names: list[str]) -> list[str]:
    """A folder-safe slug per storey name ('Ground Floor' -> 'ground-floor'), unique
    (-2, -3... on repeats; 'storey-K' when a name has no letters or digits)."""
    out: list[str] = []
    for k, name in enumerate(names):
        base = re.sub(r"[^a-z0-9]+", "-", name.lower()).strip("-") or f"storey-{k + 1}"
        slug, n = base, 1
        while slug in out:
            n += 1
            slug = f"{base}-{n}"
        out.append(slug)
    return out
