// Drives Debian's Chromium (headless, puppeteer-core) through spindown-web while a live lab runs
// (tests/integration/web_browser.sh starts the lab and compares what this records with the LCM log).
//
// Usage: node web_browser.js --url http://127.0.0.1:PORT/ --out DIR --chrome PATH
//          --benches a,b,c --coaster a --replugged b --silent c --runs a=3,b=3,c=1 --ready FILE
// (FILE is made once the room page and the coaster's page are open: then the benches start.)
// Checks, each a line "ok …" or "FAIL …" (exit 1 when any failed):
//   room page: every bench as a tile, the live stream open, no console error, no failed request;
//   bench page: the plot's data-points grow while the bench coasts; the curves and c3/c4 appear
//   with the FIT (the times and values are written to DIR/observed.json for the shell to compare
//   with the FIT messages in the log); the replugged bench's tile says so, the silent one's too;
//   a phone-width viewport shows the page without sideways scrolling; the print layout is one A4
//   page. Screenshots (DIR/*.png, print.pdf) are checked by content: the elements they show and
//   the numbers in them, and the plot's canvas has ink.
"use strict";
const fs = require("fs");
const path = require("path");
const puppeteer = require("puppeteer-core");

const args = {};
for (let i = 2; i < process.argv.length; i += 2) args[process.argv[i].replace(/^--/, "")] = process.argv[i + 1];
const base = args.url;
const out = args.out;
const benches = args.benches.split(",");
const runs = Object.fromEntries(args.runs.split(",").map((kv) => kv.split("=")).map(([k, v]) => [k, Number(v)]));
const states = ["idle", "powered", "coasting", "stopped", "partial", "silent"];
let failures = 0;
const ok = (cond, what) => {
  console.log(`${cond ? "ok" : "FAIL"} ${what}`);
  if (!cond) failures++;
  return cond;
};
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

// Every console error, uncaught exception, failed request and HTTP error of a page.
function watchErrors(page, name, errors) {
  page.on("console", (m) => { if (m.type() === "error") errors.push(`${name}: console: ${m.text()}`); });
  page.on("pageerror", (e) => errors.push(`${name}: exception: ${e.message}`));
  page.on("requestfailed", (r) => {
    // The event stream is cut when the page goes; that is not an error of the page.
    if (!r.url().includes("/events")) errors.push(`${name}: request failed: ${r.url()} ${r.failure() && r.failure().errorText}`);
  });
  page.on("response", (r) => { if (r.status() >= 400) errors.push(`${name}: HTTP ${r.status()} ${r.url()}`); });
}

// In the page from its first script on: every distinct fit shown (bench, run, c3 and c4 as their
// data-si) and when; on a bench page also when its model curves appeared; every change of a
// bench's data-state and bridge field, and of the plot's data-points (window.__timeline).
function recordFits() {
  window.__seen = new Set();
  window.__observed = [];
  window.__timeline = [];
  let last = "";
  const timeline = () => {
    const plot = document.querySelector("[data-plot]");
    const now = {
      tiles: Array.from(document.querySelectorAll("[data-bench]")).map((t) => [t.getAttribute("data-bench"), t.getAttribute("data-state"),
        (t.querySelector('[data-field="bridge"]') || document.querySelector('[data-field="bridge"]') || {}).textContent]),
      points: plot ? Number(plot.getAttribute("data-points")) : null,
    };
    const j = JSON.stringify(now);
    if (j !== last) { last = j; window.__timeline.push({ t_ms: Date.now(), ...now }); }
  };
  const scan = () => {
    timeline();
    for (const c3 of document.querySelectorAll('[data-field="c3"][data-si]')) {
      const holder = c3.closest("[data-bench]") || document.querySelector("header[data-bench]");
      const scope = c3.closest("[data-bench]") || document;
      const c4 = scope.querySelector('[data-field="c4"][data-si]');
      const bench = holder ? holder.getAttribute("data-bench") : "?";
      const run = c3.getAttribute("data-fit-run");
      const curves = document.querySelectorAll("[data-curve]").length;
      const key = [bench, run, c3.getAttribute("data-si"), c4 && c4.getAttribute("data-si"), curves >= 3].join("|");
      if (window.__seen.has(key)) continue;
      window.__seen.add(key);
      window.__observed.push({ t_ms: Date.now(), bench, run: Number(run), c3: c3.getAttribute("data-si"),
                               c4: c4 ? c4.getAttribute("data-si") : null, curves });
    }
  };
  new MutationObserver(scan).observe(document, { subtree: true, childList: true, attributes: true,
                                                 attributeFilter: ["data-si", "data-fit-run", "data-curve"] });
}

async function canvasInk(page, selector) {
  return page.evaluate((sel) => {
    const c = document.querySelector(sel);
    if (!c) return 0;
    const g = c.getContext("2d");
    const d = g.getImageData(0, 0, c.width, c.height).data;
    let ink = 0;
    for (let i = 0; i < d.length; i += 4) if (d[i + 3] > 0 && (d[i] < 200 || d[i + 1] < 200 || d[i + 2] < 200)) ink++;
    return ink;
  }, selector);
}

async function tiles(page) {
  return page.evaluate(() => Array.from(document.querySelectorAll("[data-bench]")).map((t) => ({
    id: t.getAttribute("data-bench"), state: t.getAttribute("data-state"),
    bridge: (t.querySelector('[data-field="bridge"]') || {}).textContent,
    c3: (t.querySelector('[data-field="c3"]') || {}).textContent,
    c3si: t.querySelector('[data-field="c3"]') ? t.querySelector('[data-field="c3"]').getAttribute("data-si") : null,
    health: (t.querySelector('[data-field="health"]') || {}).textContent,
  })));
}

async function state() {
  const r = await fetch(base + "api/state");
  return r.json();
}

async function waitFor(what, cond, seconds) {
  const until = Date.now() + seconds * 1000;
  while (Date.now() < until) {
    try { if (await cond()) return true; } catch (e) { /* the page is busy; again */ }
    await sleep(200);
  }
  return ok(false, `${what} within ${seconds} s`);
}

(async () => {
  fs.mkdirSync(out, { recursive: true });
  const browser = await puppeteer.launch({
    executablePath: args.chrome, headless: true,
    args: ["--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--no-first-run", "--no-default-browser-check",
           "--disable-extensions", "--no-proxy-server", "--disable-background-timer-throttling",
           "--disable-renderer-backgrounding", "--disable-backgrounding-occluded-windows"],
  });
  const errors = [];
  try {
    // ---- the room page, open from the start -------------------------------------------------
    const room = await browser.newPage();
    await room.setViewport({ width: 1280, height: 800 });
    watchErrors(room, "room", errors);
    await room.evaluateOnNewDocument(recordFits);
    await room.goto(base, { waitUntil: "load" });
    await waitFor("the room page connected", () => room.$eval("body", (b) => b.getAttribute("data-connected") === "true"), 20);
    // ---- a bench page, open from the start too ----------------------------------------------
    const coaster = args.coaster;
    const bench = await browser.newPage();
    await bench.setViewport({ width: 1280, height: 900 });
    watchErrors(bench, "bench", errors);
    await bench.evaluateOnNewDocument(recordFits);
    await bench.goto(`${base}bench/${coaster}`, { waitUntil: "load" });
    await waitFor("the bench page connected", () => bench.$eval("body", (b) => b.getAttribute("data-connected") === "true"), 20);
    fs.writeFileSync(args.ready, String(Date.now()));

    await waitFor("a tile for every bench", async () => {
      const ids = (await tiles(room)).map((t) => t.id);
      return benches.every((b) => ids.includes(b));
    }, 40);
    const first = await tiles(room);
    ok(benches.every((b) => first.some((t) => t.id === b)), `room page lists every bench: ${first.map((t) => `${t.id}=${t.state}`).join(" ")}`);
    ok(first.every((t) => states.includes(t.state)), "every tile's data-state is one of " + states.join("/"));

    // ---- the bench page: the curve grows while the bench coasts -----------------------------
    const coasting = () => bench.$eval("header[data-bench]", (h) => h.getAttribute("data-state") === "coasting");
    if (await waitFor(`${coaster} coasting`, coasting, 60)) {
      await sleep(700);
      if (await coasting()) {
        ok(await canvasInk(bench, "[data-plot] canvas") > 500, "the live plot's canvas has the readings drawn while it coasts");
        await bench.screenshot({ path: path.join(out, "bench-coasting.png") });
        // Paused, the plot keeps what it showed while the readings go on arriving; resumed, it catches up.
        const view = () => bench.$eval("[data-plot]", (p) => ({ view: p.getAttribute("data-view"), drawn: Number(p.getAttribute("data-drawn")),
                                                               points: Number(p.getAttribute("data-points")) }));
        // (On a loaded machine the coast may end before readings arrive in the pause: then again on
        // the bench's next coast, at most twice.)
        let p0 = null, p1 = null;
        for (let attempt = 0; attempt < 2; ++attempt) {
          if (attempt > 0 && !(await waitFor(`${coaster} coasting again`, coasting, 60))) break;
          await bench.click("#pause");
          p0 = await view();
          await sleep(1200);
          p1 = await view();
          await bench.click("#pause");
          if (p1.points > p0.points) break;
        }
        ok(p0 && p0.view === "paused" && p1.drawn === p0.drawn && p1.points > p0.points,
           `paused, the live plot held ${p0 && p0.drawn} readings while ${p1 && p1.points - p0.points} more arrived`);
        const caught = await waitFor("the plot caught up after resume", async () => { const v = await view(); return v.view === "live" && v.drawn >= p1.points; }, 5);
        if (caught) ok(true, "resumed, the plot caught up with the readings");
      }
    }
    // Its first fit: the curves, the markers, the residuals, the explain story.
    await waitFor(`${coaster}'s first fit on its page`, () => bench.$$eval("[data-curve]", (c) => c.length === 3), 90);
    await waitFor(`${coaster}'s cut and stop marked`, () => bench.$$eval("[data-marker]", (m) => m.map((x) => x.getAttribute("data-marker")).join() === "cut,stop"), 5);
    await waitFor(`${coaster}'s explain story`, () => bench.$eval("#explain-final", (e) => /missing by|noise/.test(e.textContent)), 20);
    ok(await bench.$$eval("[data-explain-step]", (s) => s.length === 1 && s[0].getAttribute("data-explain-step") === "coulomb"),
       `the explain story: one step, adding coulomb (the virtual bench's friction is viscous + Coulomb, the base viscous)`);
    // … told in a student's words: what was added, how much closer the model came, where it missed;
    // the statistics (ΔBIC, n_eff) only behind "the statistics".
    const words = await bench.$eval("[data-explain-step] .step-words", (e) => e.textContent);
    const where = words.match(/from (-?[\d.]+) to (-?[\d.]+) s after the cut/);
    const coastS = await bench.$eval('[data-marker="stop"]', (e) => parseFloat(e.textContent.match(/\(([\d.]+) s after/)[1]));
    ok(/Adding dry \(Coulomb\) friction/.test(words) && /× closer/.test(words) && where && +where[1] >= -0.5 && +where[2] <= coastS + 5 &&
       !/BIC|n_eff/.test(words),
       `the step in words: "${words.slice(0, 160)}…"`);
    const fitView = await bench.evaluate(() => ({
      c3: document.querySelector('[data-field="c3"]').textContent, c3si: document.querySelector('[data-field="c3"]').getAttribute("data-si"),
      c4: document.querySelector('[data-field="c4"]').textContent, c4si: document.querySelector('[data-field="c4"]').getAttribute("data-si"),
      residuals: Number(document.querySelector("[data-residuals]").getAttribute("data-count")),
      csv: document.querySelector('a[data-download="csv"]').getAttribute("href"),
      points: Number(document.querySelector("[data-plot]").getAttribute("data-points")),
    }));
    // The text is the SI value in the lab's units (×1e7) to the digits its error gives.
    const lab = (t) => parseFloat(t.replace(/[()]/g, ""));
    ok(Math.abs(lab(fitView.c3) - 1e7 * Number(fitView.c3si)) <= 0.02 * Math.abs(1e7 * Number(fitView.c3si)) &&
       fitView.c3.includes("±") && fitView.c3.includes("g·cm²"), `c3 shown in lab units with its error: "${fitView.c3}" (SI ${fitView.c3si})`);
    ok(Math.abs(lab(fitView.c4) - 1e7 * Number(fitView.c4si)) <= 0.02 * Math.abs(1e7 * Number(fitView.c4si)) &&
       fitView.c4.includes("±"), `c4 shown in lab units with its error: "${fitView.c4}" (SI ${fitView.c4si})`);
    ok(fitView.residuals > 100, `residuals drawn: ${fitView.residuals} points`);
    ok(await canvasInk(bench, "[data-residuals] canvas") > 200, "the residual plot's canvas has the points drawn");
    // data-points grew while the header said coasting (from the page's own record).
    const tl = await bench.evaluate(() => window.__timeline);
    let grew = 0, coastingRecords = 0;
    for (let i = 1; i < tl.length; i++) {
      const was = tl[i - 1].tiles.find(([id]) => id === coaster), is = tl[i].tiles.find(([id]) => id === coaster);
      if (was && is && was[1] === "coasting" && is[1] === "coasting") {
        coastingRecords++;
        if (tl[i].points > tl[i - 1].points) grew++;
      }
    }
    ok(grew >= 5, `${coaster}'s curve gains points while it coasts: data-points rose ${grew} times in ${coastingRecords} changes seen coasting`);
    // The CSV: a header and the run's samples, as many as the plot counts.
    const csv = await (await fetch(new URL(fitView.csv, base))).text();
    const rows = csv.trim().split("\n");
    ok(rows[0] === "t_s,value" && rows.length - 1 === fitView.points && rows.slice(1).every((r) => /^[-0-9.e]+,[-0-9.e]+$/.test(r)),
       `the run's CSV: header and ${rows.length - 1} rows (the plot counts ${fitView.points})`);
    await bench.screenshot({ path: path.join(out, "bench-fitted.png"), fullPage: true });
    // The residuals on a scale with numbers: in mV (a few mV off), several ticks, symmetric about 0.
    const resAxis = await bench.$eval("[data-residuals]", (r) => ({ ticks: (r.getAttribute("data-y-ticks") || "").split(",").filter((x) => x !== "").map(Number),
                                                                     label: r.getAttribute("data-unit") }));
    ok(resAxis.ticks.length >= 3 && resAxis.ticks.some((t) => t < 0) && resAxis.ticks.some((t) => t > 0) && /mV/.test(resAxis.label),
       `the residual plot's scale: ticks ${resAxis.ticks.join(", ")} mV`);
    // Zoom: a box dragged on the plot narrows both axes; a double-click shows the whole run again.
    // Paused first, so that the bench's next run (it goes on) does not replace what is zoomed.
    await bench.click("#pause");
    const range = () => bench.$eval("[data-plot]", (p) => ({ view: p.getAttribute("data-view"), zoomed: p.getAttribute("data-zoomed") === "true", x: p.getAttribute("data-x").split(",").map(Number),
                                                             y: p.getAttribute("data-y").split(",").map(Number) }));
    const whole = await range();
    const over = await bench.$eval("[data-plot] .u-over", (o) => { const b = o.getBoundingClientRect(); return { x: b.x, y: b.y, w: b.width, h: b.height }; });
    await bench.mouse.move(over.x + 0.3 * over.w, over.y + 0.2 * over.h);
    await bench.mouse.down();
    await bench.mouse.move(over.x + 0.5 * over.w, over.y + 0.5 * over.h, { steps: 8 });
    await bench.mouse.move(over.x + 0.6 * over.w, over.y + 0.7 * over.h, { steps: 8 });
    await bench.mouse.up();
    await sleep(300);
    const zoomedIn = await range();
    ok(zoomedIn.zoomed && zoomedIn.x[1] - zoomedIn.x[0] < 0.5 * (whole.x[1] - whole.x[0]) &&
       zoomedIn.y[1] - zoomedIn.y[0] < 0.7 * (whole.y[1] - whole.y[0]),
       `a box dragged zooms both axes: x ${whole.x.map((v) => v.toFixed(1))} → ${zoomedIn.x.map((v) => v.toFixed(1))}, ` +
       `y ${whole.y.map((v) => v.toFixed(2))} → ${zoomedIn.y.map((v) => v.toFixed(2))}`);
    await sleep(1000);  // readings arriving meanwhile keep the view
    ok((await range()).x[0] === zoomedIn.x[0], "the zoomed view stays while readings arrive");
    await bench.mouse.click(over.x + 0.5 * over.w, over.y + 0.5 * over.h, { clickCount: 2 });
    await sleep(300);
    const back = await range();
    ok(!back.zoomed && back.x[1] - back.x[0] >= 0.9 * (whole.x[1] - whole.x[0]), `double-click: the whole run again (x ${back.x.map((v) => v.toFixed(1))})`);
    await bench.click("#pause");
    // The units toggle: SI on a click (the same number, data-si unchanged), the lab's units back on the next.
    const c3Lab = await bench.$eval('[data-field="c3"]', (e) => [e.textContent, e.getAttribute("data-si")]);
    await bench.click("#units");
    const c3Si = await bench.$eval('[data-field="c3"]', (e) => [e.textContent, e.getAttribute("data-si")]);
    const siText = await bench.$eval("#explain-final", (e) => e.textContent);
    ok(/N·m/.test(c3Si[0]) && !/g·cm/.test(c3Si[0]) && c3Si[1] === c3Lab[1] && !/g·cm/.test(siText),
       `units toggle: c3 "${c3Lab[0]}" → "${c3Si[0]}" (explain's numbers too)`);
    await bench.click("#units");
    ok((await bench.$eval('[data-field="c3"]', (e) => e.textContent)) === c3Lab[0], "units toggle back: the lab's units again");

    // The coaster's last run fitted, with the earlier ones in its table (the README's picture).
    if (await waitFor(`${coaster}'s run ${runs[coaster]} fitted on its page`, () => bench.$eval('[data-field="c3"]',
      (e, n) => Number(e.getAttribute("data-fit-run")) === n, runs[coaster]), 120)) {
      await sleep(400);
      ok(await bench.$$eval("[data-run]", (r) => r.map((x) => x.getAttribute("data-run")).join()) ===
         Array.from({ length: runs[coaster] }, (_, i) => runs[coaster] - i).join(), "the session's runs listed, newest first");
      await bench.screenshot({ path: path.join(out, "bench-final.png"), fullPage: true });
    }

    // ---- the replugged and the silent bench on the room page ---------------------------------
    await room.bringToFront();
    const seenOnRoom = async (pred) => (await room.evaluate(() => window.__timeline)).find((r) => r.tiles.some(pred));
    if (await waitFor(`${args.replugged}'s tile says replugged`, async () =>
      !!(await seenOnRoom(([id, , bridge]) => id === args.replugged && bridge === "replugged")), 90)) {
      const r = await seenOnRoom(([id, , bridge]) => id === args.replugged && bridge === "replugged");
      ok(true, `${args.replugged}'s tile said "replugged" (at ${new Date(r.t_ms).toISOString()})`);
    }
    if (await waitFor(`${args.silent}'s tile says silent`, async () =>
      !!(await seenOnRoom(([id, state, bridge]) => id === args.silent && state === "silent" && bridge === "silent")), 90)) {
      // The other benches ran on meanwhile: a moment when only the one whose bench ended was silent.
      // (Another bench may be silent for its own reason at the same moment, e.g. its cable pulled
      // while the machine is loaded; it comes back, and then the ended bench is silent alone.)
      const alone = (r) => r.tiles.length === benches.length && r.tiles.every(([id, state]) => (id === args.silent) === (state === "silent"));
      if (await waitFor(`${args.silent}'s tile silent alone while the others run (timeline: ${args.silent} silent first with ` +
                        JSON.stringify(((await seenOnRoom(([id, state]) => id === args.silent && state === "silent")) || {}).tiles) + ")",
                        async () => (await room.evaluate(() => window.__timeline)).some(alone), 30)) {
        const r = (await room.evaluate(() => window.__timeline)).find(alone);
        ok(true, `${args.silent}'s tile said silent (its bench ended) while the others ran: ${JSON.stringify(r.tiles)}`);
      }
    }
    // Every bench's last run fitted (the room then shows every FIT).
    await waitFor("every bench's runs fitted", async () => {
      const s = await state();
      return benches.every((b) => { const x = s.benches.find((y) => y.id === b); return x && x.last_fit && x.last_fit.run >= runs[b]; });
    }, 150);
    await sleep(500);
    const end = await tiles(room);
    for (const t of end)
      ok(t.c3si !== null && /±/.test(t.c3) && ["ok", "check", "service", "not judged"].includes(t.health),
         `tile ${t.id}: c3 "${t.c3}", health "${t.health}", bridge "${t.bridge}", state ${t.state}`);
    await room.screenshot({ path: path.join(out, "room.png") });
    ok(await canvasInk(room, `[data-bench="${coaster}"] canvas`) > 200, "the room tile's curve is drawn");

    // ---- a phone ----------------------------------------------------------------------------
    const phone = await browser.newPage();
    watchErrors(phone, "phone", errors);
    await phone.setViewport({ width: 390, height: 844, isMobile: true, hasTouch: true, deviceScaleFactor: 2 });
    await phone.goto(`${base}bench/${coaster}`, { waitUntil: "load" });
    await waitFor("the phone's bench page shows the fit", () => phone.$$eval("[data-curve]", (c) => c.length === 3), 20);
    await sleep(300);
    const fits = await phone.evaluate(() => {
      const inside = (sel) => { const e = document.querySelector(sel); if (!e) return false; const r = e.getBoundingClientRect(); return r.width > 0 && r.left >= -1 && r.right <= innerWidth + 1; };
      return { scroll: document.documentElement.scrollWidth, width: innerWidth,
               plot: inside("[data-plot]"), c3: inside('[data-field="c3"]'), c4: inside('[data-field="c4"]'), csv: inside('a[data-download="csv"]'),
               csvHeight: document.querySelector('a[data-download="csv"]').getBoundingClientRect().height };
    });
    ok(fits.scroll <= fits.width + 1 && fits.plot && fits.c3 && fits.c4 && fits.csv && fits.csvHeight >= 24,
       `phone (390 px): no sideways scrolling (${fits.scroll} px wide), plot, c3, c4 and the CSV link on screen`);
    await phone.screenshot({ path: path.join(out, "phone-bench.png") });
    await phone.goto(base, { waitUntil: "load" });
    await waitFor("the phone's room page", async () => (await tiles(phone)).length >= benches.length, 20);
    const roomFits = await phone.evaluate(() => ({ scroll: document.documentElement.scrollWidth, width: innerWidth }));
    ok(roomFits.scroll <= roomFits.width + 1, `phone room page: no sideways scrolling (${roomFits.scroll} px)`);
    await phone.screenshot({ path: path.join(out, "phone-room.png") });

    // ---- print: one A4 page with the plot and the numbers --------------------------------------
    await bench.bringToFront();
    await bench.emulateMediaType("print");
    await bench.evaluate(() => window.dispatchEvent(new Event("beforeprint")));
    await sleep(300);
    const printed = await bench.evaluate(() => {
      const shown = (sel) => { const e = document.querySelector(sel); return !!e && getComputedStyle(e).display !== "none" && e.getBoundingClientRect().height > 0; };
      return { plot: shown("[data-plot] canvas"), c3: shown('[data-field="c3"]'), nav: shown(".nav"), button: shown("#print"),
               c3text: document.querySelector('[data-field="c3"]').textContent };
    });
    ok(printed.plot && printed.c3 && !printed.nav && !printed.button, `print layout: plot and c3 (${printed.c3text}) shown, controls hidden`);
    const pdf = await bench.pdf({ path: path.join(out, "print.pdf"), format: "A4", printBackground: false });
    const pages = (Buffer.from(pdf).toString("latin1").match(/\/Type\s*\/Page[^s]/g) || []).length;
    ok(pages === 1, `the print layout fits one A4 page (${pages} page(s))`);
    await bench.screenshot({ path: path.join(out, "print.png"), fullPage: true });
    await bench.emulateMediaType("screen");

    // ---- what was seen, for the comparison with the FIT messages --------------------------------
    const observed = [];
    for (const [name, p] of [["room", room], ["bench", bench]])
      for (const o of await p.evaluate(() => window.__observed)) observed.push({ page: name, ...o });
    fs.writeFileSync(path.join(out, "observed.json"), JSON.stringify(observed, null, 1));
    const s = await state();
    fs.writeFileSync(path.join(out, "state.json"), JSON.stringify(s, null, 1));
  } catch (e) {
    ok(false, `the browser test broke: ${e.stack || e}`);
  } finally {
    ok(errors.length === 0, `no console errors, exceptions or failed requests${errors.length ? ":\n  " + errors.join("\n  ") : ""}`);
    await browser.close();
  }
  process.exit(failures ? 1 : 0);
})();
