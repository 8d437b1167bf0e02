// spindown-web's room page: every bench as a tile (state, the latest run's curve and fit,
// c3/c4 in the lab's units, health, doubts, the bridge's health), live.
"use strict";

(() => {
  const { el, setText, setCoefficient, setHealth, setDoubts, setBridge, bridgeDetail, servicesText, problemsText } = spindown;
  const tilesBox = document.getElementById("tiles");
  const tiles = new Map(); // id -> {root, parts…, summary, trace}

  function makeTile(id) {
    const name = el("a", { class: "name", href: "/bench/" + encodeURIComponent(id) }, id);
    const state = el("span", { class: "state" }, "…");
    const run = el("span", { class: "run" });
    const canvas = el("canvas", { width: 600, height: 160, "aria-label": `${id}: the latest run's readings` });
    const best = el("dd", { "data-field": "best" }, "–");
    const c3 = el("dd", { "data-field": "c3" }, "–");
    const c4 = el("dd", { "data-field": "c4" }, "–");
    const health = el("dd", { "data-field": "health" }, "–");
    const doubts = el("ul", { class: "doubts", "data-field": "doubts" });
    const bridge = el("span", { "data-field": "bridge" }, "…");
    const bridgeInfo = el("span", { class: "detail" });
    const root = el("article", { class: "tile", "data-bench": id, "data-state": "idle" },
      el("header", {}, name, state),
      run,
      canvas,
      el("dl", {}, el("dt", { "data-term": "best" }, "best"), best, el("dt", {}, "c3"), c3, el("dt", {}, "c4"), c4,
        el("dt", { "data-term": "health" }, "health"), health),
      doubts,
      el("footer", {}, "bridge ", bridge, " ", bridgeInfo));
    const t = { id, root, state, run, canvas, best, c3, c4, health, doubts, bridge, bridgeInfo, summary: null,
                trace: { key: 0, x: [], y: [] }, dirty: true };
    tiles.set(id, t);
    placeTiles();
    return t;
  }

  // A room on one screen (a projector, a wide monitor): the tiles share the window, as many
  // columns as make them largest, and show as much as fits at a font of at least 14 px — the
  // whole tile, then name, state, c3, c4, health and the first doubt (compact), then name, state,
  // c3 and c4 (dense). A phone, or a room too big for its screen even so, scrolls as a list.
  const minFont = 14;
  let fitWanted = true;
  function overflows(t) {
    const r = t.root;
    return r.scrollHeight > r.clientHeight + 1 || r.scrollWidth > r.clientWidth + 1;
  }
  function unfit() {
    delete tilesBox.dataset.fit;
    delete tilesBox.dataset.density;
    tilesBox.style.removeProperty("--cols");
    tilesBox.style.removeProperty("--tile-h");
    tilesBox.style.removeProperty("--tile-font");
  }
  function fitRoom() {
    fitWanted = false;
    const n = tiles.size;
    if (n === 0 || window.innerWidth < 700) return unfit();
    const main = tilesBox.parentElement, ms = getComputedStyle(main), bs = getComputedStyle(tilesBox);
    const above = tilesBox.getBoundingClientRect().top + window.scrollY;
    const below = document.querySelector(".bottom").offsetHeight + parseFloat(ms.paddingBottom);
    const W = tilesBox.clientWidth, H = window.innerHeight - above - below;
    const gapX = parseFloat(bs.columnGap) || 0, gapY = parseFloat(bs.rowGap) || 0;
    let best = null;
    for (let c = 1; c <= n; c++) {
      const r = Math.ceil(n / c), w = (W - gapX * (c - 1)) / c, h = Math.floor((H - gapY * (r - 1)) / r);
      if (w < 150 || h < 3.2 * minFont * 1.35) continue;
      const size = Math.min(w, 1.7 * h);
      if (!best || size > best.size) best = { c, h, size };
    }
    if (!best) return unfit();
    tilesBox.dataset.fit = "";
    tilesBox.style.setProperty("--cols", String(best.c));
    tilesBox.style.setProperty("--tile-h", best.h + "px");
    const top = Math.max(minFont, Math.min(26, Math.floor(best.h / 5)));
    for (const density of ["full", "compact", "dense"]) {
      tilesBox.dataset.density = density;
      for (let f = top; f >= minFont; f--) {
        tilesBox.style.setProperty("--tile-font", f + "px");
        let all = true;
        for (const t of tiles.values()) if (overflows(t)) { all = false; break; }
        if (all) {
          for (const t of tiles.values()) t.dirty = true;
          return;
        }
      }
    }
    // Nothing fits whole: the dense tiles at the least font, each cut at its own edge.
  }

  function placeTiles() {
    const ids = Array.from(tiles.keys()).sort((a, b) => a.localeCompare(b, undefined, { numeric: true }));  // bench-2 before bench-10
    ids.forEach((id, i) => {
      const root = tiles.get(id).root;
      if (tilesBox.children[i] !== root) tilesBox.insertBefore(root, tilesBox.children[i] || null);
    });
    document.getElementById("empty").hidden = tiles.size > 0;
    fitWanted = true;
  }

  function tile(id) { return tiles.get(id) || makeTile(id); }

  function showSummary(s) {
    const t = tile(s.id);
    t.summary = s;
    t.root.setAttribute("data-state", s.state);
    t.silentSince = s.last_sample_unix_ms || null;  // sent while the bench is silent or unplugged
    setText(t.state, stateText(t));
    const fit = s.last_fit;
    const run = s.run;
    let runText = run ? `run ${run.number}${run.partial ? " (partial)" : ""}: ${run.state}` : "no run yet";
    if (fit && run && fit.run !== run.number) runText += ` · fit of run ${fit.run}`;
    setText(t.run, runText);
    setText(t.best, fit ? (fit.best || "no model converged") : "–");
    setCoefficient(t.c3, fit ? fit.c3 : null, fit ? fit.run : undefined);
    setCoefficient(t.c4, fit ? fit.c4 : null, fit ? fit.run : undefined);
    setHealth(t.health, fit);
    setDoubts(t.doubts, fit, s);
    setBridge(t.bridge, s.bridge);
    setText(t.bridgeInfo, s.refused ? `its samples are refused: ${s.refused}` : bridgeDetail(s.bridge));
    t.dirty = true;
    t.check = true;  // new text may not fit the tile's room any more
  }

  // "silent · last sample 14 s ago" while a bench is silent (counted on this page's clock).
  function ageText(ms) {
    const s = Math.max(0, Math.round(ms / 1000));
    return s < 120 ? `${s} s` : s < 7200 ? `${Math.floor(s / 60)} min ${s % 60} s` : `${Math.floor(s / 3600)} h`;
  }
  function stateText(t) {
    const s = t.summary ? t.summary.state : "…";
    return t.silentSince ? `${s} · last sample ${ageText(Date.now() - t.silentSince)} ago` : s;
  }
  setInterval(() => {
    for (const t of tiles.values()) if (t.silentSince) setText(t.state, stateText(t));
  }, 1000);

  function takeSamples(all) {
    for (const [id, p] of Object.entries(all.benches || {})) {
      const t = tile(id);
      if (p.reset || p.key !== t.trace.key) t.trace = { key: p.key, x: [], y: [] };
      for (const [x, y] of p.p) {
        t.trace.x.push(x);
        t.trace.y.push(y);
      }
      t.dirty = true;
    }
  }

  // The sparkline: the run's readings, and the best model's curve when the fit is this run's.
  function draw(t) {
    const c = t.canvas;
    if (!c.offsetParent) return;  // not shown (a compact tile)
    const w = c.clientWidth || 300, h = c.clientHeight || 80;
    const dpr = window.devicePixelRatio || 1;
    if (c.width !== Math.round(w * dpr) || c.height !== Math.round(h * dpr)) {
      c.width = Math.round(w * dpr);
      c.height = Math.round(h * dpr);
    }
    const g = c.getContext("2d");
    g.setTransform(dpr, 0, 0, dpr, 0, 0);
    g.clearRect(0, 0, w, h);
    const { x, y } = t.trace;
    const s = t.summary;
    const fit = s && s.last_fit;
    const curve = fit && s.run && fit.run === s.run.number ? s.last_fit_curve || [] : [];
    if (x.length < 2 && curve.length < 2) return;
    let x0 = Infinity, x1 = -Infinity, y0 = 0, y1 = 0.1;
    for (let i = 0; i < x.length; i++) {
      x0 = Math.min(x0, x[i]); x1 = Math.max(x1, x[i]);
      y0 = Math.min(y0, y[i]); y1 = Math.max(y1, y[i]);
    }
    for (const [cx, cy] of curve) {
      if (cy === null) continue;
      x0 = Math.min(x0, cx); x1 = Math.max(x1, cx); y1 = Math.max(y1, cy);
    }
    if (!(x1 > x0)) x1 = x0 + 1;
    const px = (v) => 4 + (w - 8) * (v - x0) / (x1 - x0);
    const py = (v) => h - 4 - (h - 8) * (v - y0) / (y1 - y0);
    g.lineWidth = 1.5;
    g.strokeStyle = getComputedStyle(document.documentElement).getPropertyValue("--data").trim() || "#333";
    g.beginPath();
    for (let i = 0; i < x.length; i++) (i ? g.lineTo : g.moveTo).call(g, px(x[i]), py(y[i]));
    g.stroke();
    if (curve.length > 1) {
      g.lineWidth = 2.5;
      g.strokeStyle = fit.best === "viscous" ? "#d62728" : fit.best === "coulomb" ? "#2ca02c" : "#1f77b4";
      g.beginPath();
      curve.forEach(([cx, cy], i) => (i ? g.lineTo : g.moveTo).call(g, px(cx), py(cy)));
      g.stroke();
    }
  }

  function frame() {
    if (!fitWanted && tilesBox.dataset.fit !== undefined)
      for (const t of tiles.values()) if (t.check) { t.check = false; if (overflows(t)) fitWanted = true; }
    if (fitWanted) fitRoom();
    for (const t of tiles.values()) if (t.dirty) { t.dirty = false; draw(t); }
    requestAnimationFrame(frame);
  }

  spindown.unitsToggle(document.getElementById("units"));
  function showLab(lab) {
    spindown.serverUnits(lab ? lab.lab_units : undefined);
    setText(document.getElementById("services"), servicesText(lab));
    document.getElementById("problems").textContent = problemsText(lab);  // none: nothing said (no dash)
  }

  spindown.live("", {
    snapshot(d) {
      const ids = new Set(d.benches.map((b) => b.id));
      for (const id of Array.from(tiles.keys())) if (!ids.has(id)) { tiles.get(id).root.remove(); tiles.delete(id); }
      for (const t of tiles.values()) t.trace = { key: 0, x: [], y: [] };
      d.benches.forEach(showSummary);
      takeSamples(d.samples ? { benches: d.samples } : {});
      showLab(d.lab);
      placeTiles();
    },
    bench: showSummary,
    samples: takeSamples,
    roster(d) {
      const ids = new Set(d.benches);
      for (const id of Array.from(tiles.keys())) if (!ids.has(id)) { tiles.get(id).root.remove(); tiles.delete(id); }
      for (const id of d.benches) tile(id);
      placeTiles();
    },
    lab: showLab,
  });
  window.addEventListener("resize", () => { fitWanted = true; for (const t of tiles.values()) t.dirty = true; });
  requestAnimationFrame(frame);
})();
