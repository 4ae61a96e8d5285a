"""Buildings on the command line (issue 33): ``--storey all`` / ``--storey A,B`` on a
multi-storey plan (IFC storeys, several plans on one DXF sheet or image, PDF pages), or
several plan files with ``--elevations``, become one building scene (``storeys:``) that
``camplace run`` plans in one run and ``camplace scene import`` writes as one YAML file."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from rich.markup import escape

from camplace.cli.common import console
from camplace.cli.space import ImportOptions, key_values, plan_names, space_kind
from camplace.core.errors import InputError
from camplace.spec.wording import did_you_mean, name_list

ELEVATIONS_OPT = typer.Option(None, "--elevations", help="Several plan files: each file's floor elevation in m, "
                                                         "comma-separated in file order (e.g. 0,3.5).")
STOREY_BUDGET_OPT = typer.Option(None, "--storey-budget", help="A building: at most K cameras on storey NAME "
                                                               "(NAME=K; repeat for several storeys).")
STOREY_HEIGHT_M = 3.0  # plans on one sheet with no elevations: storey k's floor at k times this (said in a note)


def is_building(scenes: list[str], storey: Optional[str]) -> bool:
    """True when the command plans a building: several files, or --storey all / A,B."""
    return len(scenes) > 1 or (storey is not None and (storey == "all" or "," in storey))


def storey_budgets(values: Optional[list[str]]) -> dict[str, int]:
    """--storey-budget NAME=K values -> {NAME: K} (InputError naming the flag)."""
    return key_values(values, "--storey-budget", int, lambda n: n >= 0, "NAME=K (K a whole number >= 0)")


def _elevations(text: Optional[str], n: int) -> list[float] | None:
    if text is None:
        return None
    try:
        vals = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise InputError(f"--elevations: expected numbers in m separated by commas, got '{text}'") from None
    if len(vals) != n:
        raise InputError(f"--elevations: {len(vals)} value(s) for {n} plan file(s); expected one per file")
    if sorted(set(vals)) != sorted(vals):
        raise InputError(f"--elevations: two files on one floor elevation ({text}); expected one floor each")
    return vals


def _checked(path: Path) -> Path:
    if space_kind(str(path)) != "plan":
        raise InputError(f"{path}: several files or --storey all take plans ({plan_names()})")
    if not path.is_file():
        raise InputError(f"{path}: file not found" if not path.exists() else f"{path}: is a folder, expected a file")
    return path


def building_storeys(files: list[str], opts: ImportOptions, budget: Optional[int],
                     elevations: Optional[str] = None) -> tuple[str, list, list]:
    """(building name, [(storey, scene mapping, elevation m, floor openings)], [(storey, PlanImport)])
    of the plans given: one file's storeys (--storey all or A,B) or one storey per file
    (--elevations). Plans side by side on one sheet are aligned on their lower-left corner."""
    from camplace.scene.importers import read_plan, read_storey_plans, validated
    from camplace.workflows.building import align_plans
    from camplace.workflows.storeys import unique_names

    paths = [_checked(Path(f)) for f in files]
    if len(paths) > 1:
        elev = _elevations(elevations, len(paths))
        if elev is None:
            raise InputError(f"--elevations: {len(paths)} plan files need one floor elevation each in m, "
                             f"e.g. --elevations {','.join(str(round(k * STOREY_HEIGHT_M, 1)) for k in range(len(paths)))}")
        names = unique_names([p.stem for p in paths])
        got = [(n, read_plan(p, **opts.plan_kwargs(budget)), e) for n, p, e in zip(names, paths, elev)]
        name = "-".join(p.stem for p in paths[:2]) + ("-etc" if len(paths) > 2 else "")
    else:
        if elevations is not None:
            raise InputError("--elevations: belongs to several plan files (one elevation per file)")
        want = opts.storey
        found = read_storey_plans(paths[0], **dict(opts.plan_kwargs(budget), storey="all"))
        if want not in (None, "all"):
            names = [n for n, _, _ in found]
            chosen = [w.strip() for w in want.split(",") if w.strip()]
            for w in chosen:
                if w not in names:
                    raise InputError(f"--storey: no storey '{w}' in {paths[0].name}{did_you_mean(w, names)}; "
                                     f"expected names from {name_list(names)}")
            found = [f for f in found if f[0] in chosen]
        kinds = {got.kind for _, got, _ in found}
        if kinds & {"dxf", "image"} and len(found) > 1 and len({e for _, _, e in found}) == 1:
            found = [(n, got, k * STOREY_HEIGHT_M) for k, (n, got, _) in enumerate(found)]
            found = [(n, got, e) for (n, got, e) in align_plans(found)]
        got = found
        name = paths[0].stem
    storeys = [(n, validated(g.scene, f"{name} (storey '{n}')"), e, g.floor_openings) for n, g, e in got]
    return name, storeys, [(n, g) for n, g, _ in got]


def building_spec(files: list[str], opts: ImportOptions, budget: Optional[int], elevations: Optional[str],
                  budgets: dict[str, int]):
    """(parsed building SceneSpec, [(storey, PlanImport)]) of the plans given (building_storeys),
    with the per-storey budgets ``budgets`` ({storey: K}; an unknown storey is an InputError)."""
    from camplace.spec.loading import parse_scene
    from camplace.workflows.building import building_scene

    name, storeys, imports = building_storeys(files, opts, budget, elevations)
    notes: list[str] = []
    data = building_scene(name, storeys, budget, notes)
    imports = [(n, got) for n, got in imports if n in data["storeys"]]
    for line in notes:
        console.print(f"[yellow]note: {escape(line)}[/yellow]")
    for st, k in budgets.items():
        if st not in data["storeys"]:
            raise InputError(f"--storey-budget: no storey '{st}'{did_you_mean(st, list(data['storeys']))}; expected "
                             f"names from {name_list(list(data['storeys']))}")
        data["storeys"][st]["budget"] = k
    return parse_scene(data, name), imports, data

