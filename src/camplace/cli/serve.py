"""``camplace serve``: the planner, a local web page to adjust a placement by hand
(camplace.planner). Importing this module starts nothing; :func:`serve` does."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from camplace.cli.common import CACHE_OPT, NO_CACHE_OPT, console, progress_bars, RichProgress, scale_options


def planner_app(target: str, scene: Optional[str], host: str, port: int, progress=None, cache_dir=None):
    """(app, url with the token, session) for ``target`` (a run folder or a scene), nothing started;
    ``cache_dir``: the visibility block cache (None: V is raycast anew)."""
    from camplace.planner.app import create_app, new_token
    from camplace.planner.opening import open_start
    from camplace.planner.session import Session

    session = Session(open_start(target, scene, root=None, progress=progress, cache_dir=cache_dir))
    token = new_token()
    names = {"127.0.0.1", "localhost", host, "[::1]"}
    hosts = {f"{h}:{port}" for h in names} | (names if port == 80 else set())  # port 80: browsers omit it
    url = f"http://{'127.0.0.1' if host in ('0.0.0.0', '127.0.0.1') else host}:{port}/?token={token}"
    return create_app(session, token, hosts, port), url, session


def check_port(host: str, port: int) -> None:
    """InputError when ``host:port`` cannot be bound (in use, or not an address of this machine)."""
    import socket

    from camplace.core.errors import InputError

    try:
        with socket.socket(socket.AF_INET6 if ":" in host else socket.AF_INET) as s:
            s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            s.bind((host, port))
    except OSError as err:
        raise InputError(f"--port {port}: cannot listen on {host}:{port} ({err.strerror or err}); choose another "
                         f"--port or --host") from None


def serve(target: str = typer.Argument(..., help="A run folder (with placement.json) or a scene (YAML file or "
                                       "built-in name; it is run first, on the grid)."),
          scene: Optional[str] = typer.Option(None, "--scene", help="The scene of the run folder, when it is not a "
                                              "built-in scene nor a YAML beside the folder."),
          port: int = typer.Option(8765, "--port", min=1, max=65535, help="Port to listen on."),
          host: str = typer.Option("127.0.0.1", "--host", help="Address to bind (default: this machine only)."),
          no_browser: bool = typer.Option(False, "--no-browser", help="Do not open the page in a browser."),
          cache: Optional[Path] = CACHE_OPT, no_cache: bool = NO_CACHE_OPT) -> None:
    """Adjust a placement by hand in the browser: drag, turn, add, delete, lock cameras and
    watch coverage, cost and gap update; optimise the unlocked rest; save as camplace
    evaluate would. Prints the page's URL (with its token); Ctrl-C stops the server. V comes
    from the visibility cache that ``camplace run`` filled (same --cache), so a site-scale run
    opens without raycasting again."""
    import uvicorn

    check_port(host, port)
    with progress_bars() as prog:
        app, url, session = planner_app(target, scene, host, port, RichProgress(prog),
                                         scale_options(1, None, cache, no_cache)["cache_dir"])
    console.print(f"camplace planner: {session.scene.name}, {len(session.cams)} cameras; saves under "
                  f"{session.opened.root}")
    typer.echo(url)
    if not no_browser:
        import webbrowser

        try:
            webbrowser.open(url)
        except Exception:  # noqa: BLE001 - no browser here: the URL is printed
            pass
    try:
        uvicorn.run(app, host=host, port=port, log_level="warning", timeout_graceful_shutdown=2)
    except KeyboardInterrupt:
        pass
    console.print("camplace planner: stopped")

