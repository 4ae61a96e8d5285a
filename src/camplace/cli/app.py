"""The ``camplace`` command line: the typer app, its global options and its commands
(one module each in camplace.cli; each a thin layer over camplace.workflows)."""

from __future__ import annotations

import atexit
import gc

import typer
from rich.markup import escape

from camplace.cli import (bench, common, compare, demo, essential, evaluate, render, run, scan, scenes, serve, solve,
                          solvers)
from camplace.cli.common import StopFlag as _StopFlag  # noqa: F401 - the Ctrl-C flag, imported here by older tests
from camplace.cli.scene_import import scene_app

app = typer.Typer(add_completion=False, no_args_is_help=True,
                  help="camplace: choose where to mount cameras so every place gets the coverage it needs.")


@app.callback()
def _main(debug: bool = typer.Option(False, "--debug", help="Show Python tracebacks on errors."),
          quiet: bool = typer.Option(False, "--quiet", "-q", help="Only errors and the output paths."),
          verbose: bool = typer.Option(False, "--verbose", "-v", help="Also show stage details, solver "
                                       "information and every file written."),
          json_out: bool = typer.Option(False, "--json", help="Print a JSON summary on stdout (for scripts); "
                                        "progress and messages stay on stderr.")) -> None:
    common.state.update(debug=debug, quiet=quiet, verbose=verbose and not quiet, json=json_out)


app.command("demo")(demo.demo)
app.command("run")(run.run_cmd)
app.command("bench")(bench.bench)
app.command("solve")(solve.solve_cmd)
app.command("evaluate")(evaluate.evaluate_cmd)
app.command("compare-visibility")(compare.compare_visibility_cmd)
app.command("render")(render.render)
app.command("scan")(scan.scan)
app.command("essential")(essential.essential)
app.command("scenes")(scenes.scenes)
app.command("solvers")(solvers.solvers)
app.command("serve")(serve.serve)
app.add_typer(scene_app, name="scene")


def _plugin_warnings_as_lines() -> None:
    """A plugin skipped at load (camplace.core.plugins.PluginWarning) is one 'warning:' line."""
    import warnings

    from camplace.core.plugins import PluginWarning

    shown = warnings.showwarning
    if getattr(shown, "camplace_plugins", False):  # installed already (main() called again in-process)
        return

    def show(message, category, *args, **kwargs):
        if issubclass(category, PluginWarning):
            common.console.print(f"[yellow]warning: {escape(str(message))}[/yellow]", highlight=False, soft_wrap=True)
        else:
            shown(message, category, *args, **kwargs)

    show.camplace_plugins = True  # type: ignore[attr-defined]
    warnings.showwarning = show


def main() -> None:
    """Entry point: run the app, turning CamplaceError into one line + exit code."""
    _plugin_warnings_as_lines()
    from camplace.cli.scene_import import import_cmd
    from camplace.cli.space import with_plan_formats

    with_plan_formats(run.run_cmd, import_cmd)  # the help lists the registered plan formats
    # at exit, Python then skips sweeping every object for cycles (numba, scipy, matplotlib: ~1 s after a
    # run, once every file is written); once per process (tests call main() many times)
    atexit.unregister(gc.freeze)
    atexit.register(gc.freeze)
    common.run_main(app)


if __name__ == "__main__":  # pragma: no cover
    main()
