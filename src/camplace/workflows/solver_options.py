"""The solver and its options checked before any heavy stage of a run: the solver's name,
the options it declares (camplace.solvers.build_options) and the scene's
``placement.options``, each refused with one line naming the key."""

from __future__ import annotations

from camplace.core.errors import InputError
from camplace.spec.schema import SceneSpec


def check_solver_name(name: str, key: str) -> None:
    """InputError naming ``key`` (e.g. '--solver' or 'scene.yaml: placement.solver') for an unknown solver."""
    from camplace.spec.wording import did_you_mean as _did_you_mean
    from camplace.solvers import SOLVERS

    if name not in SOLVERS:
        raise InputError(f"{key}: unknown solver '{name}'{_did_you_mean(name, list(SOLVERS))}; expected one of "
                         f"{', '.join(sorted(SOLVERS))}")


def check_solver_options(name: str, options: dict, triangulation_deg: tuple[float, float] = (20.0, 160.0)) -> str:
    """InputError(option=key) for a solver option that solver ``name`` does not take or a
    value that does not fit its type, before any heavy stage (callbacks pass;
    'greedy-triangulated' also gets the angle range). Returns the given options as the
    solver reads them ('restarts=3, seed=5'; '' when none)."""
    from camplace.solvers import build_options
    from camplace.solvers.contract import HOOK_FIELDS

    opts = {k: v for k, v in options.items() if k not in HOOK_FIELDS}
    given = list(opts)
    if name == "greedy-triangulated":
        opts.update(min_deg=triangulation_deg[0], max_deg=triangulation_deg[1])
    built = build_options(name, **opts)
    return ", ".join(f"{k}={getattr(built, k)!r}" for k in given)


def scene_solver_options(spec: SceneSpec, solver: str, source: str, log: list | None = None) -> dict:
    """The scene's ``placement.options``, checked against ``placement.solver`` (InputError
    naming the file and the key path ``placement.options.KEY``); {} when the run uses
    another ``solver`` (a line in ``log`` says so)."""
    from camplace.solvers import build_options

    opts = dict(spec.placement.options)
    if not opts:
        return {}
    if "time_limit_s" in opts:
        raise InputError(f"{source}: placement.options.time_limit_s: give the time limit as placement.time_limit_s")
    try:
        build_options(spec.placement.solver, **opts)
    except InputError as err:
        msg = str(err)
        key = err.option or ""
        raise InputError(f"{source}: placement.options.{key}: {msg.removeprefix(key + ':').strip()}") from None
    if solver != spec.placement.solver:
        if log is not None:
            log.append(f"placement.options ({', '.join(opts)}) not used: they are for solver "
                       f"'{spec.placement.solver}', the run uses '{solver}'")
        return {}
    return opts
