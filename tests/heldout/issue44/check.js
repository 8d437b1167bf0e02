'use strict';
// Browser checks of held-out issue 44 (spindown-web): one case per invocation.
//   node check.js CASE 'JSON-ARGS'
// Prints exactly one line: "PASS CASE: ..." or "FAIL CASE: why". Every wait is bounded.
// Truth comes from what a room needs (CASES.md), judged in a real Chromium.
const fs = require('fs');
const path = require('path');
const cp = require('child_process');
const zlib = require('zlib');

const CASE = process.argv[2] || '?';
let A = {};
try { A = JSON.parse(process.argv[3] || '{}'); } catch (e) { console.log(`FAIL ${CASE}: bad arguments: ${e.message}`); process.exit(0); }
const NM = process.env.SPINDOWN_NODE_MODULES || '/opt/spindown-test-node/node_modules';
const CHROME = process.env.CHROME || '/usr/bin/chromium';
let puppeteer;
try { puppeteer = require(path.join(NM, 'puppeteer-core')); } catch (e) {
  console.log(`FAIL ${A.name || CASE}: puppeteer-core cannot be loaded from ${NM}: ${e.message}`); process.exit(0);
}

const sleep = ms => new Promise(r => setTimeout(r, ms));
let done = false;
let browser = null;
const spawned = [];
function out(ok, msg) {
  if (done) return;
  done = true;
  console.log(`${ok ? 'PASS' : 'FAIL'} ${A.name || CASE}: ${String(msg).replace(/\s+/g, ' ').slice(0, 900)}`);
}
function killAll() {
  for (const c of spawned) { try { if (c.exitCode === null) process.kill(c.pid, 'SIGTERM'); } catch (e) { /* gone */ } }
  if (browser) { try { browser.process().kill('SIGKILL'); } catch (e) { /* gone */ } }
}
const LIMIT = (A.limit_s || 60) * 1000;
setTimeout(() => {
  out(false, `the check did not finish within ${LIMIT / 1000} s`);
  if (A.on_timeout) { try { cp.execSync(A.on_timeout, {timeout: 5000}); } catch (e) { /* best effort */ } }
  killAll();
  process.exit(0);
}, LIMIT).unref();

// ---------------------------------------------------------------- in-page helpers
const HELPERS = `
window.__h = (() => {
  const h = {};
  h.vis = el => {
    if (!el || !el.isConnected) return false;
    for (let e = el; e && e.nodeType === 1; e = e.parentElement) {
      const s = getComputedStyle(e);
      if (s.display === 'none' || s.visibility === 'hidden' || s.visibility === 'collapse' || parseFloat(s.opacity) === 0) return false;
    }
    const r = el.getBoundingClientRect();
    return r.width > 0 && r.height > 0;
  };
  h.R = r => ({left: r.left, top: r.top, right: r.right, bottom: r.bottom, width: r.width, height: r.height});
  h.inRect = (r, R, tol = 1) => r.left >= R.left - tol && r.top >= R.top - tol && r.right <= R.right + tol && r.bottom <= R.bottom + tol;
  h.vp = () => ({left: 0, top: 0, right: innerWidth, bottom: innerHeight});
  h.tile = id => document.querySelector('[data-bench="' + CSS.escape(id) + '"]');
  // The id as rendered inside el: its box (all lines), the font size, whether it is on top at its centre.
  h.nameBox = (el, id) => {
    const w = document.createTreeWalker(el, NodeFilter.SHOW_TEXT);
    let range = null, holder = null;
    for (let n = w.nextNode(); n; n = w.nextNode()) {
      const i = n.data.indexOf(id);
      if (i >= 0 && h.vis(n.parentElement)) { range = document.createRange(); range.setStart(n, i); range.setEnd(n, i + id.length); holder = n.parentElement; break; }
    }
    if (!range) {
      for (const e of el.querySelectorAll('*')) {
        if (h.vis(e) && e.textContent.trim() === id) { range = document.createRange(); range.selectNodeContents(e); holder = e; break; }
      }
    }
    if (!range) return null;
    const r = range.getBoundingClientRect();
    const rects = [...range.getClientRects()].filter(x => x.width > 0);
    const cx = r.left + r.width / 2, cy = (rects[0] ? rects[0].top + rects[0].height / 2 : r.top + r.height / 2);
    const onTop = document.elementFromPoint(Math.min(Math.max(cx, 0), innerWidth - 1), Math.min(Math.max(cy, 0), innerHeight - 1));
    return {rect: h.R(r), font: parseFloat(getComputedStyle(holder).fontSize), lineH: rects.length ? Math.min(...rects.map(x => x.height)) : 0,
            onTop: !!onTop && (el.contains(onTop) || onTop.contains(holder))};
  };
  // Any CSS colour to [r,g,b,a] in 0..255 through a canvas (works for rgb(), oklch(), color-mix(), ...)
  const cv = document.createElement('canvas'); cv.width = cv.height = 1;
  const cx = cv.getContext('2d', {willReadFrequently: true});
  h.rgba = c => {
    cx.clearRect(0, 0, 1, 1); cx.fillStyle = 'rgba(0,0,0,0)'; cx.fillStyle = c; cx.fillRect(0, 0, 1, 1);
    return [...cx.getImageData(0, 0, 1, 1).data];
  };
  h.lum = c => { // WCAG relative luminance of [r,g,b]
    const f = v => { v /= 255; return v <= 0.03928 ? v / 12.92 : Math.pow((v + 0.055) / 1.055, 2.4); };
    return 0.2126 * f(c[0]) + 0.7152 * f(c[1]) + 0.0722 * f(c[2]);
  };
  h.contrast = (a, b) => { const x = h.lum(a), y = h.lum(b); return (Math.max(x, y) + 0.05) / (Math.min(x, y) + 0.05); };
  // Effective background behind el: first ancestor with an opaque-ish background, else the canvas (white).
  h.bg = (el, printing) => {
    for (let e = el; e && e.nodeType === 1; e = e.parentElement) {
      const s = getComputedStyle(e);
      if (printing && s.printColorAdjust !== 'exact' && s.webkitPrintColorAdjust !== 'exact') continue; // backgrounds are not printed
      const c = h.rgba(s.backgroundColor);
      if (c[3] > 128) return c;
    }
    return [255, 255, 255, 255];
  };
  h.fg = el => h.rgba(getComputedStyle(el).color);
  // Visible text of the page without elements matching the selector
  h.textWithout = sel => {
    let t = document.body.innerText;
    if (sel) for (const e of document.querySelectorAll(sel)) { const x = e.innerText; if (x && x.trim()) t = t.split(x).join(' '); }
    return t;
  };
  // Smallest visible element whose own text matches re (for where a message is and how big)
  h.findText = (re, root, exclude) => {
    root = root || document.body;
    let best = null;
    for (const e of root.querySelectorAll('*')) {
      if (exclude && e.closest(exclude)) continue;
      if (!h.vis(e)) continue;
      const t = e.innerText || '';
      if (!re.test(t)) continue;
      if (!best || best.contains(e)) best = e;
    }
    if (!best) return null;
    const r = best.getBoundingClientRect();
    return {text: best.innerText.slice(0, 160), font: parseFloat(getComputedStyle(best).fontSize), rect: h.R(r), tag: best.tagName,
            inFooter: !!best.closest('footer'), onScreen: h.inRect(r, h.vp(), 2)};
  };
  return h;
})();
`;

async function launch() {
  browser = await puppeteer.launch({
    executablePath: CHROME, headless: true, protocolTimeout: 30000,
    args: ['--no-sandbox', '--disable-gpu', '--disable-dev-shm-usage', '--no-first-run', '--no-default-browser-check',
      '--disable-extensions', '--disable-background-networking', '--disable-component-update', '--mute-audio'],
  });
  return browser;
}
async function newPage(vp) {
  const p = await browser.newPage();
  await p.evaluateOnNewDocument(HELPERS);
  await p.setViewport(vp);
  p.setDefaultTimeout(15000);
  return p;
}
async function goto(p, url) {
  const r = await p.goto(url, {waitUntil: 'domcontentloaded', timeout: 15000});
  await p.evaluate(HELPERS).catch(() => {}); // if the document was already parsed before the hook
  return r;
}
async function waitFor(fn, ms, step = 250) {
  const end = Date.now() + ms;
  for (;;) {
    let v;
    try { v = await fn(); } catch (e) { v = undefined; }
    if (v) return v;
    if (Date.now() >= end) return v;
    await sleep(step);
  }
}
async function api(p, port) {
  return p.evaluate(async u => { const r = await fetch(u, {cache: 'no-store'}); return r.json(); }, `http://127.0.0.1:${port}/api/state`);
}
function sh(cmd) {
  const c = cp.spawn('bash', ['-c', cmd], {stdio: 'ignore'});
  spawned.push(c);
  return c;
}
function shWait(cmd, ms = 20000) {
  return new Promise(res => {
    const c = cp.spawn('bash', ['-c', cmd], {stdio: ['ignore', 'pipe', 'pipe']});
    spawned.push(c);
    let o = '';
    c.stdout.on('data', d => { o += d; });
    c.stderr.on('data', d => { o += d; });
    const t = setTimeout(() => { try { process.kill(c.pid, 'SIGKILL'); } catch (e) { /* gone */ } }, ms);
    c.on('exit', code => { clearTimeout(t); res({code, out: o}); });
  });
}
// mean WCAG luminance of a PNG screenshot (RGBA 8-bit, non-interlaced, as Chromium writes it)
function pngMeanLum(buf) {
  buf = Buffer.from(buf);
  let off = 8, w = 0, hgt = 0, ct = 6, idat = [];
  while (off < buf.length) {
    const len = buf.readUInt32BE(off), type = buf.toString('latin1', off + 4, off + 8), data = buf.subarray(off + 8, off + 8 + len);
    if (type === 'IHDR') { w = data.readUInt32BE(0); hgt = data.readUInt32BE(4); ct = data[9]; }
    if (type === 'IDAT') idat.push(data);
    off += 12 + len;
  }
  const bpp = ct === 6 ? 4 : 3;
  const raw = zlib.inflateSync(Buffer.concat(idat));
  const stride = w * bpp;
  let prev = Buffer.alloc(stride), sum = 0, n = 0;
  const f = v => { v /= 255; return v <= 0.03928 ? v / 12.92 : Math.pow((v + 0.055) / 1.055, 2.4); };
  for (let y = 0; y < hgt; y++) {
    const ft = raw[y * (stride + 1)];
    const line = Buffer.from(raw.subarray(y * (stride + 1) + 1, (y + 1) * (stride + 1)));
    for (let i = 0; i < stride; i++) {
      const a = i >= bpp ? line[i - bpp] : 0, b = prev[i], c = i >= bpp ? prev[i - bpp] : 0;
      let x = line[i];
      if (ft === 1) x += a; else if (ft === 2) x += b; else if (ft === 3) x += (a + b) >> 1;
      else if (ft === 4) { const pp = a + b - c, pa = Math.abs(pp - a), pb = Math.abs(pp - b), pc = Math.abs(pp - c); x += (pa <= pb && pa <= pc) ? a : (pb <= pc ? b : c); }
      line[i] = x & 255;
    }
    if (y % 4 === 0) for (let i = 0; i < stride; i += bpp * 4) { sum += 0.2126 * f(line[i]) + 0.7152 * f(line[i + 1]) + 0.0722 * f(line[i + 2]); n++; }
    prev = line;
  }
  return n ? sum / n : NaN;
}
function pdfPages(buf) {
  const s = Buffer.from(buf).toString('latin1');
  const m = s.match(/\/Type\s*\/Pages[^]*?\/Count\s+(\d+)/) || s.match(/\/Count\s+(\d+)/);
  if (m) return +m[1];
  return (s.match(/\/Type\s*\/Page(?![s\w])/g) || []).length;
}
function todayPatterns() {
  const mons = ['jan', 'feb', 'mar', 'apr', 'may', 'jun', 'jul', 'aug', 'sep', 'oct', 'nov', 'dec'];
  const pats = [];
  const now = new Date();
  for (const d of [now, new Date(now.getTime() - 3 * 3600e3), new Date(now.getTime() + 3 * 3600e3)]) {
    for (const utc of [false, true]) {
      const y = utc ? d.getUTCFullYear() : d.getFullYear(), m = (utc ? d.getUTCMonth() : d.getMonth()) + 1, dd = utc ? d.getUTCDate() : d.getDate();
      const p2 = v => String(v).padStart(2, '0');
      pats.push(`${y}-${p2(m)}-${p2(dd)}`, `${dd}.${m}.${y}`, `${p2(dd)}.${p2(m)}.${y}`, `${m}/${dd}/${y}`, `${p2(m)}/${p2(dd)}/${y}`, `${dd}/${m}/${y}`, `${p2(dd)}/${p2(m)}/${y}`);
      pats.push(new RegExp(`\\b${dd}(st|nd|rd|th)?\\.? ${mons[m - 1]}[a-z]*\\.?,? ${y}`, 'i'), new RegExp(`\\b${mons[m - 1]}[a-z]*\\.? ${dd}(st|nd|rd|th)?,? ${y}`, 'i'));
    }
  }
  return pats;
}
const hasAny = (t, pats) => pats.some(p => (typeof p === 'string' ? t.includes(p) : p.test(t)));

// ---------------------------------------------------------------- room layout
// In page: every id has a tile, inside the viewport, not overlapping another, its name whole, on top and >= minFont.
async function roomLayout(p, ids, minFont) {
  return p.evaluate((ids, minFont) => {
    const h = window.__h, bad = [];
    const de = document.scrollingElement || document.documentElement;
    if (de.scrollHeight > innerHeight + 1) bad.push(`the page scrolls: ${de.scrollHeight} px tall for a ${innerHeight} px screen`);
    if (de.scrollWidth > innerWidth + 1) bad.push(`the page scrolls sideways: ${de.scrollWidth} px wide for ${innerWidth} px`);
    const rects = [];
    let missing = [], off = [], names = [], small = [], hidden = [];
    for (const id of ids) {
      const t = h.tile(id);
      if (!t || !h.vis(t)) { missing.push(id); continue; }
      const r = t.getBoundingClientRect();
      rects.push([id, h.R(r)]);
      if (!h.inRect(r, h.vp(), 1)) off.push(`${id}@${Math.round(r.left)},${Math.round(r.top)}-${Math.round(r.right)},${Math.round(r.bottom)}`);
      const nb = h.nameBox(t, id);
      if (!nb) { names.push(id); continue; }
      if (!h.inRect(nb.rect, h.R(r), 1) || !h.inRect(nb.rect, h.vp(), 1)) names.push(`${id} (name cut: ${Math.round(nb.rect.left)},${Math.round(nb.rect.top)}-${Math.round(nb.rect.right)},${Math.round(nb.rect.bottom)})`);
      else if (!nb.onTop) hidden.push(id);
      if (nb.font < minFont || nb.lineH < minFont * 0.85) small.push(`${id} ${nb.font}px`);
      for (const f of t.querySelectorAll('[data-field="c3"],[data-field="c4"]')) {
        if (!h.vis(f)) continue;
        const fr = f.getBoundingClientRect();
        if (!h.inRect(fr, h.vp(), 1) || !h.inRect(fr, h.R(r), 2)) { off.push(`${id}'s ${f.dataset.field} cut`); break; }
      }
    }
    const ov = [];
    for (let i = 0; i < rects.length; i++) for (let j = i + 1; j < rects.length; j++) {
      const a = rects[i][1], b = rects[j][1];
      const w = Math.min(a.right, b.right) - Math.max(a.left, b.left), hh = Math.min(a.bottom, b.bottom) - Math.max(a.top, b.top);
      if (w > 2 && hh > 2) ov.push(`${rects[i][0]}/${rects[j][0]}`);
    }
    const list = (label, xs) => { if (xs.length) bad.push(`${label} (${xs.length}): ${xs.slice(0, 5).join(', ')}${xs.length > 5 ? ' …' : ''}`); };
    list('no visible tile', missing); list('tile not wholly on the screen', off); list('name not wholly visible', names);
    list('name covered by something else', hidden); list(`name smaller than ${minFont}px`, small); list('tiles overlap', ov);
    let area = 0;
    for (const [, r] of rects) area += Math.max(0, Math.min(r.right, innerWidth) - Math.max(r.left, 0)) * Math.max(0, Math.min(r.bottom, innerHeight) - Math.max(r.top, 0));
    return {bad, cover: area / (innerWidth * innerHeight), n: rects.length,
            tileH: rects.length ? Math.round(rects.reduce((s, x) => s + x[1].height, 0) / rects.length) : 0};
  }, ids, minFont);
}

const CASES = {};

// 1. A 1366x768 projector showing a room of 30 benches.
CASES.room = async () => {
  await launch();
  const p = await newPage({width: A.w, height: A.h});
  await goto(p, A.url);
  const n = await waitFor(() => p.evaluate(ids => ids.every(id => window.__h.tile(id)), A.ids), 12000);
  if (!n) {
    const have = await p.evaluate(() => document.querySelectorAll('[data-bench]').length).catch(() => '?');
    return out(false, `only ${have} of ${A.ids.length} bench tiles appeared within 12 s`);
  }
  await sleep(1500);
  const r = await roomLayout(p, A.ids, A.min_font);
  if (r.bad.length) return out(false, `${A.w}x${A.h}, ${A.ids.length} benches: ${r.bad.join('; ')}`);
  out(true, `${A.w}x${A.h}: all ${A.ids.length} tiles on one screen, no scrolling, names whole and >= ${A.min_font}px, no overlap (tiles ~${r.tileH}px tall)`);
};

// 2. A 1280x720 projector: 4 benches, then 18 more join while the page stays open.
CASES.grow = async () => {
  await launch();
  const p = await newPage({width: A.w, height: A.h});
  await goto(p, A.url);
  const ok1 = await waitFor(() => p.evaluate(ids => ids.every(id => window.__h.tile(id)), A.first), 12000);
  if (!ok1) return out(false, `the first ${A.first.length} benches' tiles did not appear within 12 s`);
  await sleep(1200);
  const r1 = await roomLayout(p, A.first, A.min_font);
  const bad = [];
  if (r1.bad.length) bad.push(`with ${A.first.length} benches: ${r1.bad.join('; ')}`);
  if (r1.cover < A.min_cover) bad.push(`with ${A.first.length} benches the tiles cover ${(100 * r1.cover).toFixed(0)} % of the screen (< ${(100 * A.min_cover).toFixed(0)} %: they do not grow to use it)`);
  sh(A.more_cmd);
  const all = A.first.concat(A.more);
  const ok2 = await waitFor(() => p.evaluate(ids => ids.every(id => window.__h.tile(id)), all), 15000);
  if (!ok2) {
    const have = await p.evaluate(() => document.querySelectorAll('[data-bench]').length).catch(() => '?');
    bad.push(`after 18 more benches started publishing, ${have} of ${all.length} tiles within 15 s (without a reload)`);
    return out(false, bad.join(' | '));
  }
  await sleep(1500);
  const r2 = await roomLayout(p, all, A.min_font);
  if (r2.bad.length) bad.push(`with ${all.length} benches: ${r2.bad.join('; ')}`);
  if (bad.length) return out(false, bad.join(' | '));
  out(true, `${A.w}x${A.h}: ${A.first.length} tiles cover ${(100 * r1.cover).toFixed(0)} % of the screen; with ${all.length} every tile and name (long ones included) fits without scrolling or a reload`);
};

// 3. A student's phone.
CASES.phone = async () => {
  await launch();
  const p = await newPage({width: 390, height: 844, deviceScaleFactor: 3, isMobile: true, hasTouch: true});
  await p.setUserAgent('Mozilla/5.0 (Linux; Android 14; Pixel 8) AppleWebKit/537.36 (KHTML, like Gecko) Chrome/126.0 Mobile Safari/537.36');
  const bad = [];
  await goto(p, A.bench_url);
  const got = await waitFor(() => p.evaluate(() => { const f = document.querySelector('[data-field="c3"]'); return f && /\d/.test(f.innerText) && document.querySelector('[data-plot]'); }), 12000);
  if (!got) return out(false, 'the bench page showed no c3 and plot within 12 s on the phone');
  await sleep(1200);
  const b = await p.evaluate(() => {
    const h = window.__h, de = document.scrollingElement || document.documentElement, r = {};
    r.sw = de.scrollWidth;
    const plot = document.querySelector('[data-plot]');
    const pr = plot.getBoundingClientRect(); r.plot = [Math.round(pr.left), Math.round(pr.right), Math.round(pr.width)];
    r.c3 = [...document.querySelectorAll('[data-field="c3"]')].filter(h.vis).map(e => { const q = e.getBoundingClientRect(); return [Math.round(q.left), Math.round(q.right), parseFloat(getComputedStyle(e).fontSize), e.innerText.trim()]; });
    r.wide = [...document.querySelectorAll('body *')].filter(e => h.vis(e) && e.getBoundingClientRect().right > innerWidth + 2 && getComputedStyle(e).position !== 'fixed').slice(0, 3).map(e => e.tagName.toLowerCase() + (e.className ? '.' + String(e.className).split(' ')[0] : ''));
    return r;
  });
  if (b.sw > 391) bad.push(`bench page scrolls sideways (${b.sw} px for 390; e.g. ${b.wide.join(', ')})`);
  if (b.plot[2] < 300 || b.plot[0] < -1 || b.plot[1] > 391) bad.push(`plot ${b.plot[2]} px wide at x ${b.plot[0]}..${b.plot[1]} (must lie within the 390 px screen and be >= 300 px)`);
  if (!b.c3.length) bad.push('no visible c3');
  for (const c of b.c3) {
    if (c[0] < -1 || c[1] > 391) bad.push(`c3 "${c[3]}" runs off the screen (${c[0]}..${c[1]})`);
    if (c[2] < 12) bad.push(`c3 text ${c[2]}px (< 12)`);
  }
  await goto(p, A.room_url);
  await waitFor(() => p.evaluate(() => document.querySelectorAll('[data-bench]').length > 0), 10000);
  await sleep(1000);
  const rm = await p.evaluate(() => {
    const h = window.__h, de = document.scrollingElement || document.documentElement;
    const tiles = [...document.querySelectorAll('[data-bench]')];
    return {sw: de.scrollWidth, n: tiles.length, off: tiles.filter(t => { const r = t.getBoundingClientRect(); return r.left < -1 || r.right > innerWidth + 1; }).map(t => t.dataset.bench),
            nameless: tiles.filter(t => !h.nameBox(t, t.dataset.bench)).map(t => t.dataset.bench)};
  });
  if (rm.sw > 391) bad.push(`room page scrolls sideways on the phone (${rm.sw} px)`);
  if (rm.off.length) bad.push(`room tiles wider than the phone: ${rm.off.slice(0, 4).join(', ')}`);
  if (rm.nameless.length) bad.push(`room tiles without a visible name: ${rm.nameless.slice(0, 4).join(', ')}`);
  if (bad.length) return out(false, bad.join('; '));
  out(true, `390x844 phone: bench page ${b.sw}px wide, plot ${b.plot[2]}px, c3 on screen at ${b.c3[0][2]}px; room page ${rm.n} tiles without sideways scrolling`);
};

const TRUST_RE = /not verified|unverified|forged|unknown (source|sender|session)|no fitter (announced|has|heard|sent|vouches)|not from (the|a|any|this lab'?s) fitter|untrusted|suspicious|unsigned|cannot (be )?verif|not trusted|not vouched|unconfirmed/i;

// 4. A laptop on the lab network publishes a FIT for a bench name no bridge has (no lab key).
CASES.ghost = async () => {
  await launch();
  const p = await newPage({width: 1920, height: 1080});
  await goto(p, A.room_url);
  const ok = await waitFor(() => p.evaluate(ids => ids.every(id => window.__h.tile(id)), A.real), 12000);
  if (!ok) return out(false, `the real benches' tiles (${A.real.join(', ')}) did not appear`);
  const r = await shWait(A.inject_cmd, 15000);
  if (r.code !== 0) return out(false, `harness: spindown-inject failed (${r.code}): ${r.out.slice(0, 200)}`);
  await sleep(3000);
  const bad = [];
  const tile = await p.evaluate((id, src) => {
    const t = window.__h.tile(id);
    if (!t || !window.__h.vis(t)) return null;
    const re = new RegExp(src, 'i');
    return {text: t.innerText.replace(/\s+/g, ' ').slice(0, 200), marked: re.test(t.innerText)};
  }, A.ghost, TRUST_RE.source);
  if (tile && !tile.marked) bad.push(`room tile "${A.ghost}" shows the laptop's FIT as a real result, unmarked: "${tile.text}"`);
  const p2 = await newPage({width: 1366, height: 900});
  const resp = await goto(p2, A.bench_url);
  let page = null;
  if (resp && resp.status() < 400) {
    await sleep(2500);
    page = await p2.evaluate(src => {
      const re = new RegExp(src, 'i');
      const c3 = [...document.querySelectorAll('[data-field="c3"]')].filter(window.__h.vis).map(e => e.innerText.trim()).join(' | ');
      return {c3, marked: re.test(document.body.innerText), text: document.body.innerText.replace(/\s+/g, ' ').slice(0, 160)};
    }, TRUST_RE.source);
    if (page.c3 && /\d/.test(page.c3) && !page.marked) bad.push(`bench page /bench/${A.ghost} shows c3 ${page.c3} with no word that no fitter of the lab sent it`);
  }
  if (bad.length) return out(false, bad.join('; '));
  out(true, tile ? `tile "${A.ghost}" marked untrusted ("${tile.text.slice(0, 80)}")` : `no tile for "${A.ghost}" (a FIT alone from an unknown session makes no bench)` + (page ? `; its page: ${page.marked ? 'marked' : 'no numbers'}` : ''));
};

const REFUSE_RE = /refused|unsigned|not signed|bad(ly)? signe?d?|bad signature|wrong key|another key|forged|rejected|not (the|this) lab'?s key|not verified/i;

// 5. A lab with the key: a laptop's unsigned FIT and one signed with another key, on a real bench.
CASES.keyed = async () => {
  await launch();
  const p = await newPage({width: 1366, height: 768});
  await goto(p, A.room_url);
  const before = await waitFor(() => p.evaluate(id => {
    const t = window.__h.tile(id); const f = t && t.querySelector('[data-field="c3"]');
    return f && f.dataset.si ? {si: +f.dataset.si, run: f.dataset.fitRun, text: f.innerText.trim()} : null;
  }, A.bench), 12000);
  if (!before) return out(false, `tile ${A.bench} shows no c3 (data-si) within 12 s`);
  const bad = [];
  if (Math.abs(before.si - A.real_c3) > 1e-6 * Math.abs(A.real_c3)) bad.push(`before the forgeries the tile's c3 ${before.si} is not the fitter's ${A.real_c3}`);
  for (const c of A.inject_cmds) {
    const r = await shWait(c, 15000);
    if (r.code !== 0) return out(false, `harness: spindown-inject failed (${r.code}): ${r.out.slice(0, 200)}`);
  }
  await sleep(3500);
  const after = await p.evaluate((id, src) => {
    const h = window.__h, t = h.tile(id); const f = t && t.querySelector('[data-field="c3"]');
    return {si: f ? +f.dataset.si : NaN, run: f ? f.dataset.fitRun : null, msg: t ? h.findText(new RegExp(src, 'i'), t) : null,
            tileText: t ? t.innerText.replace(/\s+/g, ' ').slice(0, 200) : ''};
  }, A.bench, REFUSE_RE.source);
  if (!(Math.abs(after.si - A.real_c3) <= 1e-6 * Math.abs(A.real_c3)) || after.run !== before.run) bad.push(`the tile's headline changed to c3 ${after.si} (run ${after.run}) after unsigned/wrongly signed FITs`);
  if (!after.msg) bad.push(`tile ${A.bench} says nothing of the refused FITs sent on its channel: "${after.tileText}"`);
  else if (after.msg.font < 11 || !after.msg.onScreen) bad.push(`the refusal on the tile is ${after.msg.font}px${after.msg.onScreen ? '' : ' and off screen'}: "${after.msg.text}"`);
  const p2 = await newPage({width: 1366, height: 900});
  await goto(p2, A.bench_url);
  await sleep(2500);
  const bp = await p2.evaluate((src, real) => {
    const h = window.__h;
    const f = [...document.querySelectorAll('[data-field="c3"]')].find(h.vis);
    return {c3: f ? f.innerText.trim() : '', si: f && f.dataset.si ? +f.dataset.si : null, msg: h.findText(new RegExp(src, 'i'), document.body, 'footer')};
  }, REFUSE_RE.source, A.real_c3);
  if (bp.si !== null && Math.abs(bp.si - A.real_c3) > 1e-6 * Math.abs(A.real_c3)) bad.push(`bench page c3 ${bp.c3} is not the fitter's`);
  if (!bp.msg) bad.push('the bench page says nothing of the refused FITs outside its footer');
  else if (bp.msg.font < 12) bad.push(`the bench page's refusal is ${bp.msg.font}px: "${bp.msg.text}"`);
  if (bad.length) return out(false, bad.join('; '));
  out(true, `headline stays the fitter's c3 (${before.text}); tile: "${after.msg.text.slice(0, 80)}"; bench page: "${bp.msg.text.slice(0, 80)}"`);
};

const REASON_RE = /restart|reset|cut short|closed early|ended early|before (the|it|its) (stop|standstill)|never stopped|no stop|without a stop|interrupted/i;

// 6. An Arduino reset mid-coast closes run 2 early: the tile's headline stays the last whole run.
CASES.reset = async () => {
  await launch();
  const p = await newPage({width: 1366, height: 768});
  await goto(p, A.room_url);
  const t = await waitFor(() => p.evaluate(id => {
    const t = window.__h.tile(id); const f = t && t.querySelector('[data-field="c3"]');
    return f && f.dataset.si ? {si: +f.dataset.si, run: f.dataset.fitRun, text: f.innerText.trim(), tile: t.innerText.replace(/\s+/g, ' ').slice(0, 160)} : null;
  }, A.bench), 12000);
  const bad = [];
  if (!t) return out(false, `tile ${A.bench} shows no c3 within 12 s`);
  if (String(t.run) !== String(A.good_run) || Math.abs(t.si - A.good_c3) > 1e-6 * Math.abs(A.good_c3))
    bad.push(`tile headline is run ${t.run} c3 ${t.si} (${t.text}); the last whole run is ${A.good_run} with c3 ${A.good_c3} — the run the reset cut short (${A.cut_run}) took the headline`);
  const p2 = await newPage({width: 1366, height: 900});
  await goto(p2, A.bench_url);
  await waitFor(() => p2.evaluate(() => document.querySelectorAll('[data-run]').length > 0), 10000);
  await sleep(1000);
  const rows = await p2.evaluate(() => [...document.querySelectorAll('[data-run]')].filter(window.__h.vis).map(e => ({run: e.dataset.run, text: e.innerText.replace(/\s+/g, ' ').trim()})));
  const cut = rows.filter(r => String(r.run) === String(A.cut_run));
  for (const r of cut) if (!REASON_RE.test(r.text)) bad.push(`run table row ${r.run} gives no reason it is not whole: "${r.text.slice(0, 120)}"`);
  const seen = new Map();
  for (const r of rows) seen.set(r.run, (seen.get(r.run) || 0) + 1);
  const dup = [...seen].filter(([, n]) => n > 1).map(([k]) => k);
  if (dup.length) bad.push(`run table lists run ${dup.join(', ')} more than once`);
  if (bad.length) return out(false, bad.join('; '));
  out(true, `tile keeps run ${t.run} (${t.text}); ${cut.length ? `row ${A.cut_run} says why: "${cut[0].text.slice(0, 90)}"` : `run ${A.cut_run} not listed as a result`}`);
};

const STALE_RE = /stale|disconnected|offline|connection (lost|lost|gone|closed|dropped)|lost (the )?(connection|stream|contact|link)|reconnecting|not live|no (data|updates?|messages?|events?|news) (for|since|in)|no contact|not updated|out of date|server (not responding|unreachable|gone)|frozen/i;

// 7. The lab PC's web server hangs (process stopped) while the projector shows the room.
CASES.stale = async () => {
  await launch();
  const p = await newPage({width: 1280, height: 720});
  await goto(p, A.room_url);
  const live = await waitFor(() => p.evaluate(() => document.body.dataset.connected === 'true' && document.querySelectorAll('[data-bench]').length > 0), 12000);
  if (!live) return out(false, 'the room page never became live (body[data-connected=true]) within 12 s');
  await sleep(1500);
  const txt = () => p.evaluate(() => window.__h.textWithout('[data-field="bridge"]'));
  const t0 = await txt();
  if (STALE_RE.test(t0)) return out(false, `the live page already says "${t0.match(STALE_RE)[0]}" before anything went wrong`);
  const bad = [];
  process.kill(A.web_pid, 'SIGSTOP');
  const tStop = Date.now();
  let shown = null;
  try {
    shown = await waitFor(async () => { const t = await txt(); return STALE_RE.test(t) ? t.match(STALE_RE)[0] : null; }, 12000, 300);
  } finally { try { process.kill(A.web_pid, 'SIGCONT'); } catch (e) { /* gone */ } }
  const dtStale = (Date.now() - tStop) / 1000;
  if (!shown) bad.push('12 s after the server stopped answering the room still looks live (no word that the stream is gone)');
  else if (dtStale > 10.5) bad.push(`the page said "${shown}" only ${dtStale.toFixed(1)} s after the server stopped (> 10 s)`);
  const tCont = Date.now();
  const back = await waitFor(async () => { const ok = await p.evaluate(() => document.body.dataset.connected === 'true'); const t = await txt(); return ok && !STALE_RE.test(t); }, 12000, 300);
  const dtBack = (Date.now() - tCont) / 1000;
  if (!back) bad.push(`12 s after the server resumed the page still says it is stale or is not connected`);
  else if (dtBack > 10.5) bad.push(`recovered only ${dtBack.toFixed(1)} s after the server resumed`);
  if (bad.length) return out(false, bad.join('; '));
  out(true, `"${shown}" ${dtStale.toFixed(1)} s after the server hung; live again ${dtBack.toFixed(1)} s after it resumed`);
};

// ages in seconds found in a text: "12 s ago", "0:12", "1 min", "12s"
function ages(t) {
  const v = [];
  const re = /(\d+(?:\.\d+)?)\s*(h|hrs?|hours?|min|mins?|minutes?|m(?![a-zµ/·²])|s|secs?|seconds?)(?![a-z⁻²·/])/gi;
  let m;
  while ((m = re.exec(t))) {
    const u = m[2].toLowerCase(); const k = u.startsWith('h') ? 3600 : (u.startsWith('m') ? 60 : 1);
    v.push(parseFloat(m[1]) * k);
  }
  const re2 = /\b(\d{1,2}):(\d{2})\b/g;
  while ((m = re2.exec(t))) v.push(60 * +m[1] + +m[2]);
  return v;
}
const GONE_RE = /silent|unplugged|disconnected|not connected|no samples|no data|lost|gone|offline|stale|cannot open/i;
const OLD_ERR_RE = /cannot open|no such file|input\/output error|unplugged|not connected|disconnected/i;

// 8. A bench's USB cable is pulled (its serial port disappears), then plugged back in.
CASES.unplug = async () => {
  await launch();
  const p = await newPage({width: 1366, height: 768});
  await goto(p, A.room_url);
  const tileText = () => p.evaluate(id => { const t = window.__h.tile(id); return t ? {state: t.dataset.state, text: t.innerText.replace(/\s+/g, ' ')} : null; }, A.bench);
  const live = await waitFor(async () => { const x = await tileText(); return x && x.state !== 'silent' && !GONE_RE.test(x.text) ? x : null; }, 15000);
  if (!live) return out(false, `tile ${A.bench} not live before the unplug (${JSON.stringify(await tileText())})`);
  const bad = [];
  let r = await shWait(A.unplug_cmd, 10000);
  const tU = Date.now();
  const gone = await waitFor(async () => { const x = await tileText(); return x && (x.state === 'silent' || GONE_RE.test(x.text)) ? x : null; }, 12000, 300);
  const dtGone = (Date.now() - tU) / 1000;
  if (!gone) bad.push(`12 s after the cable was pulled the tile still looks live: "${(await tileText()).text.slice(0, 140)}"`);
  else if (dtGone > 10.5) bad.push(`the tile showed the bench gone only after ${dtGone.toFixed(1)} s`);
  // how old its last sample is, and that this grows
  const a1 = await tileText(); const t1 = Date.now();
  await sleep(4000);
  const a2 = await tileText(); const t2 = Date.now();
  const x1 = ages(a1.text), x2 = ages(a2.text), dt = (t2 - t1) / 1000;
  let ageOk = false;
  for (let i = 0; i < Math.min(x1.length, x2.length); i++) if (x2[i] - x1[i] >= dt - 1.6 && x2[i] - x1[i] <= dt + 2.5 && x1[i] >= 1) ageOk = true;
  if (!ageOk) bad.push(`the tile does not say how old the bench's last sample is (no age that grows over ${dt.toFixed(0)} s): "${a1.text.slice(0, 120)}" then "${a2.text.slice(0, 120)}"`);
  r = await shWait(A.replug_cmd, 10000);
  const tR = Date.now();
  const back = await waitFor(async () => { const x = await tileText(); return x && x.state !== 'silent' && !OLD_ERR_RE.test(x.text) ? x : null; }, 15000, 300);
  if (!back) {
    const st = await api(p, A.port).catch(() => null);
    const b = st && st.benches.find(q => q.id === A.bench);
    bad.push(`15 s after the board was plugged back in the tile still shows the outage: "${(await tileText()).text.slice(0, 160)}" (bridge ${b ? b.bridge.state : '?'})`);
  } else {
    await sleep(2000);
    const x = await tileText();
    if (OLD_ERR_RE.test(x.text)) bad.push(`after reconnecting the tile shows "${x.text.match(OLD_ERR_RE)[0]}" again`);
    const p2 = await newPage({width: 1366, height: 900});
    await goto(p2, A.bench_url);
    await sleep(2500);
    const bt = await p2.evaluate(() => document.body.innerText.replace(/\s+/g, ' '));
    if (OLD_ERR_RE.test(bt)) bad.push(`the bench page, connected again, still shows "${bt.match(OLD_ERR_RE)[0]}": "${bt.slice(Math.max(0, bt.search(OLD_ERR_RE) - 60), bt.search(OLD_ERR_RE) + 80)}"`);
  }
  if (bad.length) return out(false, bad.join('; '));
  out(true, `gone after ${dtGone.toFixed(1)} s ("${gone.text.slice(0, 70)}"), age grows (${x1.join('/')} -> ${x2.join('/')}); clean again ${((Date.now() - tR) / 1000).toFixed(0)} s after the replug`);
};

const INTERNAL_RE = /max_coast|max_buffer|max_run_samples|max-coast|max-buffer|max-run-samples|truncated\s*[:=]\s*true|\b[a-z]+_[a-z]+_s\b/;
const CUTSAID_RE = /truncat|cut short|cut off|incomplete|only the first|first [\d.,]+\s*(s\b|seconds|samples|min)|of (the )?[\d.,]+\s*(s\b|seconds|samples)|not (the )?whole (run|coast)|too long to keep|kept only|not all (the )?samples/i;

// 9. A well-oiled motor coasts ~3 minutes: past the fitter's --max-coast and the web's sample limit.
CASES.long = async () => {
  await launch();
  const p = await newPage({width: 1366, height: 768});
  await goto(p, A.room_url);
  const bad = [];
  const tile = await waitFor(() => p.evaluate(id => { const t = window.__h.tile(id); return t ? {state: t.dataset.state, text: t.innerText.replace(/\s+/g, ' ')} : null; }, A.bench), 10000);
  if (!tile) return out(false, `no tile for ${A.bench}`);
  await sleep(1500);
  const now = Date.now() / 1000;
  if (now > A.coast_until_epoch) return out(false, `harness: too late to judge (the motor stopped ${Math.round(now - A.coast_until_epoch)} s ago)`);
  const t2 = await p.evaluate(id => { const t = window.__h.tile(id); return {state: t.dataset.state, text: t.innerText.replace(/\s+/g, ' ')}; }, A.bench);
  const coastSaid = t2.state === 'coasting' || /coast/i.test(t2.text);
  if (!coastSaid || /\b(powered|idle)\b/i.test(t2.text) || t2.state === 'powered' || t2.state === 'idle')
    bad.push(`while the motor still coasts (${Math.round(A.coast_until_epoch - now)} s before it stops) the tile reads state "${t2.state}": "${t2.text.slice(0, 120)}"`);
  if (INTERNAL_RE.test(t2.text)) bad.push(`tile shows internal text "${t2.text.match(INTERNAL_RE)[0]}"`);
  // bench page after the run is closed by the fitter
  const p2 = await newPage({width: 1366, height: 900});
  await goto(p2, A.bench_url);
  await waitFor(() => p2.evaluate(() => !!document.querySelector('a[data-download="csv"]')), 10000);
  await sleep(2000);
  const bp = await p2.evaluate(() => ({text: document.body.innerText.replace(/\s+/g, ' '), href: (document.querySelector('a[data-download="csv"]') || {}).href || ''}));
  if (INTERNAL_RE.test(bp.text)) bad.push(`bench page shows internal text "${bp.text.match(INTERNAL_RE)[0]}": "…${bp.text.slice(Math.max(0, bp.text.search(INTERNAL_RE) - 50), bp.text.search(INTERNAL_RE) + 60)}…"`);
  const st = await api(p2, A.port);
  const b = st.benches.find(q => q.id === A.bench);
  const fit = b && b.last_fit;
  if (!fit) bad.push('no FIT for the long coast reached the page');
  const csvUrl = bp.href || (b && b.run && b.run.csv ? `http://127.0.0.1:${A.port}${b.run.csv}` : '');
  if (!csvUrl) bad.push('no CSV link for the run');
  else if (fit) {
    const csv = await p2.evaluate(async u => { const r = await fetch(u); return r.ok ? r.text() : ''; }, csvUrl);
    const rows = csv.trim().split(/\r?\n/).filter(l => /^-?[\d.]/.test(l));
    const last = rows.length ? parseFloat(rows[rows.length - 1].split(/[,;]/)[0]) : NaN;
    const end = fit.t_end_s;
    const cutShort = !(last >= end - 1.0);
    if (cutShort && !CUTSAID_RE.test(bp.text)) bad.push(`the CSV stops at t = ${last.toFixed(1)} s of the run's ${end.toFixed(1)} s (${rows.length} rows) and the page does not say it is cut`);
    if (!bad.length) return out(true, `tile "${t2.state}" while coasting; no internal words; CSV ${cutShort ? `cut at ${last.toFixed(1)} s of ${end.toFixed(1)} s and said ("${bp.text.match(CUTSAID_RE)[0]}")` : `whole to ${last.toFixed(1)} s`}`);
  }
  out(false, bad.join('; '));
};

// 10. The one-page lab record, printed while the next run coasts, and the plot as an image for the report.
CASES.record = async () => {
  await launch();
  const p = await newPage({width: 1280, height: 900});
  const dl = A.download_dir;
  fs.mkdirSync(dl, {recursive: true});
  const cdp = await p.createCDPSession();
  await cdp.send('Browser.setDownloadBehavior', {behavior: 'allow', downloadPath: dl}).catch(() => cdp.send('Page.setDownloadBehavior', {behavior: 'allow', downloadPath: dl}));
  await goto(p, A.bench_url);
  const showsC3 = () => p.evaluate(x => [...document.querySelectorAll('[data-field="c3"]')].some(e => window.__h.vis(e) && e.innerText.includes(x)), A.c3_digits);
  let ok = await waitFor(showsC3, 8000);
  let how = 'as the page opened';
  const bad = [];
  if (!ok) {
    // the student picks the run to print in the session's runs: a control of its row (view/show/print/its number), else the row
    const picked = await p.evaluate(run => {
      const h = window.__h;
      const row = [...document.querySelectorAll('[data-run]')].find(e => String(e.dataset.run) === String(run) && h.vis(e));
      if (!row) return null;
      const cs = [...row.querySelectorAll('a,button,[role="button"],input,select')].filter(e => h.vis(e) && !/csv/i.test([e.innerText, e.getAttribute('href'), e.getAttribute('download')].join(' ')));
      const lbl = e => [e.innerText, e.value, e.title, e.getAttribute('aria-label'), e.getAttribute('href')].filter(Boolean).join(' ');
      const c = cs.find(e => /view|show|open|print|select|detail|record|report/i.test(lbl(e))) || cs.find(e => new RegExp('(^|\\D)' + run + '(\\D|$)').test(lbl(e))) ||
                (row.cells && row.cells[0]) || cs[0] || row;
      c.setAttribute('data-h44-pick', '1');
      return (lbl(c) || c.innerText || 'the row').trim().slice(0, 40);
    }, A.run).catch(() => null);
    if (picked !== null) {
      await p.click('[data-h44-pick]').catch(() => {});
      ok = await waitFor(showsC3, 8000);
      how = `after choosing run ${A.run} ("${picked}") in the session's runs`;
    }
  }
  if (!ok) bad.push(`while run ${A.run + 1} coasts the bench page does not show run ${A.run}'s fit (c3 ${A.c3_digits}) to print, not even after choosing run ${A.run} in the session's runs`);
  await p.evaluate(HELPERS).catch(() => {});
  await sleep(1500);
  const stBefore = await api(p, A.port);
  const liveState = (stBefore.benches.find(b => b.id === A.bench) || {}).state;
  await p.emulateMediaType('print');
  await sleep(300);
  const text = await p.evaluate(() => document.body.innerText);
  const pdf = await p.pdf({format: 'A4', printBackground: true});
  await p.emulateMediaType('screen');
  const pages = pdfPages(pdf);
  const flat = text.replace(/\s+/g, ' ');
  if (pages !== 1) bad.push(`the print is ${pages} A4 pages, not one`);
  if (ok && liveState && liveState !== 'stopped' && new RegExp(`\\b${liveState}\\b`, 'i').test(flat)) bad.push(`the record of run ${A.run} prints the bench's live state "${liveState}" (run ${A.run} is stopped)`);
  if (!new RegExp(`\\brun\\s*(#|no\\.?|number)?\\s*${A.run}\\b`, 'i').test(flat)) bad.push(`the record does not name run ${A.run}`);
  if (ok && !flat.includes(A.c3_digits)) bad.push(`the record lacks run ${A.run}'s c3 ${A.c3_digits}`);
  if (!hasAny(flat, todayPatterns())) bad.push("no date of the run (today's) on the record");
  if (!/\b\d{1,2}:\d{2}\b/.test(flat)) bad.push('no time of day of the run on the record');
  if (!flat.includes(A.lab)) bad.push(`no lab name ("${A.lab}") on the record`);
  if (!new RegExp(A.j_re, 'i').test(flat)) bad.push(`no J of ${A.j_text} on the record`);
  if (!new RegExp(A.kb_re, 'i').test(flat)) bad.push(`no K_b of ${A.kb_text} on the record`);
  if (!/\b(J|K_?b|Kb|inertia|back-?EMF constant)\b[\s\S]{0,100}\b(config|bench file|bridge|default|datasheet|toml|measured)|\b(source|from)\b[\s\S]{0,40}\b(config|bench file|bridge|default|datasheet|toml)/i.test(flat))
    bad.push('the record does not say where J and K_b came from');
  // the plot as an image for the report
  const before = new Set(fs.readdirSync(dl));
  const clicked = [];
  for (let attempt = 0; attempt < 2; attempt++) {
    const sel = await p.evaluate(skip => {
      const h = window.__h;
      const re = /\bpng\b|\bsvg\b|\bimage\b|picture|(save|download|export)\b[^\n]{0,20}\b(plot|figure|graph|chart)|(plot|figure|graph|chart)\b[^\n]{0,12}\b(save|download|export)/i;
      const els = [...document.querySelectorAll('a,button,[role="button"],[role="menuitem"],input[type="button"],input[type="submit"]')].filter(h.vis);
      for (let i = 0; i < els.length; i++) {
        const e = els[i];
        const t = [e.innerText, e.value, e.title, e.getAttribute('aria-label'), e.getAttribute('download'), e.getAttribute('href')].filter(Boolean).join(' ');
        if (/\.csv\b|\bcsv\b/i.test(t) && !/png|svg/i.test(t)) continue;
        if (re.test(t) && !skip.includes(i)) { e.setAttribute('data-h44-click', String(i)); return {i, t: t.slice(0, 80)}; }
      }
      return null;
    }, clicked.map(c => c.i));
    if (!sel) break;
    clicked.push(sel);
    await p.click(`[data-h44-click="${sel.i}"]`).catch(() => {});
    const f = await waitFor(() => fs.readdirSync(dl).filter(n => !before.has(n) && !n.endsWith('.crdownload'))[0], 6000, 250);
    if (f) {
      const buf = fs.readFileSync(path.join(dl, f));
      const isPng = buf.length > 24 && buf.readUInt32BE(0) === 0x89504e47;
      const s = buf.toString('utf8', 0, Math.min(buf.length, 200000));
      const isSvg = /<svg[\s>]/.test(s) && /<(path|polyline|line|circle)\b/.test(s);
      if (isPng) { const w = buf.readUInt32BE(16); if (w < 600) bad.push(`the plot's PNG is only ${w} px wide`); }
      else if (!isSvg) bad.push(`"${sel.t}" downloaded ${f}, neither a PNG nor an SVG with the plot's lines`);
      if (bad.length) return out(false, bad.join('; '));
      return out(true, `(${how}) 1 A4 page with run ${A.run}, its date and time, lab ${A.lab}, J and K_b with their source; plot saved as ${isPng ? 'PNG' : 'SVG'} (${f})`);
    }
  }
  bad.push(clicked.length ? `clicking ${clicked.map(c => '"' + c.t + '"').join(', ')} saved no PNG/SVG of the plot` : 'no control on the bench page saves the plot as PNG or SVG for the report');
  out(false, bad.join('; '));
};

// 11. A dim room: the projector's browser in dark mode; a student prints the record from that browser on US Letter.
CASES.dark = async () => {
  await launch();
  const p = await newPage({width: 1920, height: 1080});
  await p.emulateMediaFeatures([{name: 'prefers-color-scheme', value: 'dark'}]);
  await goto(p, A.room_url);
  const ok = await waitFor(() => p.evaluate(ids => ids.every(id => window.__h.tile(id)), A.ids), 12000);
  if (!ok) return out(false, 'room tiles did not appear within 12 s');
  await sleep(1500);
  const bad = [];
  let lum = pngMeanLum(await p.screenshot({type: 'png'}));
  let how = 'prefers-color-scheme: dark';
  if (!(lum < 0.25)) {
    // a dark mode behind a control on the page
    const clicked = await p.evaluate(() => {
      const h = window.__h;
      for (const e of document.querySelectorAll('a,button,[role="button"],[role="switch"],input,label,select')) {
        if (!h.vis(e)) continue;
        const t = [e.innerText, e.value, e.title, e.getAttribute('aria-label'), e.id, e.name].filter(Boolean).join(' ');
        if (/dark|night|theme|dim/i.test(t)) {
          if (e.tagName === 'SELECT') { const o = [...e.options].find(o => /dark|night|dim/i.test(o.text + o.value)); if (o) { e.value = o.value; e.dispatchEvent(new Event('change', {bubbles: true})); return t; } }
          e.click(); return t;
        }
      }
      return null;
    });
    if (clicked) { await sleep(800); lum = pngMeanLum(await p.screenshot({type: 'png'})); how = `the page's "${clicked.slice(0, 30)}" control`; }
  }
  const names = await p.evaluate(ids => ids.map(id => {
    const h = window.__h, t = h.tile(id); const nb = t && h.nameBox(t, id);
    if (!nb) return [id, 0];
    const el = document.elementFromPoint(nb.rect.left + nb.rect.width / 2, nb.rect.top + nb.rect.height / 2) || t;
    return [id, h.contrast(h.fg(el), h.bg(el))];
  }), A.ids);
  if (!(lum < 0.25)) bad.push(`the room is bright in a dark-mode browser (mean screen luminance ${lum.toFixed(2)}; no dark mode by preference or by a control)`);
  const low = names.filter(n => n[1] < 4.5);
  if (low.length) bad.push(`bench names with contrast < 4.5:1 on their tile: ${low.slice(0, 4).map(n => `${n[0]} ${n[1].toFixed(1)}`).join(', ')}`);
  // print the bench page from this (dark) browser on US Letter
  const p2 = await newPage({width: 1280, height: 900});
  await p2.emulateMediaFeatures([{name: 'prefers-color-scheme', value: 'dark'}]);
  await goto(p2, A.bench_url);
  await waitFor(() => p2.evaluate(() => [...document.querySelectorAll('[data-field="c3"]')].some(e => /\d/.test(e.innerText))), 12000);
  await sleep(1500);
  if (how !== 'prefers-color-scheme: dark') {
    await p2.evaluate(() => { for (const e of document.querySelectorAll('a,button,[role="button"],[role="switch"],input,label')) { const t = [e.innerText, e.title, e.getAttribute('aria-label'), e.id].filter(Boolean).join(' '); if (/dark|night|theme|dim/i.test(t) && window.__h.vis(e)) { e.click(); break; } } });
    await sleep(500);
  }
  await p2.emulateMediaType('print');
  await sleep(300);
  const pr = await p2.evaluate(() => {
    const h = window.__h;
    const ink = [];
    for (const e of document.querySelectorAll('[data-field="c3"],[data-field="c4"],h1,h2')) {
      if (!h.vis(e)) continue;
      ink.push([e.tagName.toLowerCase() + (e.dataset.field ? '.' + e.dataset.field : ''), h.contrast(h.fg(e), h.bg(e, true))]);
    }
    const controls = [...document.querySelectorAll('button,input,select,textarea,[role="button"]')].filter(h.vis).map(e => (e.innerText || e.value || e.tagName).trim().slice(0, 30));
    const t = document.body.innerText;
    const ui = (t.match(/print for the lab report|download[^\n]{0,20}|← ?all benches|all benches/gi) || []).slice(0, 3);
    return {ink, controls, ui};
  });
  const pdf = await p2.pdf({format: 'Letter'});
  const pages = pdfPages(pdf);
  if (pages !== 1) bad.push(`printed on US Letter the record is ${pages} pages`);
  const pale = pr.ink.filter(x => x[1] < 4.5);
  if (!pr.ink.length) bad.push('nothing of c3/c4/headings is printed');
  if (pale.length) bad.push(`printed from dark mode, text is pale on white paper: ${pale.slice(0, 3).map(x => `${x[0]} ${x[1].toFixed(1)}:1`).join(', ')}`);
  if (pr.controls.length) bad.push(`on-screen controls printed: ${pr.controls.slice(0, 3).join(', ')}`);
  if (pr.ui.length) bad.push(`page navigation printed: ${pr.ui.join(', ')}`);
  if (bad.length) return out(false, bad.join('; '));
  out(true, `dark room via ${how} (luminance ${lum.toFixed(2)}, names >= ${Math.min(...names.map(n => n[1])).toFixed(1)}:1); printed on one Letter page in dark ink, no controls`);
};

(async () => {
  const fn = CASES[CASE];
  if (!fn) { out(false, `unknown case ${CASE}`); return; }
  try { await fn(); } catch (e) { out(false, `error: ${e && e.message ? e.message.split('\n')[0] : e}`); }
})().finally(async () => {
  if (browser) { try { await Promise.race([browser.close(), sleep(5000)]); } catch (e) { /* ignore */ } }
  killAll();
  process.exit(0);
});
