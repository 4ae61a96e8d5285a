"""report.html: content checks, and a real browser (headless Debian chromium) that opens
it offline and must render the 3D view and every figure without a console error.

The browser is driven through the Chrome DevTools protocol over a pipe
(``--remote-debugging-pipe``: JSON messages on fds 3/4, NUL-terminated), so no
downloaded browser, driver or websocket package is needed.

Run as a script to take the README screenshot:
    python tests/test_report_html.py REPORT.html OUT.png
"""

from __future__ import annotations

import base64
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pytest

CHROMIUM = next((p for p in ("/usr/bin/chromium", shutil.which("chromium") or "", shutil.which("chromium-browser") or "")
                 if p and os.path.exists(p)), None)


# ----------------------------------------------------------------------------- CDP over a pipe
class Browser:
    """A headless chromium driven through the DevTools protocol over a pipe."""

    def __init__(self, width: int = 1400, height: int = 1000) -> None:
        self.profile = tempfile.mkdtemp(prefix="camplace-chromium-")
        to_chrome_r, self._w = os.pipe()
        self._r, from_chrome_w = os.pipe()

        def _fds() -> None:  # runs in the child before exec: the pipe ends become fds 3 and 4
            os.dup2(to_chrome_r, 3)
            os.dup2(from_chrome_w, 4)

        args = [CHROMIUM, "--headless", "--no-sandbox", "--remote-debugging-pipe", "--no-first-run",
                "--disable-background-networking", "--disable-component-update", "--disable-sync",
                "--disable-default-apps", "--disable-extensions", "--mute-audio", "--hide-scrollbars",
                "--disable-dev-shm-usage",  # containers often have a tiny /dev/shm
                "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist",
                "--host-resolver-rules=MAP * ~NOTFOUND",  # offline: no name resolves
                f"--window-size={width},{height}", f"--user-data-dir={self.profile}", "about:blank"]
        self.proc = subprocess.Popen(args, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                     stderr=subprocess.DEVNULL, preexec_fn=_fds, pass_fds=(3, 4))
        os.close(to_chrome_r)
        os.close(from_chrome_w)
        self._buf = b""
        self._id = 0
        self.events: list[dict] = []
        self.session: str | None = None

    def _send(self, method: str, params: dict | None = None, session: bool = True) -> int:
        self._id += 1
        msg = {"id": self._id, "method": method, "params": params or {}}
        if session and self.session:
            msg["sessionId"] = self.session
        os.write(self._w, json.dumps(msg).encode() + b"\0")
        return self._id

    def _read(self, timeout: float) -> dict:
        import select

        while b"\0" not in self._buf:
            ready, _, _ = select.select([self._r], [], [], timeout)
            if not ready:
                raise TimeoutError("chromium did not answer")
            chunk = os.read(self._r, 1 << 20)
            if not chunk:
                raise RuntimeError("chromium closed the pipe")
            self._buf += chunk
        raw, self._buf = self._buf.split(b"\0", 1)
        return json.loads(raw)

    def call(self, method: str, params: dict | None = None, session: bool = True, timeout: float = 60) -> dict:
        want = self._send(method, params, session)
        t_end = time.monotonic() + timeout
        while True:
            msg = self._read(max(0.1, t_end - time.monotonic()))
            if msg.get("id") == want:
                if "error" in msg:
                    raise RuntimeError(f"{method}: {msg['error']}")
                return msg.get("result", {})
            if "method" in msg:
                self.events.append(msg)
            if time.monotonic() > t_end:
                raise TimeoutError(method)

    def open(self, url: str) -> None:
        target = self.call("Target.createTarget", {"url": "about:blank"}, session=False)["targetId"]
        self.session = self.call("Target.attachToTarget", {"targetId": target, "flatten": True},
                                 session=False)["sessionId"]
        for domain in ("Runtime", "Log", "Network", "Page"):
            self.call(f"{domain}.enable")
        self.call("Page.navigate", {"url": url})

    def evaluate(self, expression: str):
        r = self.call("Runtime.evaluate", {"expression": expression, "returnByValue": True})
        if "exceptionDetails" in r:
            raise RuntimeError(f"evaluate failed: {r['exceptionDetails']}")
        return r["result"].get("value")

    def wait_for(self, expression: str, timeout: float = 60.0):
        t_end = time.monotonic() + timeout
        while time.monotonic() < t_end:
            v = self.evaluate(expression)
            if v:
                return v
            time.sleep(0.2)
        raise TimeoutError(f"waited {timeout} s for {expression}")

    def console_errors(self) -> list[str]:
        out = []
        for e in self.events:
            m, p = e.get("method"), e.get("params", {})
            if m == "Runtime.exceptionThrown":
                d = p.get("exceptionDetails", {})
                out.append((d.get("exception") or {}).get("description") or d.get("text", "exception"))
            elif m == "Runtime.consoleAPICalled" and p.get("type") in ("error", "assert"):
                out.append(" ".join(str(a.get("value", a.get("description", ""))) for a in p.get("args", [])))
            elif m == "Log.entryAdded" and p.get("entry", {}).get("level") == "error":
                out.append(p["entry"].get("text", ""))
        return out

    def requested_urls(self) -> list[str]:
        return [e["params"]["request"]["url"] for e in self.events if e.get("method") == "Network.requestWillBeSent"]

    def screenshot(self, path: str | Path, width: int = 1400, height: int = 1000) -> None:
        self.call("Emulation.setDeviceMetricsOverride",
                  {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False})
        time.sleep(1.0)  # let the responsive plots re-layout
        png = base64.b64decode(self.call("Page.captureScreenshot", {"format": "png"})["data"])
        Path(path).write_bytes(png)

    def close(self) -> None:
        try:
            self._send("Browser.close", session=False)
            self.proc.wait(timeout=10)
        except Exception:  # noqa: BLE001 - best effort, then kill our own child
            self.proc.kill()
            self.proc.wait()
        for fd in (self._r, self._w):
            try:
                os.close(fd)
            except OSError:
                pass
        shutil.rmtree(self.profile, ignore_errors=True)


PLOT_CHECK = """
(() => {
  const out = {};
  for (const div of document.querySelectorAll('div.plot')) {
    const r = {svg: !!div.querySelector('svg.main-svg'), canvas: div.querySelectorAll('canvas').length,
               gl: false, traces: 0, images: 0, bars: 0};
    const full = div._fullData || [];
    r.traces = full.length;
    const scene = div._fullLayout && div._fullLayout.scene && div._fullLayout.scene._scene;
    if (scene && scene.glplot) { r.gl = !!scene.glplot.gl; r.objects = scene.glplot.objects.length; }
    r.images = div.querySelectorAll('g.hm image').length;
    r.bars = div.querySelectorAll('g.bars path').length;
    out[div.id] = r;
  }
  return out;
})()
"""


# ----------------------------------------------------------------------------- tests without a browser
@pytest.fixture(scope="module")
def report_dir(demo_run, tmp_path_factory):
    from camplace.outputs.write import write_outputs

    out = tmp_path_factory.mktemp("report")
    r = demo_run
    t0 = time.perf_counter()
    write_outputs(out, r.scene.name, r.visibility, r.placement, r.problem.budget, r.metrics, r.timings_s,
                  scene=r.scene)
    return out, time.perf_counter() - t0


def _figs(text: str) -> dict:
    m = re.search(r"var figs = (\{.*?\});\n", text, re.S)
    assert m, "figure specs not found in the page"
    return json.loads(m.group(1).replace("<\\/", "</"))


def test_report_is_self_contained(report_dir):
    out, seconds = report_dir
    text = (out / "report.html").read_text()
    assert seconds < 10
    from camplace.outputs.report_html import plotly_js

    own = text.replace(plotly_js(), "")  # the page without the embedded plotly.js bundle
    assert len(own) < len(text) - 1_000_000  # the bundle is in the page
    # no URL outside the bundle (':' is not in base64, so the embedded JPEG views cannot fake one)
    assert "cdn.plot.ly" not in own and not re.search(r"https?:", own) and not re.search(r"<script[^>]+src=", text)
    assert "Plotly.newPlot" in text and len(text) < 10_000_000
    assert text.count("<script") == 2  # the plotly.js bundle and the figures


def test_report_figures_match_the_run(report_dir, demo_run):
    out, _ = report_dir
    figs = _figs((out / "report.html").read_text())
    heights = sorted({h for r in demo_run.scene.spec.targets if r.kind == "volume" for h in r.heights})
    assert set(figs) == {"view3d", "histogram", *(f"slice{k}" for k in range(len(heights)))}
    cov = demo_run.problem.coverage(demo_run.placement.selected)
    # one marker trace per coverage class; together they hold every target, classes right
    tr = [t for t in figs["view3d"]["data"] if t["name"].startswith("targets seen by")]
    assert len(tr) == 4
    assert sum(len(t["x"]) for t in tr) == len(cov)
    for c, t in enumerate(tr):
        assert all(min(d[0], 3) == c for d in t["customdata"])
        assert f"({int((np.minimum(cov, 3) == c).sum())})" in t["name"]
    # cameras: one labelled marker per selected camera
    cams = [t for t in figs["view3d"]["data"] if t["name"].startswith("cameras (")][0]
    placement = json.loads((out / "placement.json").read_text())
    assert cams["text"] == [str(c["candidate_id"]) for c in placement["cameras"]]
    # obstacles: 8 vertices per box
    mesh = [t for t in figs["view3d"]["data"] if t["type"] == "mesh3d"][0]
    assert len(mesh["x"]) == 8 * len(demo_run.scene.boxes)
    # histogram bars sum to the target count of each region
    metrics = json.loads((out / "metrics.json").read_text())
    for bar in figs["histogram"]["data"]:
        assert sum(bar["y"]) == metrics["regions"][bar["name"]]["targets"]
    # a slice holds the coverage of the volume targets at its height
    vol = ~demo_run.visibility.targets.is_surface
    z = demo_run.visibility.targets.positions[:, 2]
    hm = figs["slice0"]["data"][0]
    vals = [v for row in hm["customdata"] for v in row if v is not None]
    assert sorted(vals) == sorted(cov[vol & np.isclose(z, heights[0])].tolist())


def test_report_shows_camera_views(report_dir, demo_run):
    out, _ = report_dir
    text = (out / "report.html").read_text()
    n_views = text.count("<img src='data:image/jpeg;base64,")
    skipped = re.search(r"(\d+) more views not rendered", text)
    assert n_views >= 1 and n_views + (int(skipped.group(1)) if skipped else 0) == len(demo_run.placement.selected)
    for i in demo_run.placement.selected[:n_views]:
        assert f"alt='view of camera {i}'" in text


def test_report_pngs_and_exports_written(report_dir, demo_run):
    out, _ = report_dir
    heights = sorted({h for r in demo_run.scene.spec.targets if r.kind == "volume" for h in r.heights})
    for h in heights:
        assert (out / f"coverage_slice_z{h:.2f}m.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (out / "coverage_histogram.png").stat().st_size > 1000
    assert len(list((out / "opencv").glob("camera_*.yaml"))) == len(demo_run.placement.selected)
    assert (out / "colmap" / "images.txt").exists()


def test_report_without_scene_and_html_escaping(tmp_path, demo_run):
    """No Scene object (e.g. from visibility.npz only): the report still renders; names are escaped."""
    from dataclasses import replace

    from camplace.outputs.report_html import write_report

    r = demo_run
    t = replace(r.visibility.targets, region_names=("<b>walk</b>", "shelf</script>"))
    cov = r.problem.coverage(r.placement.selected)
    placement = {"scene": "x</script><script>alert(1)</script>", "solver": "file", "budget": 0, "status": "feasible",
                 "objective": 0.0, "bound": None, "cameras": []}
    metrics = r.metrics.to_dict()
    metrics["regions"] = {"<b>walk</b>": metrics["regions"]["walkable"]}
    paths = write_report(tmp_path, t, cov, placement, metrics, exports=False, figures=False)
    text = paths["report.html"].read_text()
    assert "<script>alert(1)" not in text and "<b>walk</b>" not in text.split("<script")[0]
    assert "</script><script>alert" not in text


# ----------------------------------------------------------------------------- the real browser
@pytest.mark.skipif(CHROMIUM is None, reason="Debian chromium is not installed (.ci/run installs it)")
def test_report_renders_in_headless_chromium(report_dir):
    out, _ = report_dir
    b = Browser()
    try:
        b.open((out / "report.html").resolve().as_uri())
        b.wait_for("document.body && (document.body.getAttribute('data-plots-ready') || "
                   "document.body.getAttribute('data-plots-error'))", timeout=90)
        assert b.evaluate("document.body.getAttribute('data-plots-error')") is None
        total = int(b.evaluate("document.body.getAttribute('data-plots-total')"))
        assert b.evaluate("document.body.getAttribute('data-plots-ready')") == str(total)
        time.sleep(0.5)
        plots = b.evaluate(PLOT_CHECK)
        assert len(plots) == total
        v = plots["view3d"]
        assert v["canvas"] >= 1 and v["gl"] and v["objects"] >= 6, v  # WebGL scene with the traces drawn
        for name, r in plots.items():
            assert r["svg"] and r["traces"] >= 1, (name, r)
            if name.startswith("slice"):
                assert r["images"] >= 1, (name, r)  # the heatmap image
            if name == "histogram":
                assert r["bars"] >= 1, r
        views = b.evaluate("Array.from(document.querySelectorAll('.views img')).map(i => i.complete && i.naturalWidth)")
        assert views and all(w == 240 for w in views), views  # every camera view decoded
        errors = b.console_errors()
        assert errors == [], errors
        remote = [u for u in b.requested_urls() if not u.startswith(("file:", "data:", "blob:", "about:"))]
        assert remote == [], remote  # works offline: nothing fetched from the network
    finally:
        b.close()


@pytest.mark.skipif(CHROMIUM is None, reason="Debian chromium is not installed (.ci/run installs it)")
def test_browser_harness_sees_errors_and_requests(tmp_path):
    """Negative control: the harness does catch console errors, exceptions and network use."""
    (tmp_path / "bad.html").write_text(
        "<html><body><script>console.error('boom'); fetch('http://example.invalid/x').catch(() => {});"
        "document.body.setAttribute('data-plots-ready', '0'); undefined_function();</script></body></html>")
    b = Browser()
    try:
        b.open((tmp_path / "bad.html").resolve().as_uri())
        b.wait_for("document.body && document.body.getAttribute('data-plots-ready')", timeout=60)
        time.sleep(0.5)
        b.evaluate("1")  # drain pending events
        errors = " | ".join(b.console_errors())
        assert "boom" in errors and "undefined_function" in errors
        assert any(u.startswith("http://example.invalid") for u in b.requested_urls())
    finally:
        b.close()


if __name__ == "__main__":  # python tests/test_report_html.py REPORT.html OUT.png
    src, dst = Path(sys.argv[1]), Path(sys.argv[2])
    br = Browser()
    try:
        br.open(src.resolve().as_uri())
        br.wait_for("document.body && document.body.getAttribute('data-plots-ready')", timeout=90)
        br.screenshot(dst)
        print("errors:", br.console_errors())
        from PIL import Image  # Pillow comes with matplotlib: 256-colour PNG keeps it small

        Image.open(dst).convert("RGB").quantize(256).save(dst, optimize=True)
    finally:
        br.close()
