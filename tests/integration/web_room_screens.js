// web_room_screens.sh's browser: opens the room page at each size and checks that the room fits
// the screen (see the script's header). Prints one line per screen; exit 1 on any failure.
"use strict";
const puppeteer = require("puppeteer-core");

const args = process.argv.slice(2);
const opt = { room: [], small: [], phone: [] };
for (let i = 0; i < args.length; i += 2) {
  const k = args[i].replace(/^--/, "");
  if (Array.isArray(opt[k])) opt[k].push(args[i + 1]);
  else opt[k] = args[i + 1];
}
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

// In the page: the layout as a room needs it; returns {bad: [...], cover, tileH, canvas}.
function layout(n, minFont) {
  const bad = [], de = document.scrollingElement || document.documentElement;
  if (de.scrollHeight > innerHeight + 1) bad.push(`the page scrolls: ${de.scrollHeight} px for ${innerHeight}`);
  if (de.scrollWidth > innerWidth + 1) bad.push(`the page scrolls sideways: ${de.scrollWidth} px for ${innerWidth}`);
  const tiles = [...document.querySelectorAll("[data-bench]")];
  if (tiles.length !== n) bad.push(`${tiles.length} tiles for ${n} benches`);
  const inside = (r, R, tol = 1) => r.left >= R.left - tol && r.top >= R.top - tol && r.right <= R.right + tol && r.bottom <= R.bottom + tol;
  const vp = { left: 0, top: 0, right: innerWidth, bottom: innerHeight };
  const rects = [];
  let area = 0, canvas = 0;
  for (const t of tiles) {
    const id = t.dataset.bench, r = t.getBoundingClientRect();
    rects.push([id, r]);
    area += r.width * r.height;
    if (!inside(r, vp)) bad.push(`${id}'s tile is not wholly on the screen`);
    const name = t.querySelector(".name");
    const nr = name.getBoundingClientRect();
    if (name.textContent !== id || !inside(nr, r) || !inside(nr, vp)) bad.push(`${id}'s name is not whole`);
    const top = document.elementFromPoint(nr.left + nr.width / 2, nr.top + Math.min(nr.height / 2, 8));
    if (!top || !(name === top || name.contains(top))) bad.push(`${id}'s name is covered`);
    if (parseFloat(getComputedStyle(name).fontSize) < minFont) bad.push(`${id}'s name is smaller than ${minFont} px`);
    for (const f of t.querySelectorAll('[data-field="c3"], [data-field="c4"]')) {
      if (!f.textContent.trim() || f.textContent === "–") bad.push(`${id}'s ${f.dataset.field} is empty`);
      if (!inside(f.getBoundingClientRect(), r, 2)) bad.push(`${id}'s ${f.dataset.field} is cut`);
    }
    const c = t.querySelector("canvas");
    if (c && c.offsetParent) canvas++;
  }
  for (let i = 0; i < rects.length; i++)
    for (let j = i + 1; j < rects.length; j++) {
      const a = rects[i][1], b = rects[j][1];
      if (Math.min(a.right, b.right) - Math.max(a.left, b.left) > 2 && Math.min(a.bottom, b.bottom) - Math.max(a.top, b.top) > 2)
        bad.push(`${rects[i][0]} and ${rects[j][0]} overlap`);
    }
  return { bad: bad.slice(0, 8), cover: area / (innerWidth * innerHeight), tileH: rects.length ? Math.round(rects[0][1].height) : 0, canvas };
}

async function open(browser, url, w, h, n) {
  const p = await browser.newPage();
  await p.setViewport({ width: w, height: h });
  await p.goto(url, { waitUntil: "domcontentloaded" });
  const t0 = Date.now();
  while (Date.now() - t0 < 20000) {  // every tile with its c3 (the FITs arrive at 5 Hz)
    const ok = await p.evaluate((n) => {
      const t = document.querySelectorAll('[data-bench] [data-field="c3"]');
      return t.length === n && [...t].every((e) => e.textContent !== "–");
    }, n);
    if (ok) break;
    await sleep(250);
  }
  await sleep(800);  // a few frames: the fitting runs in requestAnimationFrame
  return p;
}

(async () => {
  const browser = await puppeteer.launch({ executablePath: opt.chrome, headless: "new", args: ["--no-sandbox", "--disable-gpu"] });
  let failed = false;
  const report = (ok, what) => { console.log(`${ok ? "ok" : "FAIL"} ${what}`); if (!ok) failed = true; };
  try {
    for (const spec of opt.room) {
      const [url, w, h, n] = spec.split(",");
      const p = await open(browser, url, +w, +h, +n);
      const r = await p.evaluate(layout, +n, 14);
      await p.screenshot({ path: `${opt.out}/room-${n}-${w}x${h}.png` });
      report(r.bad.length === 0, `${n} benches at ${w}x${h}: tiles ${r.tileH} px tall${r.bad.length ? ": " + r.bad.join("; ") : ""}`);
      await p.close();
    }
    for (const spec of opt.small) {
      const [url, w, h, n] = spec.split(",");
      const p = await open(browser, url, +w, +h, +n);
      const r = await p.evaluate(layout, +n, 14);
      await p.screenshot({ path: `${opt.out}/room-${n}-${w}x${h}.png` });
      if (r.cover < 0.3) r.bad.push(`the tiles cover ${(100 * r.cover).toFixed(0)} % of the screen`);
      if (r.canvas !== +n) r.bad.push(`${r.canvas} of ${n} tiles show the run's curve`);
      report(r.bad.length === 0, `${n} benches at ${w}x${h} grow to ${(100 * r.cover).toFixed(0)} % of the screen${r.bad.length ? ": " + r.bad.join("; ") : ""}`);
      await p.close();
    }
    for (const url of opt.phone) {
      const p = await open(browser, url, 390, 844, 30);
      const sw = await p.evaluate(() => (document.scrollingElement || document.documentElement).scrollWidth);
      await p.screenshot({ path: `${opt.out}/room-phone.png` });
      report(sw <= 391, `a phone: the room is ${sw} px wide for 390`);
      await p.close();
    }
  } catch (e) {
    report(false, `browser: ${e.message}`);
  } finally {
    await browser.close();
  }
  process.exit(failed ? 1 : 0);
})();
