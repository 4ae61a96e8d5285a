"""The planner's HTTP API (camplace.planner.app) through starlette's TestClient: the issue's
acceptance (move + save = evaluate's metrics; locked cameras kept by optimise, cost ≤ the
greedy completion; token, Host and save path refused) and 4xx JSON for bad bodies."""

from __future__ import annotations

import json
import math

import pytest
from starlette.testclient import TestClient

from camplace.planner.app import create_app
from camplace.planner.session import Session

TOKEN = "test-token"
BASE = "http://127.0.0.1:8765"


@pytest.fixture
def client(opened):
    app = create_app(Session(opened), TOKEN, port=8765)
    with TestClient(app, base_url=BASE, headers={"X-Camplace-Token": TOKEN}) as c:
        yield c


def no_timings(m: dict) -> dict:
    return {k: v for k, v in m.items() if k != "timings_s"}


def test_move_save_then_evaluate_gives_the_api_metrics(client, demo_dir):
    from camplace.workflows.evaluate import evaluate

    st = client.get("/api/state").json()
    cid = st["cameras"][0]["id"]
    moved = client.put(f"/api/cameras/{cid}", json={"position": [3.0, 3.0, 2.9], "yaw_deg": 250.0})
    assert moved.status_code == 200
    m = moved.json()["metrics"]
    assert m["cost"] != st["metrics"]["cost"]
    saved = client.post("/api/save", json={"dir": "edited"})
    assert saved.status_code == 200, saved.text
    out = saved.json()
    assert out["path"] == str((demo_dir / "edited").resolve())
    for name in ("placement.json", "metrics.json", "visibility.npz", "placement.csv", "report.html", "plan.pdf"):
        assert name in out["files"] and (demo_dir / "edited" / name).is_file()
    again = evaluate("demo", demo_dir / "edited" / "placement.json").metrics.to_dict()
    assert no_timings(again) == no_timings(m) == no_timings(out["metrics"])
    written = json.loads((demo_dir / "edited" / "metrics.json").read_text())
    assert no_timings(written) == no_timings(m)


def test_locked_cameras_stay_and_optimise_beats_their_greedy_completion(client, tmp_path):
    from camplace.workflows.run import run

    st = client.get("/api/state").json()
    keep = st["cameras"][1:3]
    for c in keep:
        assert client.put(f"/api/cameras/{c['id']}", json={"locked": True}).status_code == 200
    r = client.post("/api/optimize", json={"solver": "greedy", "time_limit_s": 20})
    assert r.status_code == 200 and r.json()["job"]
    events = []
    with client.stream("GET", "/api/optimize/events") as resp:
        assert resp.headers["content-type"].startswith("text/event-stream")
        name = None
        for line in resp.iter_lines():
            if line.startswith("event: "):
                name = line[7:]
            elif line.startswith("data: "):
                events.append((name, json.loads(line[6:])))
    assert events[-1][0] == "done" and any(n == "progress" for n, _ in events)
    done = events[-1][1]
    by_id = {c["id"]: c for c in done["cameras"]}
    for c in keep:
        assert by_id[c["id"]]["position"] == c["position"] and by_id[c["id"]]["yaw_deg"] == c["yaw_deg"]
        assert by_id[c["id"]]["locked"]
    assert len(done["cameras"]) == st["budget"]
    kept = tmp_path / "kept.json"
    kept.write_text(json.dumps({"cameras": [{k: c[k] for k in ("position", "yaw_deg", "pitch_deg", "roll_deg",
                                                               "camera")} for c in keep]}))
    greedy = run("demo", budget=st["budget"] - 2, solver="greedy", keep=kept)
    assert done["metrics"]["cost"] <= greedy.metrics.cost + 1e-9
    assert client.get("/api/state").json()["metrics"]["cost"] == done["metrics"]["cost"]


def test_cancel_keeps_the_best_so_far(client):
    r = client.post("/api/optimize", json={"solver": "tabu", "time_limit_s": 60})
    assert r.status_code == 200
    busy = client.put("/api/cameras/C1", json={"yaw_deg": 1.0})
    assert busy.status_code == 409 and busy.json()["field"] == "optimize"
    assert client.post("/api/optimize/cancel").status_code == 200
    last = None
    with client.stream("GET", "/api/optimize/events") as resp:
        for line in resp.iter_lines():
            if line.startswith("event: "):
                last = line[7:]
            elif line.startswith("data: ") and last == "done":
                done = json.loads(line[6:])
    assert last == "done" and done["optimize"]["seconds"] < 30 and math.isfinite(done["metrics"]["cost"])
    assert client.get("/api/state").json()["busy"] is None


def test_token_and_host_are_required(opened):
    app = create_app(Session(opened), TOKEN, port=8765)
    with TestClient(app, base_url=BASE) as c:
        r = c.get("/api/state")
        assert r.status_code == 401 and r.json()["field"] == "token"
        assert c.get("/api/state", headers={"X-Camplace-Token": "wrong"}).status_code == 403
        assert c.put("/api/cameras/C1", json={"yaw_deg": 1}).status_code == 401
        assert c.get("/").status_code == 401
        r = c.get("/api/state", headers={"X-Camplace-Token": TOKEN, "Host": "evil.example:8765"})
        assert r.status_code == 403 and r.json()["field"] == "host"
        assert c.get(f"/api/state?token={TOKEN}", headers={"Host": "127.0.0.1:9999"}).status_code == 403
        assert c.get(f"/api/state?token={TOKEN}").status_code == 200
        page = c.get(f"/?token={TOKEN}")  # the first visit sets the cookie ...
        assert page.status_code == 200 and "camplace_token" in page.headers.get("set-cookie", "")
        assert c.get("/api/state").status_code == 200  # ... which the later calls carry


def test_save_paths_outside_the_start_folder_are_refused(client, demo_dir, tmp_path):
    (demo_dir / "out-link").symlink_to(tmp_path, target_is_directory=True)
    for bad in ("../elsewhere", "a/../../b", str(tmp_path / "abs"), "out-link", "out-link/x", "", 5):
        r = client.post("/api/save", json={"dir": bad})
        assert r.status_code == 400 and r.json()["field"] == "dir", (bad, r.text)
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("body, field", [
    ({"position": [1, 2, 3, 4]}, "position"), ({"position": [1, "x", 2]}, "position"),
    ({"position": "1,2,3"}, "position"), ({"camera": "no-such-lens"}, "camera"), ({"camera": 3}, "camera"),
    ({"yaw_deg": True}, "yaw_deg"), ({"pitch_deg": 120}, "pitch_deg"), ({"locked": "yes"}, "locked"),
    ({"zoom": 2}, "zoom"),
])
def test_bad_bodies_are_4xx_naming_the_field(client, body, field):
    r = client.put("/api/cameras/C1", json=body)
    assert 400 <= r.status_code < 500 and r.json()["field"] == field and r.json()["error"].startswith(field)


def test_nan_bad_json_unknown_id_and_unknown_route(client):
    r = client.put("/api/cameras/C1", content=b'{"yaw_deg": NaN}')
    assert r.status_code == 400 and r.json()["field"] == "yaw_deg"
    r = client.put("/api/cameras/C1", content=b'{"yaw_deg": ')
    assert r.status_code == 400 and r.json()["field"] == "body"
    r = client.put("/api/cameras/C1", content=b'[1, 2]')
    assert r.status_code == 400 and r.json()["field"] == "body"
    r = client.put("/api/cameras/nope", json={"yaw_deg": 1})
    assert r.status_code == 404 and r.json()["field"] == "id"
    assert client.delete("/api/cameras/nope").status_code == 404
    assert client.get("/api/nothing").status_code == 404 and "error" in client.get("/api/nothing").json()
    r = client.post("/api/cameras", json={"yaw_deg": 1})
    assert r.status_code == 400 and r.json()["field"] == "position"
    for body, field in (({"solver": "nope"}, "solver"), ({"solver": "min-cameras"}, "solver"), ({"time_limit_s": -1}, "time_limit_s"),
                        ({"budget": 1.5}, "budget")):
        r = client.post("/api/optimize", json=body)
        assert r.status_code == 400 and r.json()["field"] == field


def test_add_delete_undo_redo_and_scene(client):
    sc = client.get("/api/scene").json()
    assert sc["name"] == "demo" and sc["mounts"] and sc["camera_types"][0]["hfov_deg"] > 0
    assert len(sc["targets_gamma"]) == len(sc["targets_xy"]) and "min-cameras" not in sc["solvers"]
    n0 = len(client.get("/api/state").json()["cameras"])
    s = client.post("/api/cameras", json={"position": sc["mounts"][0][:2], "yaw_deg": 45}).json()
    assert len(s["cameras"]) == n0 + 1 and s["cameras"][-1]["viewshed"]
    assert len(s["coverage_floor"]) == len(sc["targets_xy"])
    new_id = s["cameras"][-1]["id"]
    assert len(client.delete(f"/api/cameras/{new_id}").json()["cameras"]) == n0
    assert len(client.post("/api/undo").json()["cameras"]) == n0 + 1
    s = client.post("/api/redo").json()
    assert len(s["cameras"]) == n0 and s["can_undo"]


def test_serve_command_builds_the_app_without_starting_it(demo_dir):
    from camplace.cli.serve import planner_app

    app, url, session = planner_app(str(demo_dir), None, "127.0.0.1", 8770)
    assert url.startswith("http://127.0.0.1:8770/?token=")
    token = url.split("token=")[1]
    with TestClient(app, base_url="http://localhost:8770") as c:
        assert c.get("/api/state").status_code == 401
        assert c.get(f"/api/state?token={token}").json()["n_cameras"] == len(session.cams)


def test_camplace_serve_prints_the_url_serves_and_stops_on_ctrl_c(demo_dir):
    import signal
    import socket
    import subprocess
    import sys
    import time

    import httpx

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    proc = subprocess.Popen([sys.executable, "-c", "from camplace.cli import main; main()", "serve", str(demo_dir), "--port", str(port),
                             "--no-browser"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        url = proc.stdout.readline().strip()
        assert url.startswith(f"http://127.0.0.1:{port}/?token="), (url, proc.stderr.read() if proc.poll() else "")
        token = url.split("token=")[1]
        for _ in range(100):  # uvicorn starts after the URL is printed
            try:
                r = httpx.get(f"http://127.0.0.1:{port}/api/state", headers={"X-Camplace-Token": token}, timeout=5)
                break
            except httpx.TransportError:
                time.sleep(0.1)
        assert r.status_code == 200 and r.json()["cameras"]
        assert httpx.get(f"http://127.0.0.1:{port}/api/state", timeout=5).status_code == 401
        proc.send_signal(signal.SIGINT)
        assert proc.wait(timeout=20) == 0
        assert "Traceback" not in proc.stderr.read()
    finally:
        if proc.poll() is None:
            proc.kill()


def test_random_bodies_never_give_a_server_error(client):
    import random

    rnd = random.Random(7)
    values = [None, True, 0, -1, 1e308, -1e308, 3.5, "x", "", [], [1], [1, 2], [1e308, 0, 2.9], [0, 0, 0],
              [1, 2, "3"], {}, {"a": 1}, "wide", [[1, 2, 3]]]
    keys = ["position", "yaw_deg", "pitch_deg", "roll_deg", "camera", "locked", "snap", "solver", "budget",
            "time_limit_s", "dir", "other"]
    for n in range(60):
        body = {k: rnd.choice(values) for k in rnd.sample(keys, rnd.randint(0, 4))}
        method, path = rnd.choice([("PUT", "/api/cameras/C3"), ("POST", "/api/cameras"), ("PUT", "/api/cameras/x")])
        r = client.request(method, path, json=body)
        assert r.status_code < 500, (method, path, body, r.text)
        assert r.status_code == 200 or set(r.json()) == {"error", "field"}, (body, r.text)
