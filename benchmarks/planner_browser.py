"""Browser-in-the-loop time per change of the planner (issue 20 benchmark).

Usage: python benchmarks/planner_browser.py [RUN_DIR | SCENE] [--changes 30] [--warmup 3]

Opens the planner (camplace.planner: session + app under uvicorn, in a thread) on a run
folder or a scene (default: the built-in standard-store, run first on the grid), loads
the page in headless Debian Chromium (Selenium, /usr/bin/chromium + /usr/bin/chromedriver)
and drags cameras on the plan with real mouse events (one mount spacing, then back).
Each change is timed in the page with performance.now(): from the PUT being sent to the
page having redrawn (DOM, metrics included) and to the next animation frame; the server's
own timing_ms.total is read from the answer. Prints median and p95 of each (ms) and one
JSON line. Goal: ≤ 200 ms per change on standard-store.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import socket
import statistics
import tempfile
import threading
import time
from pathlib import Path

TOKEN = "bench"


def pct(xs: list[float], q: float) -> float:
    """The q-quantile (0..1) of xs by linear interpolation."""
    s = sorted(xs)
    k = (len(s) - 1) * q
    lo, hi = int(k), min(int(k) + 1, len(s) - 1)
    return s[lo] + (s[hi] - s[lo]) * (k - lo)


def start_server(target: str, root: Path) -> tuple[str, object]:
    import uvicorn

    from camplace.planner.app import create_app
    from camplace.planner.opening import open_start
    from camplace.planner.session import Session

    t0 = time.perf_counter()
    session = Session(open_start(target, root=root))
    print(f"opened {target} in {time.perf_counter() - t0:.1f} s ({len(session.state()['cameras'])} cameras)")
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    srv = uvicorn.Server(uvicorn.Config(create_app(session, TOKEN, port=port), host="127.0.0.1", port=port,
                                        log_level="warning", lifespan="off"))
    threading.Thread(target=srv.run, daemon=True).start()
    while not srv.started:
        time.sleep(0.05)
    return f"http://127.0.0.1:{port}/?token={TOKEN}", srv


def browser():
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    opts = webdriver.ChromeOptions()
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--window-size=1400,900"):
        opts.add_argument(arg)
    opts.binary_location = "/usr/bin/chromium"
    drv = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=opts)
    drv.execute_cdp_cmd("Emulation.setDeviceMetricsOverride",
                        {"width": 1400, "height": 900, "deviceScaleFactor": 1, "mobile": False})
    return drv


def wait(drv, js: str, timeout: float = 60.0):
    """Poll ``return <js>`` in the page (Selenium's WebDriverWait) until it is truthy."""
    from selenium.webdriver.support.ui import WebDriverWait

    return WebDriverWait(drv, timeout, poll_frequency=0.01).until(lambda d: d.execute_script("return " + js),
                                                                 message=js)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("target", nargs="?", default="standard-store", help="run folder or scene")
    ap.add_argument("--changes", type=int, default=30)
    ap.add_argument("--warmup", type=int, default=3)
    a = ap.parse_args()
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By

    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, python {platform.python_version()}, "
          f"load {os.getloadavg()[0]:.2f}")
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(a.target).resolve() if Path(a.target).is_dir() else Path(tmp)
        url, srv = start_server(a.target, root)
        drv = browser()
        try:
            drv.get(url)
            wait(drv, "document.body.dataset.ready")
            px_per_m = drv.execute_script("return document.getElementById('plan').getScreenCTM().a")
            ids = drv.execute_script("return planner.S.state.cameras.filter(c => !c.locked && !c.existing).map(c => c.id)")
            rec, refused, k = [], 0, 0
            while len(rec) < a.changes + a.warmup and k < 4 * (a.changes + a.warmup):
                cid = ids[(k // 2) % len(ids)]
                step = px_per_m * (1.0 if k % 2 == 0 else -1.0)  # one mount spacing, then back
                k += 1
                n0 = drv.execute_script("return planner.perf.count")
                marker = drv.find_element(By.CSS_SELECTOR, f'#g-cameras .cam[data-id="{cid}"] .body')
                ActionChains(drv, duration=0).click_and_hold(marker).move_by_offset(step / 2, 0) \
                    .move_by_offset(step / 2, 0).release().perform()
                try:
                    wait(drv, f"planner.perf.count > {n0}", timeout=10)
                except TimeoutError:
                    refused += 1  # the mouse missed (no change was sent)
                    continue
                last = drv.execute_script("return planner.perf.last")
                err = drv.execute_script("return document.getElementById('message').classList.contains('error')")
                if err or not last.get("ok"):
                    refused += 1
                    drv.execute_script("document.getElementById('message').className = 'message'")
                    continue
                rec.append(last)
            rec = rec[a.warmup:]
        finally:
            drv.quit()
            srv.should_exit = True
    out = {"target": a.target, "changes": len(rec), "refused": refused}
    print(f"{len(rec)} changes timed ({refused} refused moves skipped, {a.warmup} warm-up changes dropped)")
    print("| measure | median ms | p95 ms | max ms |")
    print("|---|---|---|---|")
    for key, label in (("frame_ms", "page: PUT sent → next frame after redraw"),
                       ("dom_ms", "page: PUT sent → DOM redrawn"),
                       ("server_ms", "server: timing_ms.total")):
        xs = [float(r[key]) for r in rec if r.get(key) is not None]
        out[key] = {"median": round(statistics.median(xs), 1), "p95": round(pct(xs, 0.95), 1), "max": round(max(xs), 1)}
        print(f"| {label} | {out[key]['median']:.1f} | {out[key]['p95']:.1f} | {out[key]['max']:.1f} |")
    print(json.dumps(out))


if __name__ == "__main__":
    main()
