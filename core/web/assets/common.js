// spindown-web: what the room page and the bench page share — the live stream (Server-Sent
// Events from /events: a snapshot, then the changes; pushed, never polled) and small DOM helpers.
// Every text from the lab goes into the page as text (textContent), never as HTML.
"use strict";

const spindown = (() => {
  // el("li", {class: "x", "data-curve": "viscous"}, "text", child…)
  function el(tag, attrs, ...children) {
    const e = document.createElement(tag);
    for (const [k, v] of Object.entries(attrs || {})) {
      if (v === null || v === undefined || v === false) continue;
      e.setAttribute(k, v === true ? "" : String(v));
    }
    for (const c of children) {
      if (c === null || c === undefined) continue;
      e.append(c instanceof Node ? c : document.createTextNode(String(c)));
    }
    return e;
  }

  function setText(e, text) {
    const t = text === null || text === undefined || text === "" ? "–" : String(text);
    if (e.textContent !== t) e.textContent = t;
  }

  // The units coefficients are read in: the lab's (g·cm²…) or SI. What spindown-web was started
  // with (--si-units) until the page's toggle chooses; the choice is kept in this browser.
  let chosenUnits = null, serverLabUnits = true;
  try { chosenUnits = localStorage.getItem("spindown-units"); } catch (e) { /* private mode: not kept */ }
  const units = () => (chosenUnits === "lab" || chosenUnits === "si" ? chosenUnits : serverLabUnits ? "lab" : "si");
  const unitsListeners = [];
  const unitButtons = [];
  function showUnits() {
    for (const b of unitButtons) {
      b.textContent = units() === "lab" ? "units: g·cm² (lab) → SI" : "units: SI → g·cm² (lab)";
      b.setAttribute("data-units", units());
    }
    document.documentElement.setAttribute("data-units", units());
  }
  // The lab's own default (the "lab" part of a snapshot: its lab_units).
  function serverUnits(labUnits) {
    if (typeof labUnits !== "boolean" || labUnits === serverLabUnits) return;
    serverLabUnits = labUnits;
    unitsChanged();
  }
  function unitsChanged() {
    showUnits();
    for (const e of document.querySelectorAll("[data-si]")) if (e.spindownCoef) setCoefficient(e, e.spindownCoef, e.spindownRun);
    for (const f of unitsListeners) f(units());
  }
  // A button that switches the units (every coefficient on the page at once); f(units) after.
  function unitsToggle(button, f) {
    unitButtons.push(button);
    if (f) unitsListeners.push(f);
    button.addEventListener("click", () => {
      chosenUnits = units() === "lab" ? "si" : "lab";
      try { localStorage.setItem("spindown-units", chosenUnits); } catch (e) { /* not kept */ }
      unitsChanged();
    });
    showUnits();
  }
  // A value's text ("text", "total_text") in the page's units; the service's own when it has no other.
  function inUnits(c, key = "text") { return c[`${key}_${units()}`] || c[key]; }

  // A coefficient's field: its text in the page's units with ± error, the SI value in data-si.
  function setCoefficient(e, c, fitRun) {
    if (!c || c.value === null || c.value === undefined) {
      setText(e, "–");
      e.removeAttribute("data-si");
      e.removeAttribute("data-si-stderr");
      e.removeAttribute("data-fit-run");
      e.spindownCoef = null;
      e.title = "";
      return;
    }
    e.spindownCoef = c;
    e.spindownRun = fitRun;
    setText(e, inUnits(c));
    e.setAttribute("data-si", String(c.value));
    if (c.stderr !== null && c.stderr !== undefined) e.setAttribute("data-si-stderr", String(c.stderr));
    if (fitRun !== undefined) e.setAttribute("data-fit-run", String(fitRun));
    e.title = `${c.value} ± ${c.stderr} ${c.unit} (SI)` + (c.total_text ? `; with J and K_b: ${inUnits(c, "total_text")}` : "");
  }

  function setHealth(e, fit) {
    const h = fit ? fit.health : "";
    setText(e, h || "–");
    if (h) e.setAttribute("data-health", h); else e.removeAttribute("data-health");
    e.title = fit && fit.health_reason ? fit.health_reason : "";
  }

  // The fit's doubts, after what is known of its source: a fit no fitter of the lab vouches for, and
  // messages for the bench the lab's gate refused (summary: the bench's summary, when known).
  function setDoubts(e, fit, summary) {
    const doubts = [];
    if (fit && fit.not_verified) doubts.push(`NOT VERIFIED: ${fit.not_verified}`);
    if (summary && summary.refused_recent) doubts.push(`messages for this bench refused: ${summary.refused_recent}`);
    if (fit && fit.doubts) doubts.push(...fit.doubts);
    e.setAttribute("data-count", String(doubts.length));
    const now = Array.from(e.children).map((c) => c.textContent);
    if (now.length === doubts.length && now.every((t, i) => t === doubts[i])) return;
    e.replaceChildren(...doubts.map((d) => el("li", {}, d)));
  }

  function setBridge(e, bridge) {
    const health = bridge ? bridge.health : "silent";
    setText(e, health);
    e.setAttribute("data-bridge", health);
  }

  function bridgeDetail(bridge) {
    if (!bridge) return "";
    const parts = [];
    if (bridge.state) parts.push(bridge.state);
    if (bridge.rate_hz) parts.push(`${bridge.rate_hz} Hz`);
    if (bridge.reconnects) parts.push(`replugged ${bridge.reconnects}×`);
    if (bridge.error) parts.push(bridge.error.length > 70 ? bridge.error.slice(0, 69) + "…" : bridge.error);
    return parts.join(" · ");
  }

  function servicesText(lab) {
    if (!lab || !lab.services || lab.services.length === 0) return "no fitter heard yet";
    return lab.services.map((s) => `${s.service} ${s.state}`).join(" · ");
  }

  function problemsText(lab) {
    if (!lab) return "";
    const p = [];
    if (lab.bad_messages) p.push(`${lab.bad_messages} undecodable message(s)`);
    if (lab.refused_messages) p.push(`${lab.refused_messages} refused message(s) not shown (${lab.last_refused})`);
    return p.join("; ");
  }

  // The live stream: handlers.snapshot/bench/samples/detail/roster/lab(data). Reconnects by
  // itself (EventSource), and after a refusal (503: too many pages) every 5 s. The server sends
  // something (an event, else a "tick") at least every 2 s: heard nothing for 6 s, the page says
  // it is stale and for how long, whatever the socket claims (a frozen server, a network gone).
  function live(bench, handlers) {
    const url = "/events" + (bench ? "?bench=" + encodeURIComponent(bench) : "");
    let source = null;
    let heard = Date.now();
    let stale = false;
    const status = document.getElementById("connection");
    const connected = (yes, text) => {
      document.body.setAttribute("data-connected", yes ? "true" : "false");
      if (status) status.textContent = text;
    };
    const fresh = () => {
      heard = Date.now();
      if (stale) {
        stale = false;
        document.body.removeAttribute("data-stale");
        connected(true, "live");
      }
    };
    setInterval(() => {
      const quiet = (Date.now() - heard) / 1000;
      if (quiet < 6) return;
      stale = true;
      document.body.setAttribute("data-stale", "true");
      connected(false, `stale: nothing heard from spindown-web for ${Math.round(quiet)} s — what is shown may be old`);
    }, 1000);
    const open = () => {
      source = new EventSource(url);
      source.onopen = () => {
        fresh();
        connected(true, "live");
      };
      source.addEventListener("tick", fresh);
      source.onerror = () => {
        connected(false, "reconnecting…");
        if (source.readyState === EventSource.CLOSED) {
          source = null;
          setTimeout(open, 5000);
        }
      };
      for (const name of ["snapshot", "bench", "samples", "detail", "roster", "lab"]) {
        source.addEventListener(name, (ev) => {
          fresh();
          if (!handlers[name]) return;
          let data;
          try {
            data = JSON.parse(ev.data);
          } catch (e) {
            return;
          }
          handlers[name](data);
        });
      }
    };
    open();
  }

  return { el, setText, setCoefficient, setHealth, setDoubts, setBridge, bridgeDetail, servicesText, problemsText, live,
           unitsToggle, serverUnits, inUnits };
})();
