// issue 34 held-out: the browser side. Runs INSIDE the runner's network namespace (lab.sh).
// Drives Debian's Chromium with puppeteer-core (NODE_PATH=$SPINDOWN_NODE_MODULES), records what
// the pages show with timestamps (Date.now(), the same CLOCK_REALTIME as the LCM log's event
// times), kills and restarts one bridge, takes the final looks (projector, phone, print, CSV,
// /api/state, /events) and writes everything to $OUT/obs.json. It judges nothing: judge.py does.
'use strict';
const fs = require('fs');
const path = require('path');
const http = require('http');
const { spawn } = require('child_process');

let puppeteer;
try { puppeteer = require('puppeteer-core'); } catch (e) {
  fs.writeFileSync(path.join(process.env.OUT, 'obs.json'), JSON.stringify({ fatal: 'puppeteer-core not found in NODE_PATH=' + process.env.NODE_PATH + ': ' + e.message }));
  process.exit(3);
}

const WEB = process.env.WEB;                 // http://127.0.0.1:PORT
const OUT = process.env.OUT;                 // scratch dir (artifacts)
const BENCHES = process.env.BENCHES.split(',');
const LIVE_BENCH_PAGES = process.env.LIVE_BENCH_PAGES.split(',');
const KILL_BENCH = process.env.KILL_BENCH;
const KILL_AT = Number(process.env.KILL_AT_MS || 0);  // set later via file (T0 known only after start)
const BRIDGE_PIDFILE = process.env.BRIDGE_PIDFILE;   // pid of KILL_BENCH's bridge
const RESTART_CMD = JSON.parse(process.env.RESTART_CMD || '[]');
const PIDS = process.env.PIDS;               // file the runner's trap reads
const SCHEDULE = process.env.SCHEDULE;       // JSON written by lab.sh once the benches started
const READY = process.env.READY;             // we touch it when the pages are open
const HARD_DEADLINE = Date.now() + Number(process.env.NODE_BUDGET_MS || 200000);

const obs = { web: WEB, pages: {}, console: [], pageerrors: [], requests: [], responses: [], requestfailed: [],
  navigations: {}, events: [], final: {}, notes: [] };
let closing = false;
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
const now = () => Date.now();
function note(s) { obs.notes.push([now(), s]); }
function save() { fs.writeFileSync(path.join(OUT, 'obs.json'), JSON.stringify(obs)); }
function withTimeout(p, ms, what) {
  return Promise.race([p, new Promise((_, rej) => setTimeout(() => rej(new Error('timeout ' + ms + ' ms: ' + what)), ms))]);
}
setTimeout(() => { note('hard deadline hit'); save(); process.exit(4); }, HARD_DEADLINE - Date.now()).unref();

// In-page recorder: a snapshot of the contract's DOM facts whenever the DOM changes (MutationObserver,
// coalesced in a microtask) and every 250 ms, stored only when different, with Date.now().
const RECORDER = `(() => {
  if (window.__sdRec) return; window.__sdRec = true; window.__obs = []; window.__obsTaken = 0;
  const attr = (el, sel, a) => { const x = el && el.querySelector(sel); return x ? x.getAttribute(a) : null; };
  const txt = (el, sel) => { const x = el && el.querySelector(sel); return x ? x.textContent.replace(/\\s+/g, ' ').trim() : null; };
  const own = (sel) => [...document.querySelectorAll(sel)].filter(e => !e.closest('[data-run]'))[0] || null;
  function snap() {
    const b = document.body; if (!b) return null;
    const o = { connected: b.getAttribute('data-connected') };
    o.tiles = [...document.querySelectorAll('[data-bench]')].map(el => ({ id: el.getAttribute('data-bench'),
      state: el.getAttribute('data-state'), c3: attr(el, '[data-field="c3"]', 'data-si'), c4: attr(el, '[data-field="c4"]', 'data-si'),
      best: txt(el, '[data-field="best"]'), health: txt(el, '[data-field="health"]'), bridge: txt(el, '[data-field="bridge"]') }));
    const p = document.querySelector('[data-plot]');
    o.points = p ? p.getAttribute('data-points') : null;
    const c3 = own('[data-field="c3"]'), c4 = own('[data-field="c4"]');
    o.c3 = c3 ? c3.getAttribute('data-si') : null; o.c4 = c4 ? c4.getAttribute('data-si') : null;
    o.cut = !!document.querySelector('[data-marker="cut"]'); o.stop = !!document.querySelector('[data-marker="stop"]');
    o.curves = ['viscous', 'coulomb', 'combined'].filter(k => document.querySelector('[data-curve="' + k + '"]'));
    o.residuals = !!document.querySelector('[data-residuals]');
    o.steps = document.querySelectorAll('[data-explain-step]').length;
    o.runs = [...document.querySelectorAll('[data-run]')].map(e => e.getAttribute('data-run'));
    return o;
  }
  let last = '', pending = false;
  function rec() { pending = false; const s = snap(); if (!s) return; const j = JSON.stringify(s);
    if (j !== last) { last = j; window.__obs.push([Date.now(), s]); } }
  function kick() { if (!pending) { pending = true; Promise.resolve().then(rec); } }
  function start() { new MutationObserver(kick).observe(document.documentElement, { subtree: true, childList: true, attributes: true, characterData: true }); setInterval(rec, 250); rec(); }
  if (document.documentElement) start(); else document.addEventListener('DOMContentLoaded', start);
  window.__sdTake = () => { const r = window.__obs.slice(window.__obsTaken); window.__obsTaken = window.__obs.length; return r; };
})();`;

function hostOk(u) {
  if (u.startsWith('data:') || u.startsWith('blob:') || u.startsWith('about:')) return true;
  try { return new URL(u).hostname === '127.0.0.1'; } catch (e) { return false; }
}

async function openPage(browser, name, url, viewport, opts = {}) {
  const page = await browser.newPage();
  obs.pages[name] = obs.pages[name] || { url, snaps: [] };
  obs.navigations[name] = 0;
  page.on('console', (m) => { if (m.type() === 'error') obs.console.push({ page: name, t: now(), closing, text: m.text(), loc: m.location() && m.location().url }); });
  page.on('pageerror', (e) => obs.pageerrors.push({ page: name, t: now(), closing, text: String(e && e.message || e) }));
  page.on('request', (r) => obs.requests.push({ page: name, t: now(), url: r.url(), type: r.resourceType(), closing }));
  page.on('response', (r) => obs.responses.push({ page: name, t: now(), url: r.url(), status: r.status(), ctype: (r.headers()['content-type'] || ''), closing }));
  page.on('requestfailed', (r) => obs.requestfailed.push({ page: name, t: now(), url: r.url(), type: r.resourceType(), err: r.failure() && r.failure().errorText, closing }));
  page.on('framenavigated', (f) => { if (f === page.mainFrame()) obs.navigations[name] += 1; });
  await page.setViewport(viewport);
  if (opts.record) await page.evaluateOnNewDocument(RECORDER);
  let loadErr = null;
  try { await page.goto(url, { waitUntil: 'load', timeout: 10000 }); } catch (e) { loadErr = String(e.message); }
  obs.pages[name].load_error = loadErr;
  return page;
}

async function take(page, name) {
  try {
    const r = await withTimeout(page.evaluate(() => (window.__sdTake ? window.__sdTake() : [])), 5000, 'take ' + name);
    obs.pages[name].snaps.push(...r);
  } catch (e) { note('take ' + name + ': ' + e.message); }
}

async function waitFor(page, fn, arg, ms) {
  try { await page.waitForFunction(fn, { timeout: ms, polling: 100 }, arg); return true; } catch (e) { return false; }
}

// DOM facts of a page at the moment of a screenshot: what the artifact shows, element by element.
async function facts(page) {
  return withTimeout(page.evaluate(() => {
    const fontMax = (el) => { let m = 0; const w = document.createTreeWalker(el, NodeFilter.SHOW_TEXT);
      for (let n = w.nextNode(); n; n = w.nextNode()) { if (n.textContent.trim() && n.parentElement) m = Math.max(m, parseFloat(getComputedStyle(n.parentElement).fontSize)); }
      return m || parseFloat(getComputedStyle(el).fontSize); };
    const vis = (el) => { if (!el) return null; const r = el.getBoundingClientRect(); const cs = getComputedStyle(el);
      let op = 1; for (let e = el; e && e.nodeType === 1; e = e.parentElement) op *= Number(getComputedStyle(e).opacity);
      return { x: r.left, y: r.top, w: r.width, h: r.height, right: r.right, bottom: r.bottom, display: cs.display,
        visibility: cs.visibility, opacity: op, font_px: fontMax(el), text: el.textContent.replace(/\s+/g, ' ').trim(),
        si: el.getAttribute('data-si') }; };
    const own = (sel) => [...document.querySelectorAll(sel)].filter(e => !e.closest('[data-run]'))[0] || null;
    const se = document.scrollingElement || document.documentElement;
    const tiles = [...document.querySelectorAll('[data-bench]')].map(el => ({ id: el.getAttribute('data-bench'), state: el.getAttribute('data-state'),
      box: vis(el), c3: vis(el.querySelector('[data-field="c3"]')), c4: vis(el.querySelector('[data-field="c4"]')),
      best: vis(el.querySelector('[data-field="best"]')), health: vis(el.querySelector('[data-field="health"]')),
      doubts: vis(el.querySelector('[data-field="doubts"]')), bridge: vis(el.querySelector('[data-field="bridge"]')) }));
    let printRule = false;
    for (const sh of [...document.styleSheets]) {
      try { if (sh.media && [...sh.media].some(m => /print/i.test(m))) printRule = true;
        for (const r of [...sh.cssRules]) { if (r.media && /print/i.test(r.media.mediaText)) printRule = true; } } catch (e) { }
    }
    const a = document.querySelector('a[data-download="csv"]');
    const assets = [...document.querySelectorAll('script[src],link[href],img[src],iframe[src],source[src],video[src],audio[src],embed[src],object[data]')]
      .map(e => ({ tag: e.tagName.toLowerCase(), rel: e.getAttribute('rel'), url: e.src || e.href || e.data }));
    const res = performance.getEntriesByType('resource').map(e => ({ url: e.name, type: e.initiatorType }));
    return { t: Date.now(), vw: innerWidth, vh: innerHeight, scrollWidth: se.scrollWidth, scrollHeight: se.scrollHeight, clientWidth: se.clientWidth,
      connected: document.body.getAttribute('data-connected'), tiles, c3: vis(own('[data-field="c3"]')), c4: vis(own('[data-field="c4"]')),
      plot: vis(document.querySelector('[data-plot]')), points: (document.querySelector('[data-plot]') || { getAttribute: () => null }).getAttribute('data-points'),
      steps: [...document.querySelectorAll('[data-explain-step]')].map(e => e.textContent.replace(/\s+/g, ' ').trim()),
      runs: [...document.querySelectorAll('[data-run]')].map(e => e.getAttribute('data-run')),
      csv_href: a ? a.href : null, csv_attr: a ? a.getAttribute('href') : null,
      curves: ['viscous', 'coulomb', 'combined'].filter(k => document.querySelector('[data-curve="' + k + '"]')),
      cut: !!document.querySelector('[data-marker="cut"]'), stop: !!document.querySelector('[data-marker="stop"]'),
      residuals: !!document.querySelector('[data-residuals]'), printRule, assets, resources: res,
      html_len: document.documentElement.outerHTML.length };
  }), 10000, 'facts');
}

function httpGet(url, ms, maxBytes) {   // raw GET: status, headers, first bytes within ms
  return new Promise((resolve) => {
    const t0 = now(); let body = Buffer.alloc(0); let done = false; let firstData = null;
    const fin = (extra) => { if (done) return; done = true; try { req.destroy(); } catch (e) { }
      resolve(Object.assign({ ms: now() - t0, body: body.toString('utf8'), first_data_ms: firstData }, extra)); };
    const req = http.get(url, (res) => {
      const head = { status: res.statusCode, ctype: res.headers['content-type'] || '', headers_ms: now() - t0 };
      res.on('data', (c) => { if (firstData === null) firstData = now() - t0; body = Buffer.concat([body, c]); if (body.length >= maxBytes) fin(head); });
      res.on('end', () => fin(Object.assign({ ended: true }, head)));
      setTimeout(() => fin(head), ms);
    });
    req.on('error', (e) => fin({ error: String(e.message) }));
    setTimeout(() => fin({ error: 'no response in ' + ms + ' ms' }), ms + 200);
  });
}

function readSchedule() { try { return JSON.parse(fs.readFileSync(SCHEDULE, 'utf8')); } catch (e) { return null; } }

async function main() {
  const udd = fs.mkdtempSync(path.join(OUT, 'chromium-profile-'));
  const browser = await puppeteer.launch({
    executablePath: '/usr/bin/chromium', headless: true, dumpio: false, protocolTimeout: 30000,
    args: ['--headless=new', '--no-sandbox', '--disable-gpu', '--disable-dev-shm-usage', '--no-first-run',
      '--disable-background-networking', '--disable-component-update', '--disable-sync', '--user-data-dir=' + udd,
      '--disable-background-timer-throttling', '--disable-renderer-backgrounding', '--disable-backgrounding-occluded-windows'],
  });
  const bp = browser.process();
  if (bp && bp.pid) fs.appendFileSync(PIDS, 'pgid:' + bp.pid + '\n');
  obs.browser_version = await browser.version();

  // The live pages: the projector's room page and the students' bench pages, open for the whole session.
  const live = {};
  live.room = await openPage(browser, 'room', WEB + '/', { width: 1920, height: 1080 }, { record: true });
  for (const b of LIVE_BENCH_PAGES) live['bench:' + b] = await openPage(browser, 'bench:' + b, WEB + '/bench/' + b, { width: 1280, height: 800 }, { record: true });
  for (const [n, p] of Object.entries(live)) obs.pages[n].connected_ms = (await waitFor(p, () => document.body && document.body.getAttribute('data-connected') === 'true', null, 5000)) ? 'yes' : 'no';
  fs.writeFileSync(READY, String(now()));
  obs.events.push(['pages_ready', now()]);

  // Wait for the schedule (written by lab.sh when the benches started).
  let sch = null;
  for (let i = 0; i < 300 && !sch; i++) { sch = readSchedule(); if (!sch) await sleep(100); }
  if (!sch) { note('no schedule from lab.sh'); save(); await browser.close(); return; }
  obs.schedule = sch;

  const pull = async () => { for (const [n, p] of Object.entries(live)) await take(p, n); save(); };
  const roomTile = async (id) => { try { return await withTimeout(live.room.evaluate((id) => {
    const el = document.querySelector('[data-bench="' + id + '"]'); if (!el) return null;
    const br = el.querySelector('[data-field="bridge"]');
    return { state: el.getAttribute('data-state'), bridge: br ? br.textContent.trim() : null }; }, id), 3000, 'tile'); } catch (e) { return null; } };

  // Until the kill: observe.
  while (now() < sch.kill_at_ms) { await sleep(Math.min(2000, Math.max(10, sch.kill_at_ms - now()))); await pull(); }

  // A bridge killed (SIGKILL: a crashed bridge, no goodbye), then restarted.
  let bpid = null; try { bpid = Number(fs.readFileSync(BRIDGE_PIDFILE, 'utf8').trim()); } catch (e) { }
  if (bpid) { try { process.kill(bpid, 'SIGKILL'); obs.events.push(['bridge_killed', now(), KILL_BENCH, bpid]); } catch (e) { note('kill bridge: ' + e.message); } }
  else note('no bridge pid for ' + KILL_BENCH);
  let seenSilent = null; const tk = now();
  while (now() - tk < 15000) { const t = await roomTile(KILL_BENCH); if (t && t.state === 'silent') { seenSilent = now(); break; } await sleep(100); }
  obs.events.push(['silent_seen', seenSilent]);
  await sleep(seenSilent ? 1500 : 0);          // let the bridge field follow
  await pull();
  if (RESTART_CMD.length) {
    const out = fs.openSync(path.join(OUT, 'bridge-' + KILL_BENCH + '-restarted.err'), 'a');
    const ch = spawn(RESTART_CMD[0], RESTART_CMD.slice(1), { stdio: ['ignore', out, out], detached: false });
    fs.appendFileSync(PIDS, ch.pid + '\n');
    obs.events.push(['bridge_restarted', now(), KILL_BENCH, ch.pid]);
    const tr = now(); let back = null;
    while (now() - tr < 15000) { const t = await roomTile(KILL_BENCH); if (t && t.state && t.state !== 'silent' && !/silent/i.test(t.bridge || '')) { back = now(); break; } await sleep(100); }
    obs.events.push(['back_seen', back]);
  }

  // Observe until the schedule's end (both live benches' second FITs are due before it).
  while (now() < sch.end_at_ms) { await sleep(Math.min(2000, Math.max(10, sch.end_at_ms - now()))); await pull(); }
  await pull();
  obs.events.push(['observation_end', now()]);

  // Final looks. Each one bounded; an exception is recorded, the rest still run.
  const F = obs.final;
  const step = async (name, fn) => { try { F[name] = await withTimeout(fn(), 30000, name); } catch (e) { F[name] = { error: String(e.message) }; } save(); };

  // First the bench page as it is now (bench-a's second run fitted, its third not yet cut), and its print.
  const BA = LIVE_BENCH_PAGES[0];
  await step('bench', async () => { const p = live['bench:' + BA]; const f = await facts(p); await p.screenshot({ path: path.join(OUT, 'bench-' + BA + '.png'), fullPage: true }); return f; });
  await step('print', async () => { const p = await openPage(browser, 'print', WEB + '/bench/' + BA, { width: 1280, height: 800 });
    const ok = await waitFor(p, () => { const e = [...document.querySelectorAll('[data-field="c3"]')].filter(e => !e.closest('[data-run]'))[0]; return e && e.getAttribute('data-si'); }, null, 6000);
    await sleep(300); await p.emulateMediaType('print'); await sleep(300); const f = await facts(p); f.waited_ok = ok;
    const pdfA4 = await p.pdf({ format: 'A4', printBackground: true, timeout: 20000 });
    fs.writeFileSync(path.join(OUT, 'bench-print-A4.pdf'), pdfA4);
    const pdfL = await p.pdf({ format: 'Letter', printBackground: true, timeout: 20000 });
    fs.writeFileSync(path.join(OUT, 'bench-print-Letter.pdf'), pdfL);
    f.pdf = ['bench-print-A4.pdf', 'bench-print-Letter.pdf']; await p.close(); return f; });
  await step('room', async () => { const f = await facts(live.room); await live.room.screenshot({ path: path.join(OUT, 'room-1920x1080.png') }); return f; });
  await step('csv_link', async () => { const h = F.bench && F.bench.csv_href; if (!h) return { error: 'no a[data-download="csv"]' };
    const r = await httpGet(h, 5000, 5e6); return { url: h, status: r.status, ctype: r.ctype, ms: r.ms, head: r.body.slice(0, 300), rows: r.body.split('\n').length, error: r.error }; });
  await step('csv', async () => { const out = {};
    for (let n = 1; n <= 4; n++) { const u = WEB + '/bench/' + BA + '/runs/' + n + '.csv'; const r = await httpGet(u, 5000, 5e6);
      fs.writeFileSync(path.join(OUT, 'run-' + BA + '-' + n + '.csv'), r.body || '');
      out[n] = { url: u, status: r.status, ctype: r.ctype, error: r.error, file: 'run-' + BA + '-' + n + '.csv' }; }
    return out; });
  await step('api_state', async () => { const r = await httpGet(WEB + '/api/state', 3000, 5e6); let j = null; try { j = JSON.parse(r.body); } catch (e) { }
    return { t: now(), status: r.status, ctype: r.ctype, ms: r.ms, json: j, body_head: j ? null : (r.body || '').slice(0, 300), error: r.error }; });
  await step('events', async () => { const r = await httpGet(WEB + '/events', 5000, 200000);
    return { status: r.status, ctype: r.ctype, headers_ms: r.headers_ms, first_data_ms: r.first_data_ms, data_lines: (r.body.match(/^data:/mg) || []).length, head: r.body.slice(0, 300), error: r.error }; });
  await step('pages', async () => { const o = {}; for (const [n, p] of Object.entries(live)) o[n] = await withTimeout(p.evaluate(() => document.body.getAttribute('data-connected')), 3000, 'conn'); return o; });

  // Phone: 390x844, a phone's metrics; the room and a bench page (layout: the fields, whatever run is on).
  for (const [nm, url, isRoom] of [['phone_room', WEB + '/', true], ['phone_bench', WEB + '/bench/' + BA, false]]) {
    await step(nm, async () => { const p = await openPage(browser, nm, url, { width: 390, height: 844, deviceScaleFactor: 2, isMobile: true, hasTouch: true });
      const ok = await waitFor(p, (isRoom) => { const own = (s) => [...document.querySelectorAll(s)].filter(e => !e.closest('[data-run]'))[0];
        const a = own('[data-field="c3"]'), b = own('[data-field="c4"]'); return a && b && a.textContent.trim() && b.textContent.trim() &&
          (!isRoom || document.querySelectorAll('[data-bench] [data-field="c3"][data-si]').length >= 3); }, isRoom, 8000);
      await sleep(500); const f = await facts(p); f.waited_ok = ok; await p.screenshot({ path: path.join(OUT, nm + '-390x844.png'), fullPage: true }); await p.close(); return f; });
  }

  closing = true;
  obs.events.push(['closing', now()]);
  save();
  try { await withTimeout(browser.close(), 10000, 'close'); } catch (e) { note('close: ' + e.message); try { bp.kill('SIGKILL'); } catch (e2) { } }
  save();
}

main().then(() => process.exit(0)).catch((e) => { note('fatal: ' + (e && e.stack || e)); obs.fatal = String(e && e.message || e); save(); process.exit(2); });
