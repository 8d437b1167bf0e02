// spindown-web's bench page: the current run's readings as they arrive, the cut and the stop
// once the fitter finds them, the three models' curves when the FIT arrives, the best model's
// residuals, the explain story, the session's earlier runs (to overlay and compare), the run's
// CSV, and a print layout for the lab report.
"use strict";

(() => {
  const { el, setText, setCoefficient, setHealth, setDoubts, setBridge, bridgeDetail } = spindown;
  const id = decodeURIComponent(location.pathname.replace(/^\/bench\//, "").replace(/\/$/, ""));
  const $ = (x) => document.getElementById(x);
  const head = $("head"), plotBox = $("plot"), residualBox = $("residuals");
  const colors = { viscous: "#d62728", coulomb: "#2ca02c", combined: "#1f77b4" };
  const overlayColors = ["#9ca3af", "#c084fc", "#f59e0b", "#14b8a6", "#f472b6", "#84cc16", "#60a5fa"];

  document.title = `spindown · ${id}`;
  head.setAttribute("data-bench", id);
  setText($("bench-name"), id);

  // What the page knows.
  let trace = { key: 0, n: 0, x: [], y: [] };
  let detail = null;              // the current run's detail event
  let lastSummary = null;         // the bench's latest summary: what is known of its messages' sources
  const overlays = new Map();     // run number -> {points, color}
  let labName = "";               // the lab's name (--lab of spindown-web)
  let chosen = null;              // a finished run chosen in the runs table to show and print (its row)
  let plot = null, residualPlot = null, dirty = true;

  // ---- the main plot ------------------------------------------------------------------------
  function series() {
    const s = [{ label: "s after the cut" }, { label: "reading", stroke: getComputedStyle(document.documentElement).getPropertyValue("--data").trim() || "#222", width: 1.5, points: { show: false } }];
    const models = curveModels();
    for (const m of models) s.push({ label: m.name, stroke: colors[m.name] || "#555", width: m.name === bestName() ? 3 : 2,
                                     dash: m.name === "viscous" ? [8, 4] : m.name === "coulomb" ? [3, 3] : undefined,
                                     spanGaps: true, points: { show: false } });
    for (const [n, o] of overlays) s.push({ label: `run ${n}`, stroke: o.color, width: 1, spanGaps: true, points: { show: false } });
    return s;
  }

  function curveModels() {
    const c = detail && detail.run && detail.run.curves;
    return c ? c.models.filter((m) => m.converged && m.curve.length > 1) : [];
  }

  function bestName() {
    const f = detail && detail.run && detail.run.fit;
    return f ? f.best : "";
  }

  // uPlot wants one x for every series: the union of the readings', the curves' and the
  // overlays' x, each series null where it has no point (drawn across: spanGaps).
  function plotData() {
    const lines = [{ x: trace.x, y: trace.y }];
    for (const m of curveModels()) lines.push({ x: m.curve.map((p) => p[0]), y: m.curve.map((p) => p[1]) });
    for (const o of overlays.values()) lines.push({ x: o.points.map((p) => p[0]), y: o.points.map((p) => p[1]) });
    const xs = [];
    lines.forEach((l, li) => l.x.forEach((x, i) => xs.push([x, li, i])));
    xs.sort((a, b) => a[0] - b[0]);
    const out = [[]];
    for (let i = 0; i < lines.length; i++) out.push([]);
    for (const [x, li, i] of xs) {
      out[0].push(x);
      for (let k = 0; k < lines.length; k++) out[k + 1].push(k === li ? lines[li].y[i] : null);
    }
    return out;
  }

  // On screen, height; printed, printHeight (the main plot smaller, the residuals as tall as their
  // scale needs: a tick either side of 0 and the axis's name).
  function plotSize(box, height, printHeight = Math.round(height * 0.6)) {
    const printing = window.matchMedia && window.matchMedia("print").matches;
    const width = printing ? 680 : Math.max(240, box.clientWidth || 600);
    return { width, height: printing ? printHeight : height };
  }

  // The cut and the stop as lines on the plot (drawn on the canvas: they print too).
  function drawMarkers(u) {
    const m = detail && detail.run && detail.run.markers;
    if (!m) return;
    const g = u.ctx;
    g.save();
    g.strokeStyle = "#9a3412";
    g.fillStyle = "#9a3412";
    g.lineWidth = 1.5 * devicePixelRatio;
    g.setLineDash([6 * devicePixelRatio, 4 * devicePixelRatio]);
    g.font = `${12 * devicePixelRatio}px system-ui, sans-serif`;
    for (const [name, x] of Object.entries({ cut: m.cut, stop: m.stop })) {
      if (x === null || x === undefined) continue;
      const px = u.valToPos(x, "x", true);
      if (px < u.bbox.left || px > u.bbox.left + u.bbox.width) continue;
      g.beginPath();
      g.moveTo(px, u.bbox.top);
      g.lineTo(px, u.bbox.top + u.bbox.height);
      g.stroke();
      g.fillText(name, px + 4 * devicePixelRatio, u.bbox.top + 14 * devicePixelRatio);
    }
    g.restore();
  }

  // Zoom: drag a box (both axes), or along one axis; double-click or "whole run" shows all again.
  // A zoomed or paused plot keeps its view while readings arrive (they are kept, and shown on resume).
  let zoomed = false, paused = false, rebuildWanted = false;
  function showView() {
    $("zoom-reset").hidden = !zoomed;
    $("pause").textContent = paused ? "Resume the live plot" : "Pause the live plot";
    $("pause").setAttribute("aria-pressed", paused ? "true" : "false");
    plotBox.setAttribute("data-view", paused ? "paused" : "live");
    plotBox.setAttribute("data-zoomed", zoomed ? "true" : "false");
  }
  function rebuildPlot() {
    if (typeof uPlot === "undefined") return;
    if (plot) plot.destroy();
    const unit = (detail && detail.unit) || "V";
    zoomed = false;
    showView();
    plot = new uPlot({
      ...plotSize(plotBox, 340),
      series: series(),
      scales: { x: { time: false } },
      // The unit in words beside the axis: a rotated "V" alone reads as ">".
      axes: [{ label: "s after the cut" }, { label: `reading (${unit})`, size: 60 }],
      legend: { show: false },
      cursor: { drag: { x: true, y: true, uni: 40 } },
      hooks: {
        draw: [drawMarkers],
        setSelect: [(u) => { if (u.select.width > 0 || u.select.height > 0) { zoomed = true; showView(); } }],
        // The view's ranges, for a reader of the page (and its tests): data-x, data-y "min,max".
        setScale: [(u, key) => { if (key === "x" || key === "y") plotBox.setAttribute(`data-${key}`, `${u.scales[key].min},${u.scales[key].max}`); }],
      },
    }, plotData(), plotBox);
    plot.over.addEventListener("dblclick", () => { zoomed = false; showView(); dirty = true; });
  }

  function redraw() {
    dirty = false;
    plotBox.setAttribute("data-points", String(trace.n));
    if (paused) { /* the view stays as it was: a new run, its curves and readings show on resume */ }
    else if (!plot || plot.series.length !== series().length) rebuildPlot();
    else plot.setData(plotData(), !zoomed);
    if (!paused) plotBox.setAttribute("data-drawn", String(trace.n));  // the readings the plot shows
  }

  // ---- residuals ---------------------------------------------------------------------------
  function showResiduals() {
    const r = detail && detail.run && detail.run.curves && detail.run.curves.residuals;
    if (residualPlot) { residualPlot.destroy(); residualPlot = null; }
    setText($("residuals-title"), r ? `of the ${r.model} model, ${r.unit} (reading noise σ ${r.noise === null ? "?" : r.noise.toPrecision(2)} ${r.unit})` : "after the fit");
    residualBox.setAttribute("data-count", r ? String(r.points.length) : "0");
    if (!r || typeof uPlot === "undefined") return;
    // In mV when the residuals are volts under a tenth of one (the usual: a few mV), so that the
    // ticks read as numbers; the scale symmetric about 0, at least ±3 σ of the reading's noise.
    const milli = r.unit === "V" && r.points.every((p) => Math.abs(p[1]) < 0.1);
    const k = milli ? 1000 : 1, unit = milli ? "mV" : r.unit;
    const x = r.points.map((p) => p[0]), y = r.points.map((p) => p[1] * k);
    const reach = Math.max(...y.map(Math.abs), 3 * (r.noise || 0) * k) * 1.1 || 1;
    residualBox.setAttribute("data-range", String(reach));
    const decade = 10 ** Math.floor(Math.log10(reach / 1.1));
    const tick = [5, 2, 1].map((m) => m * decade).find((v) => v <= reach / 1.1) || decade;
    residualBox.setAttribute("data-unit", unit);
    residualPlot = new uPlot({
      ...plotSize(residualBox, 200, 140),
      series: [{ label: "s" }, { label: "residual", stroke: colors[r.model] || "#1f77b4", width: 0, paths: () => null,
                                  points: { show: true, size: 2.5, fill: colors[r.model] || "#1f77b4" } },
               { label: "0", stroke: "#888", width: 1 }],
      scales: { x: { time: false }, y: { range: () => [-reach, reach] } },
      axes: [{ label: "s after the cut" },
             // The unit's name alone where it reads upright turned (mV, rpm: it fits a printed
             // plot's height); a lone "V" turned reads as ">", so it is named.
             { label: unit === "V" ? "residual (V)" : unit, size: 56,
               // 0 and a round step either side (1, 2 or 5 × 10^k within the scale), however short
               // the plot (printed, it is): the scale is always read off.
               splits: () => [-tick, 0, tick],
               values: (u, splits) => { residualBox.setAttribute("data-y-ticks", splits.join()); return splits.map((v) => String(+v.toPrecision(3))); } }],
      legend: { show: false },
    }, [x, y, x.map(() => 0)], residualBox);
  }

  // ---- the run's detail: title, markers, fit, curves, explain, earlier runs -----------------
  function showDetail(d) {
    const newRun = !detail || !detail.run || !d.run || detail.run.key !== d.run.key;
    detail = d;
    const run = d.run;
    setText($("unit"), d.unit || "V");
    if (!run) {
      setText($("run-title"), "Waiting for a run");
    } else if (!chosen) {
      setText($("run-title"), `Run ${run.number}${run.partial ? " (partial: the cut was not seen)" : ""} · ${run.state}`);
    }
    // A run longer than this page keeps is said where its plot is: the plot and the CSV are its start only.
    const cut = run && run.truncated
      ? `The plot and the CSV hold only the first ${run.kept} of this run's ${run.samples} samples (this page keeps that many of a run); the fit uses them all. `
      : "";
    setText($("run-note"), run ? cut + (run.note || "") : "Spin the motor up and cut the supply: the run appears here as it coasts.");
    // Markers present once the fitter found them.
    const markers = [];
    if (run && run.markers.cut !== null) markers.push(el("li", { "data-marker": "cut" }, `cut at t = ${run.t_cut_s.toFixed(3)} s`));
    if (run && run.markers.stop !== null) markers.push(el("li", { "data-marker": "stop" },
      `stop at t = ${run.t_stop_s.toFixed(3)} s (${run.markers.stop.toFixed(2)} s after the ${run.partial ? "first sample" : "cut"})`));
    $("markers").replaceChildren(...markers);
    // The fit (a run chosen in the runs table keeps its own until "back to the live run").
    const fit = run ? run.fit : null;
    if (!chosen) showLatestFit();
    // One legend entry per model the FIT carries.
    const legend = [el("li", {}, el("span", { class: "swatch" }), "readings")];
    if (run && run.curves) for (const m of run.curves.models) {
      const rmse = m.rmse === null ? "" : ` RMSE ${m.rmse.toPrecision(3)} ${fit.residual_unit}`;
      legend.push(el("li", { "data-curve": m.name, "data-converged": m.converged ? "true" : "false", class: m.name === fit.best ? "best" : null },
        el("span", { class: "swatch" }), m.name + (m.converged ? rmse : ": did not converge") + (m.name === fit.best ? " (best)" : "")));
    }
    for (const [n, o] of overlays) {
      const sw = el("span", { class: "swatch" });
      sw.style.background = o.color;
      legend.push(el("li", { "data-overlay": String(n) }, sw, `run ${n}`));
    }
    $("legend").replaceChildren(...legend);
    // CSV of this run.
    const csv = $("csv");
    if (run) {
      csv.href = run.csv;
      csv.setAttribute("download", `${id}-run${run.number}.csv`);
      csv.removeAttribute("aria-disabled");
    } else {
      csv.href = "#";
      csv.setAttribute("aria-disabled", "true");
    }
    showExplain(run ? run.explain : null);
    showRuns(d.earlier || [], run);
    // The plots in a task of their own: the numbers, curves' legend and markers show at once.
    setTimeout(() => {
      showResiduals();
      if (newRun && !paused) rebuildPlot();
      else if (newRun) rebuildWanted = true;
      dirty = true;
    }, 0);
  }

  // The lab record's line: which run, where, when, and the J and K_b its numbers rest on.
  function when(ms) {
    if (!ms) return "";
    const d = new Date(ms), p = (n) => String(n).padStart(2, "0");
    return `${d.getFullYear()}-${p(d.getMonth() + 1)}-${p(d.getDate())} ${p(d.getHours())}:${p(d.getMinutes())}`;
  }
  function g(v, digits = 3) { return Number(v).toPrecision(digits).replace(/\.?0+(e|$)/, "$1"); }
  function recordText(run, fit) {
    if (!run) return "";
    const parts = [`Run ${run.number} of ${id}`];
    if (labName) parts.push(`lab ${labName}`);
    if (fit && fit.unix_ms) parts.push(when(fit.unix_ms));
    if (fit && fit.inertia_kg_m2) parts.push(`J = ${g(fit.inertia_kg_m2)} kg·m² (${g(fit.inertia_kg_m2 * 1e7)} g·cm²), from ${fit.inertia_source || fit.bench_source || "?"}`);
    if (fit && fit.kb_v_s_per_rad) parts.push(`K_b = ${g(fit.kb_v_s_per_rad)} V·s/rad (${g(fit.kb_v_s_per_rad * 1e3)} mV·s/rad), from ${fit.kb_source || fit.bench_source || "?"}`);
    return parts.join(" · ");
  }

  // The numbers of the run shown: the live run's, or a finished run chosen in the runs table.
  function showFit(fit) {
    setText($("best"), fit ? (fit.best || "no model converged") : "–");
    setCoefficient($("c3"), fit ? fit.c3 : null, fit ? fit.run : undefined);
    setCoefficient($("c4"), fit ? fit.c4 : null, fit ? fit.run : undefined);
    setHealth($("health"), fit);
    setDoubts($("doubts"), fit, lastSummary);
    $("best-reason").textContent = fit ? fit.best_reason : "";
    $("health-reason").textContent = fit && fit.health_reason ? `health: ${fit.health_reason}` : "";
  }
  // The live run's fit; while it has none (it coasts), the bench's last whole run's, said so (as
  // the room's tile shows it).
  function showLatestFit() {
    const run = detail && detail.run, fit = run ? run.fit : null;
    const last = lastSummary && lastSummary.last_fit;
    const shown = fit || (last && (!run || last.run !== run.number) ? last : null);
    showFit(shown);
    const earlier = !fit && shown && run;
    $("fit-of").textContent = earlier ? `of run ${shown.run}, the last whole run (run ${run.number} is ${run.state})` : "";
    // The record is of the run whose numbers are shown; printed then, the page is that run's record
    // (the live run's title, plot and state are not printed: spindown.css).
    if (earlier) document.body.setAttribute("data-fit-of", String(shown.run));
    else document.body.removeAttribute("data-fit-of");
    for (const tr of $("runs").children) tr.classList.toggle("chosen", !!earlier && tr.getAttribute("data-run") === String(shown.run));
    setText($("record"), earlier ? recordText({ number: shown.run }, shown) : recordText(run, fit));
  }
  function choose(r) {
    chosen = r;
    document.body.setAttribute("data-chosen-run", String(r.number));
    document.body.removeAttribute("data-fit-of");
    $("back-live").hidden = false;
    setText($("run-title"), `Run ${r.number}${r.partial ? " (partial: the cut was not seen)" : ""} · ${r.state} (chosen in this session's runs)`);
    $("fit-of").textContent = "";
    setText($("record"), recordText(r, r.fit));
    showFit(r.fit);
    for (const tr of $("runs").children) tr.classList.toggle("chosen", tr.getAttribute("data-run") === String(r.number));
    if (!overlays.has(r.number)) toggleOverlay(r.number, true);
  }
  $("back-live").addEventListener("click", () => {
    chosen = null;
    document.body.removeAttribute("data-chosen-run");
    $("back-live").hidden = true;
    if (detail) showDetail(detail);
  });

  // What each effect the explain workflow adds is, in a student's words (the models' own meanings,
  // core/models/src/effects.cpp, shortened); the statistics stay one click away.
  const effectWords = {
    viscous: ["viscous friction", "a drag that grows with speed, like oil being sheared"],
    coulomb: ["dry (Coulomb) friction", "a constant drag, like brushes and bearings rubbing; it is what makes the shaft stop"],
    stribeck: ["Stribeck friction", "extra friction near standstill, where the lubricant film breaks down"],
    windage: ["air drag", "drag of the flywheel in the air, growing with the square of the speed"],
    sensor_offset: ["an offset of the reading", "the reading does not come back to zero when the shaft stands still"],
  };
  function stepWords(s, noise, unit, tCut) {  // tCut: the run's cut on the bench's clock (where's times are on it)
    const [name, meaning] = effectWords[s.added] || [s.added, ""];
    const before = s.rmse_before, after = s.rmse_after;
    const parts = [`Adding ${name}${meaning ? ` (${meaning})` : ""}`];
    if (before > 0 && after > 0) {
      const ratio = before / after;
      parts.push(`: the model then misses the readings by ${fmt(after)} ${unit} on average instead of ${fmt(before)} ${unit}` +
                 (ratio >= 1.05 ? ` (${ratio >= 10 ? ratio.toFixed(0) : ratio.toFixed(1)}× closer)` : ""));
      if (noise > 0 && after <= 1.5 * noise) parts.push(`, about as close as the reading's own noise (${fmt(noise)} ${unit}) allows`);
    }
    const w = (s.where || []).filter((x) => x.mean_residual !== null).sort((a, b) => Math.abs(b.mean_residual) - Math.abs(a.mean_residual))[0];
    if (w) parts.push(`. Without it the model was furthest off from ${(w.t_from_s - tCut).toFixed(1)} to ${(w.t_to_s - tCut).toFixed(1)} s after the cut, ` +
                      `where the readings were ${fmt(Math.abs(w.mean_residual))} ${unit} ${w.mean_residual > 0 ? "above" : "below"} it`);
    return parts.join("") + ".";
  }

  function showExplain(x) {
    const list = $("explain");
    if (!x) {
      list.replaceChildren();
      setText($("explain-base"), "");
      $("explain-final").textContent = "The story arrives after the fit (the fitter's EXPLAIN).";
      return;
    }
    const unit = (detail && detail.unit) || "V";
    const baseName = x.base.map((b) => (effectWords[b] || [b])[0]).join(" and ");
    setText($("explain-base"), `starting from ${baseName} alone, which misses by ${fmt(x.rmse_base)} ${unit}`);
    const base = x.rmse_base > 0 ? x.rmse_base : 1;
    list.replaceChildren(...x.steps.map((s) => {
      const pct = Math.max(1, Math.min(100, 100 * (s.rmse_after || 0) / base));
      return el("li", { "data-explain-step": s.added },
        el("strong", {}, `+ ${(effectWords[s.added] || [s.added])[0]}`), " ",
        el("span", { class: "gap" }, `misses by ${fmt(s.rmse_before)} → ${fmt(s.rmse_after)} ${unit}`),
        el("div", { class: "bar", role: "img", "aria-label": `${pct.toFixed(0)} % of the first model's miss left` }, barFill(pct)),
        el("p", { class: "step-words" }, stepWords(s, x.noise_level, unit, (detail && detail.run && detail.run.t_cut_s) || 0)),
        el("details", { class: "why" }, el("summary", {}, "the statistics"), s.why));
    }));
    const params = x.params.map((p) => `${p.name} = ${spindown.inUnits(p)}`).join(", ");
    $("explain-final").textContent = x.steps.length
      ? `final model: ${x.final.map((b) => (effectWords[b] || [b])[0]).join(" + ")}, missing by ${fmt(x.rmse_final)} ${unit} ` +
        `(${(x.rmse_base / x.rmse_final).toFixed(1)}× closer than at the start); ${params}`
      : `nothing missing: ${baseName} explains the run down to the reading's noise (${fmt(x.noise_level)} ${unit}); ${params}`;
  }

  function barFill(pct) {
    const s = el("span");
    s.style.width = pct + "%";
    return s;
  }

  function fmt(v) { return v === null || v === undefined ? "?" : Number(v).toPrecision(3); }

  // Every kept run of the session, the current one first: its fit, and a box to overlay it.
  // Why a run is not a whole one (abandoned, or its window closed before the stop), in words; "" when whole.
  const endWords = { "clock restart": "cut short: the board reset (clock restart)", "new source": "cut short: another source took over",
    "power back": "closed early: the reading rose again (power back)", "silent": "cut short: the bench went silent",
    "cap": "closed early: coast longer than the fitter keeps", "gap": "cut short: a gap in the samples",
    "end of data": "cut short: the samples ended before the stop" };
  function notWhole(r) {
    if (r.state === "abandoned") return `abandoned${r.note ? ": " + r.note : ""}`;
    const end = r.fit && r.fit.end;
    if (end && endWords[end]) return endWords[end];
    return r.partial ? "partial: its cut was not seen" : "";
  }

  function coefCell(c, run) {
    const td = el("td");
    setCoefficient(td, c, run);
    return td;
  }

  function showRuns(earlier, current) {
    // Newest first; a number the fitter gave again after abandoning a run is listed once (its latest).
    const seen = new Set();
    const all = (current ? [current] : []).concat(earlier.slice().reverse()).filter((r) => {
      if (seen.has(r.number)) return false;
      seen.add(r.number);
      return true;
    });
    const rows = all.map((r) => {
      const f = r.fit;
      const isCurrent = current && r.key === current.key;
      let compare = "this run";
      if (!isCurrent) {
        compare = el("input", { type: "checkbox", class: "compare", "aria-label": `overlay run ${r.number}` });
        compare.checked = overlays.has(r.number);
        compare.addEventListener("change", () => toggleOverlay(r.number, compare.checked));
      }
      const why = notWhole(r);
      let show = "";
      if (!isCurrent && r.fit) {
        show = el("button", { type: "button", class: "show-run", "aria-label": `show run ${r.number} to print` }, `show run ${r.number}`);
        show.addEventListener("click", () => choose(r));
      }
      const printed = chosen ? chosen.number : Number(document.body.getAttribute("data-fit-of") || NaN);
      const cls = [isCurrent ? "current" : "", printed === r.number ? "chosen" : ""].join(" ").trim();
      return el("tr", { "data-run": r.number, class: cls || null },
        el("td", {}, `${r.number}${r.partial ? " (partial)" : ""}`),
        el("td", {}, f ? f.best || "–" : r.state, why ? el("div", { class: "why-not-whole" }, why) : null),
        coefCell(f ? f.c3 : null, r.number),
        coefCell(f ? f.c4 : null, r.number),
        el("td", {}, f ? f.health : "–"),
        el("td", {}, show),
        el("td", {}, compare),
        el("td", {}, el("a", { href: r.csv, download: `${id}-run${r.number}.csv` }, "CSV")));
    });
    if (rows.length === 0) rows.push(el("tr", {}, el("td", { colspan: 8 }, "no run yet")));
    $("runs").replaceChildren(...rows);
    // Overlays of runs no longer kept go.
    const kept = new Set(earlier.map((r) => r.number));
    for (const n of Array.from(overlays.keys())) if (!kept.has(n)) overlays.delete(n);
  }

  async function toggleOverlay(n, on) {
    if (!on) { overlays.delete(n); rebuildPlot(); return; }
    try {
      const r = await fetch(`/api/bench/${encodeURIComponent(id)}/runs/${n}`);
      if (!r.ok) return;
      const j = await r.json();
      overlays.set(n, { points: j.points, color: overlayColors[overlays.size % overlayColors.length] });
      rebuildPlot();
      if (detail) showDetail(detail);  // its legend entry
    } catch (e) {
      // the run is gone (no longer kept): nothing to overlay
    }
  }

  // ---- the stream ---------------------------------------------------------------------------
  function showSummary(s) {
    if (s.id !== id) return;
    lastSummary = s;
    if (chosen) setDoubts($("doubts"), chosen.fit, s);
    else showLatestFit();
    head.setAttribute("data-state", s.state);
    setText($("state"), s.state);
    setBridge($("bridge"), s.bridge);
    setText($("bridge-detail"), bridgeDetail(s.bridge));
  }

  function takeSamples(all) {
    const p = (all.benches || {})[id];
    if (!p) return;
    if (p.reset || p.key !== trace.key) trace = { key: p.key, n: 0, x: [], y: [] };
    for (const [x, y] of p.p) {
      trace.x.push(x);
      trace.y.push(y);
    }
    trace.n = p.n;
    plotBox.setAttribute("data-points", String(trace.n));
    if (p.live !== null && p.live !== undefined) setText($("live"), `${p.live.toFixed(2)} ${(detail && detail.unit) || "V"}`);
    dirty = true;
  }

  spindown.live(id, {
    snapshot(d) {
      const s = d.benches.find((b) => b.id === id);
      if (s) showSummary(s);
      else { head.setAttribute("data-state", "silent"); setText($("state"), "not heard yet"); }
      trace = { key: -1, n: 0, x: [], y: [] };
      takeSamples({ benches: d.samples || {} });
      labName = (d.lab && d.lab.name) || "";
      spindown.serverUnits(d.lab ? d.lab.lab_units : undefined);
      showDetail(d.detail || { bench: id, run: null, earlier: [] });
      setText($("connection"), "live");
    },
    bench: showSummary,
    samples: takeSamples,
    detail: showDetail,
  });

  $("print").addEventListener("click", () => window.print());
  $("pause").addEventListener("click", () => {
    paused = !paused;
    if (!paused && rebuildWanted) { rebuildWanted = false; rebuildPlot(); }
    showView();
    dirty = true;
  });
  $("zoom-reset").addEventListener("click", () => { zoomed = false; showView(); if (plot) plot.setData(plotData(), true); });
  spindown.unitsToggle($("units"), () => { if (detail) showExplain(detail.run ? detail.run.explain : null); });
  // The plot as a PNG for the written report: white ground, the record line above it, the legend's
  // names below (the canvas has the curves and axes; the legend is HTML).
  $("png").addEventListener("click", () => {
    if (!plot) return;
    const src = plot.ctx.canvas, pad = 8, line = 22;
    const names = Array.from($("legend").children).map((li) => li.textContent);
    const out = document.createElement("canvas");
    out.width = Math.max(src.width, 800);
    out.height = src.height + 2 * line + pad * 3;
    const c = out.getContext("2d");
    c.fillStyle = "#fff";
    c.fillRect(0, 0, out.width, out.height);
    c.fillStyle = "#000";
    c.font = "15px sans-serif";
    // the plot is the live run's unless a run was chosen: its title then, not the last whole run's record
    const live = !chosen && document.body.hasAttribute("data-fit-of");
    c.fillText(`${id} · ` + (live ? $("run-title").textContent : $("record").textContent || $("run-title").textContent), pad, pad + 14);
    c.drawImage(src, 0, line + pad);
    c.font = "13px sans-serif";
    c.fillText(names.join("   ·   "), pad, line + 2 * pad + src.height + 14);
    const a = el("a", { href: out.toDataURL("image/png"), download: `${id}-run${chosen ? chosen.number : (detail && detail.run ? detail.run.number : 0)}.png` });
    document.body.append(a);
    a.click();
    a.remove();
  });
  const resize = () => { if (plot) plot.setSize(plotSize(plotBox, 340)); if (residualPlot) residualPlot.setSize(plotSize(residualBox, 200, 140)); };
  window.addEventListener("resize", resize);
  window.addEventListener("beforeprint", resize);
  window.addEventListener("afterprint", resize);
  if (window.matchMedia) window.matchMedia("print").addEventListener("change", resize);
  setInterval(() => { if (dirty) redraw(); }, 100);
  redraw();
})();
