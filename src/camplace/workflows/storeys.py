"""Folder- and file-safe names of a building's storeys (the per-storey preview files of a
building import, camplace.cli.scene_import)."""

from __future__ import annotations

import re


def unique_names(names: list[str]) -> list[str]:
    """``names`` made unique in order: a repeat gets -2, -3, ... ('plan', 'plan-2')."""
    out: list[str] = []
    for base in names:
        name, n = base, 1
        while name in out:
            n += 1
            name = f"{base}-{n}"
        out.append(name)
    return out


def storey_slugs(names: list[str]) -> list[str]:
    """A folder-safe slug per storey name ('Ground Floor' -> 'ground-floor'), unique
    (-2, -3... on repeats; 'storey-K' when a name has no letters or digits)."""
    return unique_names([re.sub(r"[^a-z0-9]+", "-", name.lower()).strip("-") or f"storey-{k + 1}"
                         for k, name in enumerate(names)])
