"""The planner's web app (Starlette): the page, its static files and the JSON API under /api.

Security, as for a local notebook server: every /api call (and the page) needs the
session token (query ``token``, header ``X-Camplace-Token`` or the cookie
``camplace_token`` that ``GET /?token=T`` sets); the Host header must name the bound
address (127.0.0.1 / localhost / the host given, with the port) so a DNS-rebound page
cannot talk to it; no path outside the start folder is read or written
(camplace.planner.save.safe_dir); a bad request is a 4xx JSON error naming the field,
never a traceback. Routes: see docs/planner.md.
"""

from __future__ import annotations

import asyncio
import json
import secrets
from http.cookies import SimpleCookie
from pathlib import Path
from urllib.parse import parse_qs

from starlette.applications import Starlette
from starlette.concurrency import run_in_threadpool
from starlette.exceptions import HTTPException
from starlette.requests import Request
from starlette.responses import HTMLResponse, JSONResponse, Response, StreamingResponse
from starlette.routing import Mount, Route
from starlette.staticfiles import StaticFiles

from camplace.core.errors import InputError
from camplace.planner import bodies, optimize
from camplace.planner.errors import ApiError
from camplace.planner.save import save_session
from camplace.planner.statejson import state_bytes
from camplace.planner.sceneinfo import scene_payload

STATIC = Path(__file__).with_name("static")
COOKIE = "camplace_token"
HEADER = b"x-camplace-token"
SSE_POLL_S = 0.05


def new_token() -> str:
    """A fresh random session token (URL-safe)."""
    return secrets.token_urlsafe(24)


def _json_error(status: int, message: str, field: str | None) -> JSONResponse:
    return JSONResponse({"error": message, "field": field}, status_code=status)


class Guard:
    """ASGI middleware: the Host check (DNS rebinding) on every request and the token on
    the page and every /api call."""

    def __init__(self, app, token: str, hosts: set[str]) -> None:
        self.app, self.token, self.hosts = app, token, {h.lower() for h in hosts}

    def _token_of(self, scope) -> str | None:
        q = parse_qs(scope.get("query_string", b"").decode("latin-1")).get("token")
        if q:
            return q[0]
        headers = dict(scope.get("headers") or [])
        if HEADER in headers:
            return headers[HEADER].decode("latin-1")
        if b"cookie" in headers:
            c = SimpleCookie()
            try:
                c.load(headers[b"cookie"].decode("latin-1"))
            except Exception:  # noqa: BLE001 - a malformed cookie header is no token
                return None
            if COOKIE in c:
                return c[COOKIE].value
        return None

    async def __call__(self, scope, receive, send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        headers = dict(scope.get("headers") or [])
        host = headers.get(b"host", b"").decode("latin-1").lower()
        if host not in self.hosts:
            await _json_error(403, f"host: requests must address {sorted(self.hosts)[0]} (got {host!r})",
                              "host")(scope, receive, send)
            return
        path = scope.get("path", "")
        if path == "/" or path.startswith("/api"):
            got = self._token_of(scope)
            if got is None:
                await _json_error(401, "token: missing; open the URL camplace serve printed (it holds ?token=...)",
                                  "token")(scope, receive, send)
                return
            if not secrets.compare_digest(got.encode("utf-8", "replace"), self.token.encode()):
                await _json_error(403, "token: wrong token; open the URL camplace serve printed", "token")(
                    scope, receive, send)
                return
        await self.app(scope, receive, send)


def api(fn):
    """A route from ``fn(request, body_dict) -> dict`` run in a worker thread; ApiError and
    InputError become 4xx JSON errors naming the field."""
    async def endpoint(request: Request) -> Response:
        try:
            body = bodies.parse_json(await request.body()) if request.method in ("PUT", "POST") else {}
            out = await run_in_threadpool(fn, request, body)
        except ApiError as err:
            return JSONResponse(err.payload(), status_code=err.status)
        except InputError as err:
            return _json_error(400, str(err), err.option or "body")
        except Exception as err:  # noqa: BLE001 - a bug: one JSON line, no traceback in the page
            return _json_error(500, f"internal error: {type(err).__name__}: {err}", None)
        if isinstance(out, Response):
            return out
        if isinstance(out, dict) and "cameras" in out and "version" in out:  # a state: cameras encoded once
            return Response(state_bytes(out), media_type="application/json")
        return JSONResponse(out)
    return endpoint


def create_app(session, token: str, hosts: set[str] | None = None, port: int = 8765) -> Starlette:
    """The ASGI app of a camplace.planner.session.Session. ``hosts``: the Host header
    values accepted (default 127.0.0.1:port and localhost:port)."""
    hosts = hosts or {f"127.0.0.1:{port}", f"localhost:{port}"}
    scene_info = scene_payload(session)

    async def page(request: Request) -> Response:
        index = STATIC / "index.html"
        html = index.read_text(encoding="utf-8") if index.is_file() else \
            "<!doctype html><title>camplace planner</title><p>The planner page is not installed.</p>"
        resp = HTMLResponse(html)
        if request.query_params.get("token"):
            resp.set_cookie(COOKIE, token, httponly=True, samesite="strict", path="/")
        return resp

    def camera_id(request: Request) -> str:
        return request.path_params["id"]

    def put_camera(request, body):
        return session.update(camera_id(request), bodies.camera_change(body))

    def post_camera(request, body):
        return session.add(bodies.new_camera(body))

    def delete_camera(request, body):
        return session.delete(camera_id(request))

    def post_optimize(request, body):
        job = optimize.start(session, bodies.optimize_request(body, session.budget))
        return {"job": job.id}

    def post_cancel(request, body):
        job = session.job
        if job is None or job.finished:
            raise ApiError("optimize: no optimisation is running", "optimize", 409)
        job.stop.set()
        return {"job": job.id, "cancelled": True}

    def post_save(request, body):
        return save_session(session, bodies.save_dir(body))

    async def events(request: Request) -> Response:
        job = session.job
        if job is None:
            return _json_error(409, "optimize: no optimisation was started (POST /api/optimize first)", "optimize")

        async def stream():
            k = 0
            while True:
                got, finished = job.since(k)
                for name, data in got:
                    yield f"event: {name}\ndata: {json.dumps(data)}\n\n"
                k += len(got)
                if finished and not got:
                    return
                if not got:
                    await asyncio.sleep(SSE_POLL_S)
        return StreamingResponse(stream(), media_type="text/event-stream",
                                 headers={"Cache-Control": "no-cache", "X-Accel-Buffering": "no"})

    async def not_found(request: Request, exc: HTTPException) -> Response:
        what = "path" if exc.status_code == 404 else "method"
        return _json_error(exc.status_code, f"{what}: {request.method} {request.url.path}: {exc.detail}", what)

    routes = [
        Route("/", page, methods=["GET"]),
        Route("/api/scene", api(lambda request, body: scene_info), methods=["GET"]),
        Route("/api/state", api(lambda request, body: session.state()), methods=["GET"]),
        Route("/api/cameras", api(post_camera), methods=["POST"]),
        Route("/api/cameras/{id}", api(put_camera), methods=["PUT"]),
        Route("/api/cameras/{id}", api(delete_camera), methods=["DELETE"]),
        Route("/api/undo", api(lambda request, body: session.undo()), methods=["POST"]),
        Route("/api/redo", api(lambda request, body: session.redo()), methods=["POST"]),
        Route("/api/optimize", api(post_optimize), methods=["POST"]),
        Route("/api/optimize/events", events, methods=["GET"]),
        Route("/api/optimize/cancel", api(post_cancel), methods=["POST"]),
        Route("/api/save", api(post_save), methods=["POST"]),
        Mount("/static", StaticFiles(directory=STATIC, check_dir=False), name="static"),
    ]
    app = Starlette(routes=routes, exception_handlers={HTTPException: not_found})
    app.add_middleware(Guard, token=token, hosts=set(hosts))
    return app
