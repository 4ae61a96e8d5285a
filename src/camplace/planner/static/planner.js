/* camplace planner page: plan view, 3D view, metrics, camera list, optimise, save.
   Plain JS, no build step, no network beyond this page's own server (/api, /static). */
(function () {
  "use strict";

  const TOKEN = new URLSearchParams(location.search).get("token") || "";
  const SVGNS = "http://www.w3.org/2000/svg";
  const TYPE_COLOURS = ["#2563eb", "#d97706", "#059669", "#db2777", "#7c3aed", "#0891b2", "#65a30d", "#dc2626"];
  const $ = (id) => document.getElementById(id);

  const S = {
    scene: null, state: null, prev: null, sel: null, adding: false, optimizing: false,
    es: null, drag: null, colour: {}, gamma: 3, covRects: [], chain: Promise.resolve(),
    view: "plan", orbit: { az: -0.9, el: 0.75, zoom: 1 },
  };
  /* Change timing, read by tests and benchmarks: ms from the request being sent to the
     page having redrawn (dom_ms) and to the next animation frame (frame_ms). */
  const perf = { count: 0, last: null, changes: [] };
  window.planner = { perf, S, select: (id) => select(id) };

  /* ---------- messages and API ---------- */
  let msgTimer = null;
  function message(text, kind) {
    const el = $("message");
    el.textContent = text;
    el.className = "message" + (kind ? " " + kind : "");
    if (msgTimer) clearTimeout(msgTimer);
    if (kind === "ok") msgTimer = setTimeout(() => { el.className = "message"; }, 6000);
  }
  const error = (text) => message(text, "error");

  async function api(method, path, body) {
    const headers = { "Accept": "application/json" };
    if (TOKEN) headers["X-Camplace-Token"] = TOKEN;
    if (body !== undefined) headers["Content-Type"] = "application/json";
    let res;
    try {
      res = await fetch(path, { method, headers, body: body === undefined ? undefined : JSON.stringify(body), credentials: "same-origin" });
    } catch (e) {
      error("cannot reach the planner server (" + method + " " + path + "): is camplace serve still running?");
      return null;
    }
    let data = null;
    try { data = await res.json(); } catch (e) { data = null; }
    if (!res.ok) {
      const what = data && data.error ? data.error : "HTTP " + res.status;
      const field = data && data.field ? " [" + data.field + "]" : "";
      error(method + " " + path.split("?")[0] + ": " + what + field);
      return null;
    }
    return data;
  }

  /* A change: one mutating call, serialised, timed, then the state redrawn. */
  function change(method, path, body) {
    S.chain = S.chain.then(async () => {
      const t0 = performance.now();
      const st = await api(method, path, body);
      if (!st) {
        render();
        perf.last = { method, path: path.split("?")[0], ok: false, dom_ms: performance.now() - t0, frame_ms: null, server_ms: null };
        perf.count += 1;
        return null;
      }
      applyState(st);
      const t1 = performance.now();
      const rec = { method, path: path.split("?")[0], ok: true, dom_ms: t1 - t0, frame_ms: null, server_ms: st.timing_ms ? st.timing_ms.total : null };
      await new Promise((r) => requestAnimationFrame(() => { rec.frame_ms = performance.now() - t0; r(); }));
      perf.last = rec; perf.changes.push(rec); perf.count += 1;
      showTiming(st, rec);
      return st;
    });
    return S.chain;
  }

  function showTiming(st, rec) {
    const t = st.timing_ms || {};
    const f = (v) => (typeof v === "number" ? v.toFixed(0) : "–");
    let s = "";
    if (rec) s += "last change " + f(rec.frame_ms) + " ms · ";
    s += "server " + f(t.total) + " ms (raycast " + f(t.raycast) + (t.viewshed != null ? ", viewshed " + f(t.viewshed) : "") + ", metrics " + f(t.metrics) + ")";
    $("timing").textContent = s;
  }

  /* ---------- helpers ---------- */
  const el = (tag, attrs, parent) => {
    const e = document.createElementNS(SVGNS, tag);
    for (const k in attrs) e.setAttribute(k, attrs[k]);
    if (parent) parent.appendChild(e);
    return e;
  };
  const pts = (poly) => poly.map((p) => p[0].toFixed(3) + "," + (-p[1]).toFixed(3)).join(" ");
  const cam = (id) => (S.state && id !== null && id !== undefined ? S.state.cameras.find((c) => String(c.id) === String(id)) || null : null);
  const fixed = (c) => !!(c && (c.locked || c.existing));
  const typeOf = (name) => (S.scene.camera_types || []).find((t) => t.name === name);
  const colourOf = (name) => S.colour[name] || "#475569";
  const fmt = (v, d) => (typeof v === "number" && isFinite(v) ? v.toFixed(d) : "–");
  const wrapDeg = (a) => { a = ((a + 180) % 360 + 360) % 360 - 180; return a; };

  function covColour(v, need) {
    const g = need || S.gamma;
    if (v <= 0) return "#ef4444";
    if (v >= g) return "#22c55e";
    const t = v / g; // amber → yellow-green
    const r = Math.round(245 - 120 * t), gg = Math.round(158 + 40 * t), b = Math.round(11 + 40 * t);
    return "rgb(" + r + "," + gg + "," + b + ")";
  }

  const gammaAt = (i) => (S.scene.targets_gamma ? S.scene.targets_gamma[i] : 0) || S.gamma;

  function worldFromEvent(e) {
    const svg = $("plan");
    const pt = svg.createSVGPoint();
    pt.x = e.clientX; pt.y = e.clientY;
    const p = pt.matrixTransform(svg.getScreenCTM().inverse());
    return [p.x, -p.y];
  }

  /* ---------- scene (static) ---------- */
  function drawScene() {
    const sc = S.scene;
    const [lo, hi] = sc.bounds;
    const m = 0.6;
    const svg = $("plan");
    svg.setAttribute("viewBox", [lo[0] - m, -hi[1] - m, hi[0] - lo[0] + 2 * m, hi[1] - lo[1] + 2 * m].join(" "));
    const defs = el("defs", {}, svg);
    const pat = el("pattern", { id: "hatch", width: 0.25, height: 0.25, patternUnits: "userSpaceOnUse", patternTransform: "rotate(45)" }, defs);
    el("rect", { width: 0.25, height: 0.25, fill: "#7c3aed", "fill-opacity": 0.06 }, pat);
    el("line", { x1: 0, y1: 0, x2: 0, y2: 0.25, stroke: "#7c3aed", "stroke-width": 0.04, "stroke-opacity": 0.5 }, pat);
    svg.insertBefore(defs, svg.firstChild);

    const floors = (sc.storeys || []).map((f) => f.name);
    if (floors.length) {  // a building: one footprint per storey, the floor selector shows one storey
      for (const f of sc.storeys) el("polygon", { points: pts(f.footprint), class: "footprint", "data-storey": f.name }, $("g-footprint"));
      for (const id of ["floor", "ed-storey"]) {
        const fs = $(id);
        fs.innerHTML = "";
        for (const n of floors) { const o = document.createElement("option"); o.value = o.textContent = n; fs.appendChild(o); }
      }
      S.floor = floors[0];
      $("floor-pick").classList.remove("hidden");
      $("ed-storey-pick").classList.remove("hidden");
    } else el("polygon", { points: pts(sc.footprint), class: "footprint" }, $("g-footprint"));
    // scale ticks along the bottom edge, every metre
    const gx = $("g-footprint");
    for (let x = Math.ceil(lo[0]); x <= hi[0] + 1e-9; x += (hi[0] - lo[0] > 30 ? 5 : 1)) {
      const t = el("text", { x: x, y: -lo[1] + 0.42, class: "axis", "text-anchor": "middle" }, gx);
      t.textContent = x + (x === Math.ceil(lo[0]) ? " m" : "");
    }
    const cell = sc.target_cell_m || 0.25;
    const gc = $("g-coverage");
    S.covRects = (sc.targets_xy || []).map((p, i) => el("rect", Object.assign({
      x: (p[0] - cell / 2).toFixed(3), y: (-p[1] - cell / 2).toFixed(3), width: cell, height: cell,
      fill: "#ef4444", "fill-opacity": 0.5,
    }, floors.length ? { "data-storey": sc.targets_storey[i] } : {}), gc));
    const onFloor = (name) => {  // 'Storey/name' of a building's obstacles and zones
      const k = String(name).indexOf("/");
      return floors.length && k > 0 && floors.includes(name.slice(0, k)) ? { "data-storey": name.slice(0, k) } : {};
    };
    for (const z of sc.zones || []) {
      el("polygon", { points: pts(z.polygon), class: "zone" }, $("g-zones"));
      const b = bboxOf(z.polygon);
      const t = el("text", { x: b[0] + 0.12, y: -b[3] + 0.32, class: "zone-label" }, $("g-zones"));
      t.textContent = z.name;
    }
    for (const z of sc.privacy || []) {
      el("polygon", { points: pts(z.polygon), class: "privacy" }, $("g-zones"));
      label(z.polygon, z.name + " (private)", "zone-label privacy-label", $("g-zones"));
    }
    for (const r of sc.mount_rules || []) {
      el("polygon", { points: pts(r.polygon), class: "mount-rule " + (r.kind === "forbid" ? "forbid" : "allow") }, $("g-zones"));
      label(r.polygon, (r.kind === "forbid" ? "no mounts" : "mounts") + (r.name ? ": " + r.name : ""), "zone-label rule-label", $("g-zones"), -0.3);
    }
    for (const o of sc.obstacles || []) {
      const tall = (o.zmax || 0) >= 1.5;
      el("polygon", Object.assign({ points: pts(o.polygon), class: "obstacle" + (tall ? "" : " low") }, onFloor(o.name)), $("g-obstacles"));
      const t = label(o.polygon, o.name, "label", $("g-obstacles"));
      if (onFloor(o.name)["data-storey"]) t.setAttribute("data-storey", onFloor(o.name)["data-storey"]);
    }
    (sc.mounts || []).forEach((mt, i) => el("circle", Object.assign({ cx: mt[0], cy: -mt[1], r: 0.04, class: "mount" },
      floors.length ? { "data-storey": sc.mounts_storey[i] } : {}), $("g-mounts")));
    applyFloor();
    $("g-mounts").classList.add("hidden");

    (sc.camera_types || []).forEach((t, i) => { S.colour[t.name] = TYPE_COLOURS[i % TYPE_COLOURS.length]; });
    S.gamma = sc.coverage_required || 3;
    const sel = $("ed-type");
    sel.innerHTML = "";
    for (const t of sc.camera_types || []) {
      const o = document.createElement("option");
      o.value = t.name; o.textContent = t.name + " (" + fmt(t.hfov_deg, 0) + "°, " + fmt(t.max_range_m, 0) + " m)";
      sel.appendChild(o);
    }
    const solvers = sc.solvers && sc.solvers.length ? sc.solvers : ["greedy", "greedy-ls", "tabu", "mip"];
    const ss = $("opt-solver");
    ss.innerHTML = "";
    for (const n of solvers) { const o = document.createElement("option"); o.value = o.textContent = n; ss.appendChild(o); }
    $("opt-budget").value = sc.budget;
    $("scene-name").textContent = sc.name;
    document.title = sc.name + " · camplace planner";
    drawLegend();
  }

  /* A building: show only the selected floor's footprint, targets, obstacles, mounts and cameras. */
  function applyFloor() {
    if (!S.floor) return;
    for (const e of document.querySelectorAll("#plan [data-storey]")) {
      e.style.display = e.getAttribute("data-storey") === S.floor ? "" : "none";
    }
  }

  function setFloor(name) {
    S.floor = name;
    $("floor").value = name;
    applyFloor();
    if (S.view === "3d") draw3d();
  }

  function drawLegend() {
    const lg = $("legend");
    lg.innerHTML = "";
    const item = (c, t) => { const s = document.createElement("span"); s.innerHTML = '<i style="background:' + c + '"></i>'; s.appendChild(document.createTextNode(t)); lg.appendChild(s); };
    for (const t of S.scene.camera_types || []) item(colourOf(t.name), t.name);
    item("#ef4444", "unseen");
    item(covColour(Math.max(1, S.gamma - 1)), "partly");
    item("#22c55e", S.scene.targets_gamma ? "≥ Γ views" : "≥ " + S.gamma + " views");
  }

  /* A polygon's name at its centre: turned along a tall narrow shape, left out when it fits neither way. */
  function label(poly, text, cls, group, dy) {
    const c = centroid(poly), b = bboxOf(poly);
    const w = b[1] - b[0], h = b[3] - b[2], len = text.length * 0.15;
    const t = el("text", { x: c[0], y: -c[1] + (dy || 0.09), class: cls, "text-anchor": "middle" }, group);
    t.textContent = text;
    if (len > w && h > w && len <= h * 1.05) t.setAttribute("transform", "rotate(-90 " + c[0] + " " + (-c[1]) + ")");
    else if (len > w * 1.05 && (h < 0.3 || len > h * 1.05)) t.remove();
    return t;
  }

  function centroid(poly) {
    let x = 0, y = 0;
    for (const p of poly) { x += p[0]; y += p[1]; }
    return [x / poly.length, y / poly.length];
  }
  function bboxOf(poly) {
    const xs = poly.map((p) => p[0]), ys = poly.map((p) => p[1]);
    return [Math.min(...xs), Math.max(...xs), Math.min(...ys), Math.max(...ys)];
  }

  /* ---------- state (dynamic) ---------- */
  function applyState(st) {
    if (S.state) S.prev = S.state;
    S.state = st;
    if (S.sel !== null && !cam(S.sel)) S.sel = null;
    if (!S.scene.coverage_required && st.coverage_floor && st.coverage_floor.length) {
      const mx = st.coverage_floor.reduce((a, b) => Math.max(a, b), 0);
      if (mx > S.gamma) { S.gamma = mx; drawLegend(); }
    }
    render();
  }

  function render() {
    const st = S.state;
    if (!st) return;
    drawCoverage(st);
    drawCameras(st);
    drawMetrics(st);
    drawZones(st);
    drawList(st);
    drawEditor();
    $("btn-undo").disabled = !st.can_undo || S.optimizing;
    $("btn-redo").disabled = !st.can_redo || S.optimizing;
    if (S.view === "3d") draw3d();
  }

  function drawCoverage(st) {
    const cov = st.coverage_floor || [];
    const old = S.prev && S.prev.coverage_floor;
    for (let i = 0; i < S.covRects.length; i++) {
      const v = cov[i] || 0;
      if (old && old === cov) break;
      if (!old || old[i] !== v || !S.covDrawn) S.covRects[i].setAttribute("fill", covColour(v, gammaAt(i)));
    }
    S.covDrawn = true;
  }

  /* Cameras and viewsheds, redrawn only where a camera changed (or was previewed). */
  function drawCameras(st) {
    const gv = $("g-viewsheds"), gc = $("g-cameras");
    const els = S.camEls || (S.camEls = new Map());
    const seen = new Set();
    let selEls = null;
    for (const c of st.cameras) {
      const key = String(c.id);
      const isSel = key === String(S.sel);
      const vs = c.viewshed || [];
      const sig = [c.position.join(","), c.yaw_deg, c.pitch_deg, c.roll_deg, c.camera, c.locked, c.existing, isSel,
        vs.length, vs.length ? vs[0].join(",") + vs[vs.length >> 1].join(",") : ""].join("|");
      seen.add(key);
      let e = els.get(key);
      if (e && e.sig === sig && S.previewed !== key) { if (isSel) selEls = e; continue; }
      if (e) { if (e.vs) e.vs.remove(); e.g.remove(); }
      e = { sig, vs: null, g: null };
      const col = colourOf(c.camera);
      const floor = c.storey ? { "data-storey": c.storey } : {};
      if (vs.length > 2) e.vs = el("polygon", Object.assign({ points: pts(vs), class: "viewshed" + (isSel ? " sel" : ""), fill: col, stroke: col, "data-id": key }, floor), gv);
      const g = el("g", Object.assign({ class: "cam" + (isSel ? " sel" : "") + (c.locked ? " locked" : ""), "data-id": key,
        transform: "translate(" + c.position[0].toFixed(3) + "," + (-c.position[1]).toFixed(3) + ")" }, floor), gc);
      const yaw = c.yaw_deg * Math.PI / 180;
      el("line", { x1: 0, y1: 0, x2: (0.5 * Math.cos(yaw)).toFixed(3), y2: (-0.5 * Math.sin(yaw)).toFixed(3), class: "dir", stroke: col }, g);
      if (isSel) el("circle", { r: 0.3, class: "ring" }, g);
      if (fixed(c)) el("rect", { x: -0.16, y: -0.16, width: 0.32, height: 0.32, class: "body", fill: col }, g);
      else el("circle", { r: 0.17, class: "body", fill: col }, g);
      el("text", { x: 0.2, y: 0.36, class: "cam-label" }, g).textContent = key;
      e.g = g;
      els.set(key, e);
      if (isSel) selEls = e;
    }
    for (const [key, e] of els) {
      if (!seen.has(key)) { if (e.vs) e.vs.remove(); e.g.remove(); els.delete(key); }
    }
    if (selEls) { if (selEls.vs) gv.appendChild(selEls.vs); gc.appendChild(selEls.g); }  // selected on top
    S.previewed = null;
    applyFloor();
    drawHandle();
  }

  function drawHandle() {
    const gh = $("g-handle");
    gh.textContent = "";
    const c = cam(S.sel);
    if (!c || fixed(c)) return;
    const yaw = c.yaw_deg * Math.PI / 180, R = 1.1;
    const x = c.position[0], y = c.position[1];
    const g = el("g", { class: "handle" }, gh);
    el("line", { x1: x, y1: -y, x2: x + R * Math.cos(yaw), y2: -(y + R * Math.sin(yaw)) }, g);
    el("circle", { cx: x + R * Math.cos(yaw), cy: -(y + R * Math.sin(yaw)), r: 0.13, class: "yaw-handle" }, g);
  }

  const METRICS = [
    ["coverage gap", (m) => m.coverage_gap, 4, -1, "coverage gap (eq. 8): 0 = every target seen Γ times"],
    ["shortfall cost", (m) => m.cost, 0, -1, "sum of w·(Γ − views)² over targets (the solvers' objective)"],
    ["cameras", (m, st) => st.cameras.length, 0, 0, "cameras placed / budget"],
    ["well triangulated", (m) => m.well_triangulated_pct, 1, 1, "% of targets seen by two cameras at a usable angle"],
    ["non-triangulatable", (m) => m.non_triangulatable_pct, 1, -1, "% of targets seen by fewer than two cameras"],
    ["unseen targets", (m) => (m.coverage_histogram ? m.coverage_histogram["0"] || 0 : undefined), 0, -1, "targets no camera sees"],
    ["equipment cost", (m, st) => st.cameras.reduce((a, c) => a + ((typeOf(c.camera) || {}).cost || 0), 0), 0, -1, "sum of the camera types' cost"],
    ["locked / existing", (m, st) => st.cameras.filter((c) => c.locked || c.existing).length, 0, 0, "locked and existing cameras stay when optimising"],
    ["version", (m, st) => st.version, 0, 0, "state version (one per change)"],
  ];

  function drawMetrics(st) {
    const box = $("metrics");
    if (!box.children.length) {
      for (const [k, , , , tip] of METRICS) {
        const d = document.createElement("div");
        d.className = "metric"; d.title = tip;
        d.innerHTML = '<div class="k"></div><div class="v"></div><div class="d"></div>';
        d.querySelector(".k").textContent = k;
        box.appendChild(d);
      }
    }
    const m = st.metrics || {}, pm = S.prev ? S.prev.metrics || {} : null;
    METRICS.forEach(([k, f, dig, sense], i) => {
      const node = box.children[i];
      const v = f(m, st);
      let txt = fmt(v, dig);
      if (k === "cameras") txt += " / " + (st.budget != null ? st.budget : S.scene.budget != null ? S.scene.budget : "–");
      if (k.endsWith("triangulated") || k === "non-triangulatable") txt += " %";
      node.querySelector(".v").textContent = txt;
      node.dataset.metric = k.replace(/ /g, "-");
      const dn = node.querySelector(".d");
      dn.textContent = ""; dn.className = "d";
      if (pm && sense !== 0) {
        const pv = f(pm, S.prev);
        if (typeof v === "number" && typeof pv === "number" && Math.abs(v - pv) >= Math.pow(10, -dig) / 2) {
          const dv = v - pv;
          dn.textContent = (dv > 0 ? "▲ +" : "▼ ") + dv.toFixed(dig);
          dn.className = "d " + ((dv * sense) > 0 ? "better" : "worse");
        }
      }
    });
  }

  const ZONE_COLS = [
    ["coverage", "covered %", 1, 100], ["targets", "targets", 0], ["gap", "gap", 4], ["coverage_gap", "gap", 4],
    ["cost", "cost", 0], ["well_triangulated_pct", "well tri. %", 1], ["non_triangulatable_pct", "non-tri. %", 1],
  ];
  function drawZones(st) {
    let rows = st.zones && st.zones.length ? st.zones : null;
    if (!rows && st.metrics && st.metrics.regions) rows = Object.entries(st.metrics.regions).map(([name, r]) => Object.assign({ name }, r));
    const t = $("zones");
    rows = rows || [];
    const cols = [];
    for (const col of ZONE_COLS) {
      if (col[0] === "coverage_gap" && cols.some((c) => c[1] === "gap")) continue;
      if (rows.some((r) => typeof r[col[0]] === "number")) cols.push(col);
    }
    t.querySelector("thead").innerHTML = "<tr><th>zone / region</th>" + cols.map((c) => '<th class="num">' + c[1] + "</th>").join("") + "</tr>";
    const tb = t.querySelector("tbody");
    tb.innerHTML = "";
    for (const r of rows) {
      const tr = document.createElement("tr");
      const td = document.createElement("td"); td.textContent = r.name; tr.appendChild(td);
      for (const [key, , dig, mul] of cols) { const c = document.createElement("td"); c.className = "num"; c.textContent = fmt(typeof r[key] === "number" ? r[key] * (mul || 1) : r[key], dig); tr.appendChild(c); }
      tb.appendChild(tr);
    }
  }

  function drawList(st) {
    const tb = $("cam-list").querySelector("tbody");
    tb.innerHTML = "";
    $("cam-count").textContent = "(" + st.cameras.length + ")";
    for (const c of st.cameras) {
      const tr = document.createElement("tr");
      tr.dataset.id = c.id;
      if (String(c.id) === String(S.sel)) tr.className = "sel";
      tr.innerHTML = '<td><span class="swatch"></span></td><td></td><td><input type="checkbox" class="lock"></td>' +
        '<td class="num"></td><td class="num"></td><td class="num"></td>';
      const tds = tr.children;
      tds[0].querySelector(".swatch").style.background = colourOf(c.camera);
      tds[0].appendChild(document.createTextNode(String(c.id)));
      tds[1].textContent = c.camera + (c.existing ? " (site)" : "");
      const lk = tds[2].querySelector("input");
      lk.checked = !!c.locked || !!c.existing;
      lk.disabled = !!c.existing || S.optimizing;
      lk.title = c.existing ? "an existing camera: always kept" : c.locked ? "locked: the optimiser keeps it" : "unlocked";
      lk.addEventListener("click", (e) => { e.stopPropagation(); change("PUT", "/api/cameras/" + c.id, { locked: lk.checked }); });
      tds[3].textContent = fmt(c.yaw_deg, 0);
      tds[4].textContent = fmt(c.pitch_deg, 0);
      tds[5].textContent = fmt(c.position[0], 2) + ", " + fmt(c.position[1], 2);
      tr.addEventListener("click", () => select(c.id));
      tb.appendChild(tr);
    }
  }

  function drawEditor() {
    const c = cam(S.sel);
    $("editor").classList.toggle("disabled", !c || S.optimizing);
    $("sel-id").textContent = c ? String(c.id) : "— click a camera";
    if (!c) { $("ed-pos").textContent = ""; return; }
    $("ed-type").value = c.camera;
    if (c.storey) { $("ed-storey").value = c.storey; $("ed-storey").disabled = fixed(c); }
    $("ed-locked").checked = !!c.locked || !!c.existing;
    $("ed-locked").disabled = !!c.existing;
    $("btn-delete").disabled = fixed(c);
    for (const [k, key] of [["yaw", "yaw_deg"], ["pitch", "pitch_deg"], ["roll", "roll_deg"]]) {
      const inp = $("ed-" + k);
      if (document.activeElement !== inp || !S.sliding) inp.value = Math.round(k === "yaw" ? wrapDeg(c[key] || 0) : c[key] || 0);
      inp.disabled = fixed(c);
      $("ed-" + k + "-v").textContent = fmt(c[key] || 0, 1) + "°";
    }
    $("ed-type").disabled = fixed(c);
    $("ed-pos").textContent = "at " + c.position.map((v) => fmt(v, 2)).join(", ") + " m" +
      (c.candidate_id != null ? " · cand. " + c.candidate_id : " · off the grid") +
      (typeof c.targets_seen === "number" ? " · sees " + c.targets_seen + " targets" : "") +
      (c.existing ? " · existing camera" : c.locked ? " · locked (unlock to edit)" : "");
  }

  function select(id) {
    const c = cam(id);
    S.sel = c ? c.id : null;
    render();
    const row = document.querySelector('#cam-list tr[data-id="' + String(id) + '"]');
    const wrap = document.querySelector("#list-panel .list-wrap");
    if (row && wrap) {
      const top = row.offsetTop - 24, bottom = row.offsetTop + row.offsetHeight;
      if (top < wrap.scrollTop) wrap.scrollTop = top;
      else if (bottom > wrap.scrollTop + wrap.clientHeight) wrap.scrollTop = bottom - wrap.clientHeight;
    }
  }

  /* ---------- plan interactions ---------- */
  function setAdding(on) {
    S.adding = on;
    $("btn-add").classList.toggle("active", on);
    $("plan").classList.toggle("adding", on);
    $("mode-hint").textContent = on ? "click on the plan to place a camera (Esc cancels)" : "";
  }

  function onPointerDown(e) {
    if (e.button !== 0 || !S.state || S.view !== "plan") return;
    const svg = $("plan");
    const w = worldFromEvent(e);
    if (e.target.classList && e.target.classList.contains("yaw-handle")) {
      const c = cam(S.sel);
      S.drag = { kind: "yaw", id: c.id, start: w, moved: true, c };
    } else {
      const g = e.target.closest ? e.target.closest(".cam") : null;
      if (g) {
        const c = cam(g.getAttribute("data-id"));
        if (c) S.drag = { kind: "move", id: c.id, start: w, sx: e.clientX, sy: e.clientY, moved: false, c, g };
      } else {
        S.drag = { kind: "none", start: w, sx: e.clientX, sy: e.clientY };
      }
    }
    try { svg.setPointerCapture(e.pointerId); } catch (err) { /* synthetic events */ }
    e.preventDefault();
  }

  function onPointerMove(e) {
    const d = S.drag;
    if (!d) return;
    const w = worldFromEvent(e);
    if (d.kind === "move") {
      if (!d.moved && Math.hypot(e.clientX - d.sx, e.clientY - d.sy) < 3) return;
      if (fixed(d.c)) { if (!d.moved) message("camera " + d.id + (d.c.existing ? " is an existing camera: it stays where it is" : " is locked: unlock it to move it")); d.moved = true; d.blocked = true; return; }
      if (!d.moved && d.id !== S.sel) { S.sel = d.id; render(); d.g = document.querySelector('#g-cameras .cam[data-id="' + d.id + '"]'); }
      d.moved = true;
      const dx = w[0] - d.start[0], dy = w[1] - d.start[1];
      d.to = [d.c.position[0] + dx, d.c.position[1] + dy];
      if (d.g) d.g.setAttribute("transform", "translate(" + d.to[0] + "," + (-d.to[1]) + ")");
      S.previewed = String(d.id);
      const vs = document.querySelector('#g-viewsheds polygon[data-id="' + d.id + '"]');
      if (vs) vs.setAttribute("transform", "translate(" + dx + "," + (-dy) + ")");
      $("g-handle").textContent = "";
    } else if (d.kind === "yaw") {
      const c = d.c;
      const yaw = Math.atan2(w[1] - c.position[1], w[0] - c.position[0]) * 180 / Math.PI;
      d.yaw = yaw;
      previewYaw(c, yaw);
    }
  }

  function previewYaw(c, yaw) {
    S.previewed = String(c.id);
    const g = document.querySelector('#g-cameras .cam[data-id="' + c.id + '"] line.dir');
    const r = yaw * Math.PI / 180;
    if (g) { g.setAttribute("x2", 0.5 * Math.cos(r)); g.setAttribute("y2", -0.5 * Math.sin(r)); }
    const vs = document.querySelector('#g-viewsheds polygon[data-id="' + c.id + '"]');
    if (vs) vs.setAttribute("transform", "rotate(" + (-(yaw - c.yaw_deg)) + " " + c.position[0] + " " + (-c.position[1]) + ")");
    const h = $("g-handle").querySelector("g");
    if (h) {
      const x = c.position[0] + 1.1 * Math.cos(r), y = c.position[1] + 1.1 * Math.sin(r);
      h.querySelector("line").setAttribute("x2", x); h.querySelector("line").setAttribute("y2", -y);
      h.querySelector("circle").setAttribute("cx", x); h.querySelector("circle").setAttribute("cy", -y);
    }
    $("ed-yaw-v").textContent = fmt(yaw, 1) + "°";
  }

  function onPointerUp(e) {
    const d = S.drag;
    S.drag = null;
    if (!d) return;
    const w = worldFromEvent(e);
    if (d.kind === "move") {
      if (!d.moved) { select(d.id); return; }
      if (d.blocked || !d.to) { render(); return; }
      const z = d.c.position[2];
      change("PUT", "/api/cameras/" + d.id, { position: [d.to[0], d.to[1], z], snap: true });
    } else if (d.kind === "yaw") {
      if (d.yaw === undefined) { render(); return; }
      change("PUT", "/api/cameras/" + d.id, { yaw_deg: Number(d.yaw.toFixed(2)) });
    } else if (d.kind === "none") {
      if (Math.hypot(e.clientX - d.sx, e.clientY - d.sy) > 3) return;
      if (S.adding) {
        setAdding(false);
        const t = $("ed-type").value || ((S.scene.camera_types || [])[0] || {}).name;
        const body = { position: [w[0], w[1]], yaw_deg: 0, pitch_deg: 45 };
        if (t) body.camera = t;
        if (S.floor) body.storey = S.floor;
        const before = new Set(S.state.cameras.map((c) => String(c.id)));
        change("POST", "/api/cameras", body).then((st) => {
          const added = st ? st.cameras.find((c) => !before.has(String(c.id))) : null;
          if (added) { select(added.id); message("added camera " + added.id + " (snapped to the nearest mount)", "ok"); }
        });
      } else if (S.sel !== null) {
        S.sel = null; render();
      }
    }
  }

  /* ---------- editor, toolbar, keyboard ---------- */
  function putSel(body) {
    const c = cam(S.sel);
    if (c) change("PUT", "/api/cameras/" + c.id, body);
  }
  function undo() { if (S.state && S.state.can_undo && !S.optimizing) change("POST", "/api/undo", {}); }
  function redo() { if (S.state && S.state.can_redo && !S.optimizing) change("POST", "/api/redo", {}); }
  function del() {
    const c = cam(S.sel);
    if (!c) return;
    change("DELETE", "/api/cameras/" + c.id).then((st) => { if (st) message("deleted camera " + c.id + " (Ctrl-Z brings it back)"); });
  }

  function wire() {
    const svg = $("plan");
    svg.addEventListener("pointerdown", onPointerDown);
    svg.addEventListener("pointermove", onPointerMove);
    svg.addEventListener("pointerup", onPointerUp);
    svg.addEventListener("pointercancel", () => { S.drag = null; render(); });
    $("btn-undo").addEventListener("click", undo);
    $("btn-redo").addEventListener("click", redo);
    $("btn-add").addEventListener("click", () => setAdding(!S.adding));
    $("btn-delete").addEventListener("click", del);
    $("btn-save").addEventListener("click", save);
    $("btn-opt").addEventListener("click", optimise);
    $("btn-cancel").addEventListener("click", () => api("POST", "/api/optimize/cancel", {}).then((r) => { if (r) $("opt-status").textContent = "cancelling: keeping the best placement so far…"; }));
    $("ed-type").addEventListener("change", (e) => putSel({ camera: e.target.value }));
    $("ed-locked").addEventListener("change", (e) => putSel({ locked: e.target.checked }));
    $("floor").addEventListener("change", (e) => setFloor(e.target.value));
    $("ed-storey").addEventListener("change", (e) => { setFloor(e.target.value); putSel({ storey: e.target.value }); });
    for (const [k, key] of [["yaw", "yaw_deg"], ["pitch", "pitch_deg"], ["roll", "roll_deg"]]) {
      const inp = $("ed-" + k);
      inp.addEventListener("input", () => {
        S.sliding = true;
        $("ed-" + k + "-v").textContent = Number(inp.value).toFixed(1) + "°";
        const c = cam(S.sel);
        if (c && k === "yaw") previewYaw(c, Number(inp.value));
      });
      inp.addEventListener("change", () => { S.sliding = false; const b = {}; b[key] = Number(inp.value); putSel(b); });
    }
    for (const [id, g] of [["show-coverage", "g-coverage"], ["show-viewsheds", "g-viewsheds"], ["show-mounts", "g-mounts"]]) {
      $(id).addEventListener("change", (e) => { $(g).classList.toggle("hidden", !e.target.checked); });
    }
    $("tab-plan").addEventListener("click", () => setView("plan"));
    $("tab-3d").addEventListener("click", () => setView("3d"));
    document.addEventListener("keydown", (e) => {
      const typing = e.target && (e.target.tagName === "INPUT" && e.target.type !== "range" && e.target.type !== "checkbox" || e.target.tagName === "SELECT");
      const k = e.key.toLowerCase();
      if ((e.ctrlKey || e.metaKey) && k === "z" && !e.shiftKey) { if (!typing) { e.preventDefault(); undo(); } }
      else if ((e.ctrlKey || e.metaKey) && (k === "y" || (k === "z" && e.shiftKey))) { if (!typing) { e.preventDefault(); redo(); } }
      else if ((k === "delete" || k === "backspace") && !typing && S.sel !== null) { e.preventDefault(); del(); }
      else if (k === "escape") { if (S.adding) setAdding(false); else if (S.sel !== null) { S.sel = null; render(); } }
    });
    window.addEventListener("resize", () => { if (S.view === "3d") draw3d(); });
    wire3d();
  }

  /* ---------- optimise (SSE) and save ---------- */
  function setOptimizing(on) {
    S.optimizing = on;
    $("btn-opt").disabled = on;
    $("btn-cancel").disabled = !on;
    $("btn-add").disabled = on;
    render();
  }

  async function optimise() {
    if (S.optimizing) return;
    const body = { solver: $("opt-solver").value, time_limit_s: Number($("opt-time").value) || 10 };
    const b = $("opt-budget").value;
    if (b !== "") body.budget = Number(b);
    $("opt-bar").style.width = "0%";
    $("opt-status").textContent = "starting " + body.solver + "…";
    const r = await api("POST", "/api/optimize", body);
    if (!r) { $("opt-status").textContent = "not started"; return; }
    follow(body.solver);
  }

  /* Follow the running job's progress stream (it replays the job's events from its start). */
  function follow(solver) {
    setOptimizing(true);
    const t0 = performance.now();
    const es = new EventSource("/api/optimize/events" + (TOKEN ? "?token=" + encodeURIComponent(TOKEN) : ""));
    S.es = es;
    const finish = () => { es.close(); S.es = null; setOptimizing(false); };
    es.addEventListener("progress", (ev) => {
      let p; try { p = JSON.parse(ev.data); } catch (e) { return; }
      const frac = p.total ? Math.min(1, p.done / p.total) : 0;
      $("opt-bar").style.width = (100 * frac).toFixed(1) + "%";
      let s = (p.stage || "solve") + " " + (p.done != null ? p.done : "") + (p.total ? "/" + p.total : "");
      if (p.objective != null) s += " · objective " + fmt(p.objective, 0);
      if (p.bound != null) s += " · bound " + fmt(p.bound, 0);
      $("opt-status").textContent = s;
    });
    es.addEventListener("done", (ev) => {
      finish();
      let st = null; try { st = JSON.parse(ev.data); } catch (e) { st = null; }
      $("opt-bar").style.width = "100%";
      const secs = ((performance.now() - t0) / 1000).toFixed(1);
      if (st && st.cameras) {
        applyState(st);
        const o = st.optimize || {};
        $("opt-status").textContent = (o.status || "done") + " in " + (o.seconds != null ? fmt(o.seconds, 1) : secs) + " s · gap " + fmt(st.metrics.coverage_gap, 4) + " · cost " + fmt(st.metrics.cost, 0);
        message("optimised with " + (o.solver || solver) + ": " + st.cameras.length + " cameras (Ctrl-Z undoes it)", "ok");
      } else { refresh(); $("opt-status").textContent = "done in " + secs + " s"; }
    });
    es.addEventListener("error", (ev) => {
      // a server-sent `event: error` carries data; a dropped connection does not
      let msg = null;
      if (ev && ev.data) { try { msg = JSON.parse(ev.data).error; } catch (e) { msg = String(ev.data); } }
      if (!S.es) return;
      finish();
      $("opt-status").textContent = msg ? "failed: " + msg : "progress stream closed";
      error(msg ? "optimise: " + msg : "optimise: the progress stream closed before the job finished");
      refresh();
    });
  }

  async function save() {
    const dir = $("save-dir").value.trim();
    const body = dir ? { dir } : {};
    $("btn-save").disabled = true;
    message("saving: contract files, report and hand-over set…");
    const r = await api("POST", "/api/save", body);
    $("btn-save").disabled = false;
    if (!r) return;
    const n = r.files ? r.files.length : 0;
    message("Saved " + n + " files to " + r.path + " · gap " + fmt(r.metrics && r.metrics.coverage_gap, 4), "ok");
    document.body.dataset.savedPath = r.path;
  }

  async function refresh() {
    const st = await api("GET", "/api/state");
    if (st) applyState(st);
  }

  /* ---------- 3D view (canvas, own projection) ---------- */
  function setView(v) {
    S.view = v;
    $("tab-plan").classList.toggle("active", v === "plan");
    $("tab-3d").classList.toggle("active", v === "3d");
    $("plan-wrap").classList.toggle("hidden", v !== "plan");
    $("view3d-wrap").classList.toggle("hidden", v !== "3d");
    if (v === "3d") draw3d();
  }

  function wire3d() {
    const cv = $("view3d");
    let last = null;
    cv.addEventListener("pointerdown", (e) => { last = [e.clientX, e.clientY]; try { cv.setPointerCapture(e.pointerId); } catch (err) { /* */ } });
    cv.addEventListener("pointermove", (e) => {
      if (!last) return;
      S.orbit.az -= (e.clientX - last[0]) * 0.008;
      S.orbit.el = Math.max(0.05, Math.min(1.5, S.orbit.el + (e.clientY - last[1]) * 0.008));
      last = [e.clientX, e.clientY];
      draw3d();
    });
    cv.addEventListener("pointerup", () => { last = null; });
    cv.addEventListener("wheel", (e) => { e.preventDefault(); S.orbit.zoom = Math.max(0.4, Math.min(4, S.orbit.zoom * (e.deltaY > 0 ? 0.9 : 1.1))); draw3d(); }, { passive: false });
  }

  function projector(W, H) {
    const [lo, hi] = S.scene.bounds;
    const cx = (lo[0] + hi[0]) / 2, cy = (lo[1] + hi[1]) / 2, cz = (lo[2] + hi[2]) / 3;
    const span = Math.max(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
    const { az, el, zoom } = S.orbit;
    const D = span * 2.2;
    const f = Math.min(W, H) * 1.9 * zoom;
    const ca = Math.cos(az), sa = Math.sin(az), ce = Math.cos(el), se = Math.sin(el);
    return (p) => {
      const x = p[0] - cx, y = p[1] - cy, z = p[2] - cz;
      const xr = ca * x - sa * y, yr = sa * x + ca * y;     // about z
      const u = xr, v = se * yr + ce * z;                   // viewer above -y', looking down by el
      const dd = D + ce * yr - se * z;
      return [W / 2 + f * u / dd, H / 2 - f * v / dd, dd];
    };
  }

  function draw3d() {
    const cv = $("view3d");
    const dpr = window.devicePixelRatio || 1;
    const W = cv.clientWidth, H = cv.clientHeight;
    if (!W || !H || !S.scene) return;
    cv.width = W * dpr; cv.height = H * dpr;
    const ctx = cv.getContext("2d");
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    ctx.clearRect(0, 0, W, H);
    const P = projector(W, H);
    const sc = S.scene, st = S.state;
    const poly = (ps, fill, stroke) => {
      ctx.beginPath();
      ps.forEach((p, i) => { const q = P(p); if (i) ctx.lineTo(q[0], q[1]); else ctx.moveTo(q[0], q[1]); });
      ctx.closePath();
      if (fill) { ctx.fillStyle = fill; ctx.fill(); }
      if (stroke) { ctx.strokeStyle = stroke; ctx.stroke(); }
    };
    ctx.lineWidth = 1;
    // a building: a cut-away, the selected storey and the ones below it, its coverage on its floor
    const floors = (sc.storeys || []).map((f) => f.name), top = floors.indexOf(S.floor);
    const below = (name) => !floors.length || !name || floors.indexOf(name) <= top;
    const ownFloor = (name) => { const k = String(name).indexOf("/"); return k > 0 && floors.includes(name.slice(0, k)) ? name.slice(0, k) : null; };
    const drawn = { storeys: [], cameras: [] };
    if (floors.length) {
      sc.storeys.forEach((f, k) => {
        if (k > top) return;
        poly(f.footprint.map((p) => [p[0], p[1], f.elevation_m]), k === top ? "#f1f3f6" : "rgba(241,243,246,0.55)", "#1f2430");
        drawn.storeys.push(f.name);
      });
    } else poly(sc.footprint.map((p) => [p[0], p[1], 0]), "#f1f3f6", "#1f2430");
    if (st && st.coverage_floor && $("show-coverage").checked) {
      const h = (sc.target_cell_m || 0.25) / 2;
      const z = floors.length ? sc.storeys[top].elevation_m : 0;
      (sc.targets_xy || []).forEach((p, i) => {
        if (floors.length && sc.targets_storey[i] !== S.floor) return;
        poly([[p[0] - h, p[1] - h, z], [p[0] + h, p[1] - h, z], [p[0] + h, p[1] + h, z], [p[0] - h, p[1] + h, z]], covColour(st.coverage_floor[i] || 0, gammaAt(i)));
      });
    }
    // obstacle faces, far to near
    const faces = [];
    for (const o of sc.obstacles || []) {
      if (!below(ownFloor(o.name))) continue;
      const pg = o.polygon, z0 = o.zmin || 0, z1 = o.zmax || 0;
      for (let i = 0; i < pg.length; i++) {
        const a = pg[i], b = pg[(i + 1) % pg.length];
        faces.push({ top: false, ps: [[a[0], a[1], z0], [b[0], b[1], z0], [b[0], b[1], z1], [a[0], a[1], z1]] });
      }
      faces.push({ top: true, ps: pg.map((p) => [p[0], p[1], z1]) });
    }
    const depth = (f) => f.reduce((s, p) => s + P(p)[2], 0) / f.length;
    faces.map((f) => [depth(f.ps), f]).sort((a, b) => b[0] - a[0]).forEach(([, f]) => {
      poly(f.ps, f.top ? "rgba(170,176,188,0.95)" : "rgba(120,128,142,0.88)", "#4b5160");
    });
    S.drawn3d = drawn;  // what the 3D view shows (the browser tests read it)
    if (!st) return;
    for (const c of st.cameras) {
      if (!below(c.storey)) continue;
      drawn.cameras.push(c.id);
      const t = typeOf(c.camera) || { hfov_deg: 60, vfov_deg: 40 };
      const y = c.yaw_deg * Math.PI / 180, p = c.pitch_deg * Math.PI / 180, r = (c.roll_deg || 0) * Math.PI / 180;
      const fw = [Math.cos(p) * Math.cos(y), Math.cos(p) * Math.sin(y), -Math.sin(p)];
      const rt0 = [Math.sin(y), -Math.cos(y), 0];
      const dn0 = [fw[1] * rt0[2] - fw[2] * rt0[1], fw[2] * rt0[0] - fw[0] * rt0[2], fw[0] * rt0[1] - fw[1] * rt0[0]];
      const rt = rt0.map((v, i) => v * Math.cos(r) + dn0[i] * Math.sin(r));
      const dn = dn0.map((v, i) => v * Math.cos(r) - rt0[i] * Math.sin(r));
      const L = c.id === S.sel ? 2.0 : 1.0, th = Math.tan(Math.min(t.hfov_deg, 150) * Math.PI / 360), tv = Math.tan(Math.min(t.vfov_deg, 150) * Math.PI / 360);
      const o = c.position;
      const corner = (sx, sy) => o.map((v, i) => v + L * (fw[i] + sx * th * rt[i] + sy * tv * dn[i]));
      const cs = [corner(-1, -1), corner(1, -1), corner(1, 1), corner(-1, 1)];
      const col = colourOf(c.camera);
      ctx.strokeStyle = col; ctx.lineWidth = c.id === S.sel ? 2 : 1;
      const po = P(o);
      ctx.beginPath();
      for (const q of cs) { const qq = P(q); ctx.moveTo(po[0], po[1]); ctx.lineTo(qq[0], qq[1]); }
      ctx.stroke();
      ctx.globalAlpha = c.id === S.sel ? 0.35 : 0.15;
      poly(cs, col, null);
      ctx.globalAlpha = 1;
      poly(cs, null, col);
      ctx.beginPath(); ctx.arc(po[0], po[1], c.id === S.sel ? 5 : 3.5, 0, 2 * Math.PI); ctx.fillStyle = col; ctx.fill();
    }
  }

  /* ---------- start ---------- */
  async function start() {
    wire();
    const sc = await api("GET", "/api/scene");
    if (!sc) {
      if (!TOKEN) error("no token: open the address camplace serve printed (it ends in ?token=…)");
      return;
    }
    S.scene = sc;
    drawScene();
    const st = await api("GET", "/api/state");
    if (!st) return;
    applyState(st);
    $("timing").textContent = "no change yet";
    if (st.busy) { $("opt-status").textContent = "an optimisation is running…"; follow("the solver"); }
    message("ready: drag a camera, turn it with its handle or the sliders; “Optimise the rest” keeps the locked ones");
    document.body.dataset.ready = "1";
  }
  start();
})();
