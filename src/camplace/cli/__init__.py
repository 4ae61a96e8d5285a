"""camplace.cli (layer 13): the command line (typer), a thin layer over camplace.workflows: one
module per command, the app in camplace.cli.app, shared options and error wording in
camplace.cli.common."""

from __future__ import annotations


def main() -> None:
    """The ``camplace`` entry point (camplace.cli.app.main, imported when called)."""
    from camplace.cli.app import main as app_main

    app_main()


__all__ = ["main"]
