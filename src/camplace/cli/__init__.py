"""camplace.cli: the command line (typer), a thin layer over camplace.workflows."""

from camplace.cli.app import main

__all__ = ["main"]
