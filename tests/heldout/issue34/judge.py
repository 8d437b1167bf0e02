#!/usr/bin/python3
"""issue 34 held-out: judge what the browser saw against the truth.

judge.py SCRATCH BIN      -> one PASS/FAIL line per case, SUMMARY, exit 1 if any failed.
judge.py --list           -> the case ids.
judge.py --all-fail MSG   -> every case FAIL with MSG (the runner could not run the lab).

Truth: the benches' physics (benches.py, and spindown-virtual-bench's --truth files, checked
against it), the LCM log the logger recorded (FIT messages with the logger's receive time,
read by `spindown refit --live --json` for the values and by the LCM log format for the
times), the samples (`spindown export --csv --no-fits`) and the runner's own actions
(bridge killed/restarted at known times). See CASES.md."""
import json, math, os, re, struct, subprocess, sys

CASES = ['room-benches', 'console-clean', 'local-assets', 'pushed-live', 'coasting-state', 'plot-grows',
         'fit-room-1s', 'fit-bench-1s', 'fit-truth', 'lab-units', 'bench-extras', 'csv-run', 'silent-bench',
         'replugged-bench', 'phone-width', 'print-layout', 'projector', 'dead-clients', 'api-state', 'read-only']
STATES = {'idle', 'powered', 'coasting', 'stopped', 'partial', 'silent'}
BENCHES = ['bench-a', 'bench-b', 'bench-c']
LIVE_BENCH_PAGES = ['bench-a', 'bench-b']
KILLED = 'bench-c'
FIT_MS = 1000          # the FIT's numbers on the page within 1 s (issue: "within 1 s of the FIT")
SILENT_MS = 15000      # a silent bench shown within 15 s (fitter --silent default 10 s, + margin)
BACK_MS = 15000
TRUTH_REL = 0.03       # "within a few percent" of the physics truth
EQ_REL = 1e-9          # "equal to the FIT message's"

results = []
def out(cid, ok, msg):
    results.append((cid, ok, msg))

def finish():
    done = {c for c, _, _ in results}
    for c in CASES:
        if c not in done:
            results.append((c, False, 'not judged (runner error)'))
    order = {c: i for i, c in enumerate(CASES)}
    results.sort(key=lambda r: order.get(r[0], 99))
    for cid, ok, msg in results:
        print('%s %s: %s' % ('PASS' if ok else 'FAIL', cid, msg))
    n = sum(1 for r in results if r[1])
    print('SUMMARY: %d/%d passed' % (n, len(CASES)))
    sys.exit(0 if n == len(CASES) else 1)

if len(sys.argv) > 1 and sys.argv[1] == '--list':
    print('\n'.join(CASES)); sys.exit(0)
if len(sys.argv) > 1 and sys.argv[1] == '--all-fail':
    for c in CASES:
        out(c, False, sys.argv[2])
    finish()

S, BIN = sys.argv[1], sys.argv[2]

def load(p, default=None):
    try:
        with open(p) as f:
            return json.load(f)
    except Exception:
        return default

status = {}
try:
    for line in open(os.path.join(S, 'lab-status')):
        k, _, v = line.rstrip('\n').partition('=')
        status[k] = v
except OSError:
    pass
if status.get('lab_error'):
    for c in CASES:
        out(c, False, 'lab did not run: ' + status['lab_error'])
    finish()

obs = load(os.path.join(S, 'obs.json'))
if not obs:
    for c in CASES:
        out(c, False, 'the browser driver wrote no observations (see %s/browser.err)' % S)
    finish()
if obs.get('fatal') and not obs.get('pages'):
    for c in CASES:
        out(c, False, 'browser driver failed: ' + obs['fatal'])
    finish()

bconf = load(os.path.join(S, 'benches.json'))
truth_bench = {b['id']: b for b in bconf['benches']}
vtruth = {b: load(os.path.join(S, 'truth-%s.json' % b)) for b in BENCHES}
lab_problems = []
for b in BENCHES:
    vt = vtruth[b]
    if not vt:
        lab_problems.append('no truth file for ' + b); continue
    want = truth_bench[b]['truth']
    for k, w in (('c_v', want['c3']), ('c_c', want['c4'])):
        if abs(vt[k] - w) > 1e-12 * abs(w):
            lab_problems.append('%s truth %s=%g, benches.py %g' % (b, k, vt[k], w))
    for r in vt['runs']:
        if abs(r['t_stop_s'] - want['t_stop_s']) > 1e-3:
            lab_problems.append('%s run %d: virtual bench t_stop %.4f s vs physics %.4f s' % (b, r['run'], r['t_stop_s'], want['t_stop_s']))

# ---- the LCM log: event headers by the LCM log format (sync 0xEDA1DA01, big-endian) ----
logdir = os.path.join(S, 'log')
logs = sorted(os.path.join(logdir, f) for f in os.listdir(logdir) if f.endswith('.lcm')) if os.path.isdir(logdir) else []
events = []   # (t_us, channel, data)
for lp in logs:
    d = open(lp, 'rb').read(); i = 0
    while i + 28 <= len(d):
        sync, num, ts, cl, dl = struct.unpack('>IqqII', d[i:i + 28])
        if sync != 0xEDA1DA01 or cl > 1000 or i + 28 + cl + dl > len(d):
            j = d.find(b'\xed\xa1\xda\x01', i + 1)
            if j < 0:
                break
            i = j; continue
        ch = d[i + 28:i + 28 + cl].decode('latin-1')
        events.append((ts, ch, d[i + 28 + cl:i + 28 + cl + dl]))
        i += 28 + cl + dl
if not logs:
    lab_problems.append('no LCM log from the logger')

def run_json(args):
    try:
        p = subprocess.run(args, capture_output=True, timeout=60)
        return json.loads(p.stdout.decode() or 'null')
    except Exception as e:
        return None

refit = run_json([os.path.join(BIN, 'spindown'), 'refit', '--live', '--json'] + logs) if logs else None
fits_by_bench = {b: [] for b in BENCHES}
if refit:
    for f in refit.get('files', []):
        for r in f.get('runs', []):
            bid = (r.get('bench') or {}).get('id')
            if bid not in fits_by_bench:
                continue
            comb = [m for m in r['models'] if m['name'] == 'combined']
            fits_by_bench[bid].append(dict(bench=bid, run=r['run'], best=r.get('best'), samples=r.get('samples'),
                t_cut_s=r.get('t_cut_s'), t_stop_s=r.get('t_stop_s'), t_end_s=r.get('t_end_s'),
                c3=comb[0]['params']['c3']['value'] if comb else None, c3se=comb[0]['params']['c3']['stderr'] if comb else None,
                c4=comb[0]['params']['c4']['value'] if comb else None, c4se=comb[0]['params']['c4']['stderr'] if comb else None))
else:
    lab_problems.append('spindown refit --live --json gave nothing')
fit_events = {b: [e for e in events if e[1] == 'SPINDOWN.%s.FIT' % b] for b in BENCHES}
FITS = []   # with the logger's receive time
for b in BENCHES:
    rs = sorted(fits_by_bench[b], key=lambda r: r['run'])
    evs = fit_events[b]
    if len(rs) != len(evs):
        lab_problems.append('%s: %d FIT events in the log but %d runs from refit --live' % (b, len(evs), len(rs)))
    for r, e in zip(rs, evs):
        r['t_ms'] = e[0] / 1000.0
        FITS.append(r)
FITS.sort(key=lambda r: r['t_ms'])

# samples: bench, seq, device_time_s, host_time_s, value
samples = {b: [] for b in BENCHES}
if logs:
    csvp = os.path.join(S, 'log-samples.csv')
    subprocess.run([os.path.join(BIN, 'spindown'), 'export', logs[0], '--csv', '--no-fits', '-o', csvp], capture_output=True, timeout=60)
    try:
        for ln in open(csvp).read().splitlines()[1:]:
            p = ln.split(',')
            if p[0] in samples:
                samples[p[0]].append((int(p[1]), float(p[2]), float(p[3]), float(p[4]) if p[4] not in ('', 'NaN', 'nan') else float('nan')))
    except OSError:
        lab_problems.append('spindown export --csv failed')

ev = {}
for e in obs.get('events', []):
    ev.setdefault(e[0], e)
t_kill = ev.get('bridge_killed', [None, None])[1]
t_restart = ev.get('bridge_restarted', [None, None])[1]
t_end = ev.get('observation_end', [None, None])[1]
t_ready = ev.get('pages_ready', [None, None])[1]
if not t_end:
    lab_problems.append('the browser driver did not reach the end of the observation (%s)' % '; '.join(n[1] for n in obs.get('notes', []))[:300])

def dev_to_host_ms(b, td, before_ms=None):
    """host time (ms) of bench device time td, from the bridge's samples (before the kill for the killed bench)."""
    ss = samples[b]
    for (seq, dt, ht, v) in ss:
        if before_ms is not None and ht * 1000 > before_ms:
            break
        if dt >= td:
            return (ht - (dt - td)) * 1000.0
    return None

coasts = {b: [] for b in BENCHES}   # true coasts in host ms
for b in BENCHES:
    vt = vtruth[b]
    if not vt:
        continue
    lim = t_kill if b == KILLED else None
    for r in vt['runs']:
        c = dev_to_host_ms(b, r['cut_bench_s'], lim)
        s = dev_to_host_ms(b, r['cut_bench_s'] + r['t_stop_s'], lim)
        if c and s and t_end and s < t_end:
            coasts[b].append(dict(run=r['run'], cut=c, stop=s))

pages = obs.get('pages', {})
def snaps(name):
    return pages.get(name, {}).get('snaps', [])
def state_at(name, t):
    last = None
    for ts, s in snaps(name):
        if ts > t:
            break
        last = s
    return last
def tile(s, b):
    if not s:
        return None
    for t in s.get('tiles', []):
        if t.get('id') == b:
            return t
    return None
def fnum(x):
    try:
        return float(x)
    except (TypeError, ValueError):
        return None
def eq(a, b):
    a = fnum(a)
    return a is not None and b is not None and abs(a - b) <= EQ_REL * abs(b)

PRE = ('; lab: ' + '; '.join(lab_problems)) if lab_problems else ''
F = obs.get('final', {})

# ---------------- room-benches ----------------
room = snaps('room')
if not room:
    out('room-benches', False, 'no observation of the room page' + PRE)
else:
    last = room[-1][1]
    ids = sorted(t['id'] for t in last.get('tiles', []))
    bad_states = sorted({str(t.get('state')) for _, s in room for t in s.get('tiles', []) if t.get('state') not in STATES})
    ok = ids == BENCHES and not bad_states
    out('room-benches', ok, 'tiles [data-bench] at the end %s vs truth %s; data-state outside the vocabulary: %s' % (ids, BENCHES, bad_states or 'none'))

# ---------------- console-clean ----------------
errs = [e for e in obs.get('console', []) if not e.get('closing') and 'favicon.ico' not in (e.get('loc') or '') + e.get('text', '')] + [dict(e, text='pageerror: ' + e['text']) for e in obs.get('pageerrors', []) if not e.get('closing')]
out('console-clean', not errs and bool(room), '%d console errors / page errors on %d pages%s' % (len(errs), len(pages), (': ' + ' | '.join('%s: %s' % (e['page'], e['text'][:120]) for e in errs[:4])) if errs else ''))

# ---------------- local-assets ----------------
web = obs.get('web', '')
def host_ok(u):
    if u.startswith(('data:', 'blob:', 'about:')):
        return True
    m = re.match(r'^[a-z]+://([^/:]+)', u)
    return bool(m) and m.group(1) == '127.0.0.1'
reqs = obs.get('requests', [])
foreign = sorted({r['url'][:100] for r in reqs if not host_ok(r['url'])})
for k in ('room', 'bench', 'phone_room', 'phone_bench', 'print'):
    for a in (F.get(k) or {}).get('assets', []) + (F.get(k) or {}).get('resources', []):
        if a.get('url') and not host_ok(a['url']):
            foreign.append(a['url'][:100])
not_assets = sorted({r['url'][:100] for r in reqs if r['type'] in ('script', 'stylesheet', 'font') and
                     not (r['url'].startswith(web + '/assets/'))})
bad_status = sorted({'%s %d' % (r['url'][:80], r['status']) for r in obs.get('responses', [])
                     if r['status'] >= 400 and not r['url'].endswith('/favicon.ico')})
failed = sorted({'%s %s' % (r['url'][:80], r.get('err')) for r in obs.get('requestfailed', [])
                 if not r.get('closing') and r.get('err') != 'net::ERR_ABORTED'})
nscript = sum(1 for r in reqs if r['type'] == 'script' and r['url'].startswith(web + '/assets/'))
ok = not foreign and not not_assets and not bad_status and not failed and bool(reqs)
out('local-assets', ok, '%d requests; to other hosts: %s; scripts/styles/fonts not under %s/assets/: %s; HTTP errors: %s; failed: %s; %d scripts from /assets/'
    % (len(reqs), sorted(set(foreign))[:3] or 'none', web, not_assets[:3] or 'none', bad_status[:3] or 'none', failed[:3] or 'none', nscript))

# ---------------- pushed-live ----------------
live_names = ['room'] + ['bench:' + b for b in LIVE_BENCH_PAGES]
msgs = []; ok = True
for n in live_names:
    nav = sum(1 for r in reqs if r['page'] == n and r['type'] == 'document')
    stream = [r for r in reqs if r['page'] == n and r['type'] in ('eventsource', 'websocket')]
    conn0 = pages.get(n, {}).get('connected_ms')
    conn_end = (F.get('pages') or {}).get(n)
    good = nav == 1 and stream and conn0 == 'yes' and conn_end == 'true'
    ok = ok and bool(good)
    msgs.append('%s: document loads %s (1: never reloaded), %s stream %s, data-connected in 5 s %s, at end %s' % (n, nav, len(stream), stream[0]['type'] if stream else '-', conn0, conn_end))
E = F.get('events') or {}
eok = E.get('status') == 200 and str(E.get('ctype', '')).lower().startswith('text/event-stream') and (E.get('data_lines') or 0) >= 1
ok = ok and eok
msgs.append('GET /events: %s %r, %s data lines in 5 s%s' % (E.get('status'), E.get('ctype'), E.get('data_lines'), (' ' + E['error']) if E.get('error') else ''))
out('pushed-live', ok, '; '.join(msgs))

# ---------------- coasting-state ----------------
msgs = []; ok = True; n = 0
for b in BENCHES:
    for c in coasts[b]:
        if t_ready and c['cut'] < t_ready:
            continue
        mid = (c['cut'] + c['stop']) / 2
        st = (tile(state_at('room', mid), b) or {}).get('state')
        n += 1
        f = [x for x in FITS if x['bench'] == b and x['t_ms'] > c['stop'] - 1000]
        after = None
        if f and f[0]['t_ms'] + 1500 < t_end:
            after = (tile(state_at('room', f[0]['t_ms'] + 1500), b) or {}).get('state')
        good = st == 'coasting' and (after is None or after in ('stopped', 'idle'))
        ok = ok and good
        if not good or len(msgs) < 2:
            msgs.append('%s run %d: mid-coast %r (truth coasting), FIT+1.5 s %r (truth stopped/idle)' % (b, c['run'], st, after))
if n == 0:
    ok = False; msgs.append('no true coast observed')
out('coasting-state', ok, '%d true coasts checked; ' % n + '; '.join(msgs) + PRE)

# ---------------- plot-grows ----------------
msgs = []; ok = True; n = 0
for b in LIVE_BENCH_PAGES:
    name = 'bench:' + b
    for c in coasts[b]:
        if t_ready and c['cut'] < t_ready:
            continue
        w0, w1 = c['cut'] + 1000, c['stop'] - 500
        v0 = fnum((state_at(name, w0) or {}).get('points'))
        v1 = fnum((state_at(name, w1) or {}).get('points'))
        seq = [fnum(s.get('points')) for ts, s in snaps(name) if w0 <= ts <= w1]
        inc = sum(1 for x, y in zip(seq, seq[1:]) if x is not None and y is not None and y > x)
        good = v0 is not None and v1 is not None and v1 > v0 and inc >= 5
        n += 1; ok = ok and good
        msgs.append('%s run %d: data-points %s at cut+1 s -> %s at stop-0.5 s, %d increases (need growth, >= 5)' % (b, c['run'], v0, v1, inc))
if n == 0:
    ok = False; msgs.append('no true coast observed on a bench page')
out('plot-grows', ok, '; '.join(msgs) + PRE)

# ---------------- fit-room-1s / fit-bench-1s / fit-truth ----------------
def fit_shown(name, f, on_room):
    """first time (ms) after the FIT at which the page shows its c3/c4 (or a FIT of the same bench
    that followed within 1 s), and the page's state at FIT + 1 s."""
    later = [x for x in FITS if x['bench'] == f['bench'] and f['t_ms'] < x['t_ms'] <= f['t_ms'] + FIT_MS]
    ok_vals = [f] + later
    first = None
    for ts, s in snaps(name):
        if ts < f['t_ms'] - 2000:
            continue
        src = tile(s, f['bench']) if on_room else s
        if src and any(eq(src.get('c3'), x['c3']) and eq(src.get('c4'), x['c4']) for x in ok_vals):
            first = ts; break
    return first, state_at(name, f['t_ms'] + FIT_MS)

eligible = [f for f in FITS if t_end and f['t_ms'] < t_end - 1500 and (not t_ready or f['t_ms'] > t_ready)]
msgs = []; ok = bool(eligible); lat = []
for f in eligible:
    first, s = fit_shown('room', f, True)
    d = None if first is None else first - f['t_ms']
    good = d is not None and d <= FIT_MS
    t = tile(s, f['bench']) or {}
    best_ok = f['best'] and t.get('best') and f['best'].lower() in t['best'].lower()
    good = good and bool(best_ok)
    ok = ok and good
    if d is not None:
        lat.append(d)
    if not good or len(msgs) < 1:
        msgs.append('%s run %d: c3/c4 = FIT (%.6g, %.6g) shown %s after the FIT (<= %d ms); best %r vs FIT %r'
                    % (f['bench'], f['run'], f['c3'], f['c4'], 'never' if d is None else '%.0f ms' % d, FIT_MS, t.get('best'), f['best']))
out('fit-room-1s', ok, '%d FITs; latency max %s ms; ' % (len(eligible), '%.0f' % max(lat) if lat else '-') + '; '.join(msgs[:5]) + PRE)

msgs = []; ok = True; lat = []; n = 0
for f in eligible:
    if f['bench'] not in LIVE_BENCH_PAGES:
        continue
    n += 1
    name = 'bench:' + f['bench']
    first, s = fit_shown(name, f, False)
    d = None if first is None else first - f['t_ms']
    s = s or {}
    good = d is not None and d <= FIT_MS and sorted(s.get('curves') or []) == ['combined', 'coulomb', 'viscous'] \
        and s.get('cut') and s.get('stop') and s.get('residuals')
    ok = ok and bool(good)
    if d is not None:
        lat.append(d)
    if not good or len(msgs) < 1:
        msgs.append('%s run %d: c3/c4 = FIT shown %s after the FIT; at FIT+1 s curves %s, markers cut %s stop %s, residuals %s'
                    % (f['bench'], f['run'], 'never' if d is None else '%.0f ms' % d, s.get('curves'), s.get('cut'), s.get('stop'), s.get('residuals')))
ok = ok and n > 0
out('fit-bench-1s', ok, '%d FITs on bench pages; latency max %s ms; ' % (n, '%.0f' % max(lat) if lat else '-') + '; '.join(msgs[:5]) + PRE)

msgs = []; ok = True; n = 0
for f in eligible:
    if f['bench'] == KILLED and t_kill and f['t_ms'] > t_kill:
        continue   # its coast was cut by the bridge kill
    tr = truth_bench[f['bench']]['truth']
    t = tile(state_at('room', f['t_ms'] + FIT_MS), f['bench']) or {}
    c3, c4 = fnum(t.get('c3')), fnum(t.get('c4'))
    n += 1
    good = c3 is not None and c4 is not None and abs(c3 - tr['c3']) <= TRUTH_REL * tr['c3'] and abs(c4 - tr['c4']) <= TRUTH_REL * tr['c4']
    ok = ok and good
    if not good or len(msgs) < 3:
        msgs.append('%s run %d: shown c3 %s (truth %g, %s), c4 %s (truth %g, %s)' % (
            f['bench'], f['run'], '%.4g' % c3 if c3 else None, tr['c3'], '%+.2f %%' % (100 * (c3 / tr['c3'] - 1)) if c3 else '-',
            '%.4g' % c4 if c4 else None, tr['c4'], '%+.2f %%' % (100 * (c4 / tr['c4'] - 1)) if c4 else '-'))
ok = ok and n > 0
out('fit-truth', ok, '%d runs, tolerance %.0f %%: ' % (n, 100 * TRUTH_REL) + '; '.join(msgs[:6]) + PRE)

# ---------------- lab-units ----------------
SUP = str.maketrans('⁰¹²³⁴⁵⁶⁷⁸⁹⁻⁺', '0123456789-+')
NUM = r'[-+]?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?'
def parse_pm(text):
    t = (text or '').replace('\u2212', '-').replace('\u00a0', ' ').replace('\u202f', ' ')
    m = re.search(r'\(?\s*(' + NUM + r')\s*(?:±|\+/-|\+-)\s*(' + NUM + r')\s*\)?(?:\s*(?:[eE]([-+]?\d+)|[×x]\s*10\^?\s*([-+⁻⁺]?[0-9⁰¹²³⁴⁵⁶⁷⁸⁹]+)))?', t)
    if not m:
        return None
    e = m.group(3) or (m.group(4).translate(SUP) if m.group(4) else '0')
    k = 10.0 ** int(e)
    return float(m.group(1)) * k, float(m.group(2)) * k
R = F.get('room') or {}
msgs = []; ok = bool(R.get('tiles'))
for tl in R.get('tiles', []):
    b = tl['id']
    fs = [f for f in FITS if f['bench'] == b and f['t_ms'] <= R.get('t', 0)]
    if not fs:
        ok = False; msgs.append('%s: no FIT before the look' % b); continue
    for key, se in (('c3', 'c3se'), ('c4', 'c4se')):
        el = tl.get(key) or {}
        si = fnum(el.get('si')); pm = parse_pm(el.get('text'))
        unit = bool(re.search(r'g\s*[·.*⋅ ]?\s*cm', el.get('text') or ''))
        fit = [f for f in fs if eq(si, f[key])]
        good = bool(fit) and pm is not None and unit
        if good:
            lab, err = si * 1e7, fit[-1][se] * 1e7
            good = abs(pm[0] - lab) <= max(pm[1], 0.005 * abs(lab)) and 0.6 <= pm[1] / err <= 1.7
        ok = ok and good
        if not good or len(msgs) < 2:
            msgs.append('%s %s: text %r, data-si %s (FIT %s), truth in lab units %.5g ± %.2g g·cm²…' % (
                b, key, (el.get('text') or '')[:60], el.get('si'), 'equal' if fit else 'DIFFERENT',
                (si or 0) * 1e7, (fit[-1][se] * 1e7) if fit else float('nan')))
    h = (tl.get('health') or {}).get('text') or ''
    bt = (tl.get('best') or {}).get('text') or ''
    good = bool(re.search(r'not\s*judged', h, re.I)) and 'combined' in bt.lower()
    ok = ok and good
    if not good:
        msgs.append('%s: health %r (truth: not judged — no bench file), best %r (truth: combined)' % (b, h[:40], bt[:40]))
out('lab-units', ok, '; '.join(msgs[:6]) or 'no room look')

# ---------------- bench-extras ----------------
Bf = F.get('bench') or {}
msgs = []; ok = bool(Bf) and 'error' not in Bf
steps = Bf.get('steps') or []
good = len(steps) == 1 and 'coulomb' in steps[0].lower()
sch = obs.get('schedule') or {}
a3 = dev_to_host_ms(LIVE_BENCH_PAGES[0], vtruth[LIVE_BENCH_PAGES[0]]['runs'][2]['cut_bench_s']) if vtruth.get(LIVE_BENCH_PAGES[0]) else None
late_look = bool(a3 and Bf.get('t', 0) > a3)
if late_look and not steps:
    good = True   # the look came after the next cut: a page may clear the story of the run before
ok = ok and good
msgs.append('explain steps %d %s (truth: 1, adding coulomb: the bench has viscous+coulomb, base viscous)%s' % (len(steps), [s[:50] for s in steps],
            ' [look taken after the next cut]' if late_look else ''))
fa = [f for f in FITS if f['bench'] == LIVE_BENCH_PAGES[0] and f['t_ms'] <= Bf.get('t', 0) - 2000]
runs = Bf.get('runs') or []
want = [str(f['run']) for f in fa]
maxrun = max([f['run'] for f in FITS if f['bench'] == LIVE_BENCH_PAGES[0]] or [0]) + 1
good = all(w in runs for w in want) and all((fnum(r) or 0) <= maxrun for r in runs) and len(runs) == len(set(runs))
ok = ok and good
msgs.append('[data-run] %s vs fitted earlier runs %s' % (runs, want))
cl = F.get('csv_link') or {}
m = re.match(re.escape(web) + r'/bench/' + LIVE_BENCH_PAGES[0] + r'/runs/(\d+)\.csv$', cl.get('url') or '')
good = bool(m) and cl.get('status') == 200 and (cl.get('rows') or 0) >= 2
ok = ok and good
msgs.append('CSV link %s -> %s, %s lines' % (cl.get('url'), cl.get('status'), cl.get('rows')))
out('bench-extras', ok, '; '.join(msgs) + PRE)

# ---------------- csv-run ----------------
C = F.get('csv') or {}
msgs = []; ok = True; n = 0
sa = samples[LIVE_BENCH_PAGES[0]]
for f in [x for x in FITS if x['bench'] == LIVE_BENCH_PAGES[0]][:2]:
    c = C.get(str(f['run'])) or {}
    n += 1
    rows = []; hdr = None
    try:
        lines = open(os.path.join(S, c.get('file', 'none'))).read().replace('\r', '').split('\n')
        hdr = lines[0]
        for ln in lines[1:]:
            if ln.strip():
                p = ln.split(',')
                rows.append((float(p[0]), float(p[1])))
    except Exception as e:
        msgs.append('run %d: %s %s unreadable (%s)' % (f['run'], c.get('url'), c.get('status'), str(e)[:60])); ok = False; continue
    good = c.get('status') == 200 and hdr and re.search(r'[A-Za-z]', hdr) and len(rows) >= f['samples']
    start = None
    if good:
        vals = [s[3] for s in sa]
        for i in range(len(sa) - len(rows) + 1):
            if all(abs(vals[i + k] - rows[k][1]) <= 1e-6 for k in range(len(rows))) and \
               all(abs((sa[i + k][1] - sa[i][1]) - (rows[k][0] - rows[0][0])) <= 1e-3 for k in range(len(rows))):
                start = i; break
        good = start is not None
    cover = None
    if good:
        d0, d1 = sa[start][1], sa[start + len(rows) - 1][1]
        cover = (d0, d1)
        good = d0 <= f['t_cut_s'] + 0.025 and d1 >= (f['t_stop_s'] or 0) - 1e-6   # the first coast sample lies < 1 period after the cut
        vmax = max(r[1] for r in rows)
        e0 = truth_bench[f['bench']]['e0']
        good = good and abs(vmax - e0) <= 0.05
    ok = ok and bool(good)
    msgs.append('run %d: HTTP %s, %d rows (FIT fitted %s samples), %s, device %s s vs FIT cut %.3f stop %.3f'
                % (f['run'], c.get('status'), len(rows), f['samples'],
                   'a contiguous stretch of the bridge\'s samples, same times' if start is not None else 'NOT the bridge\'s samples',
                   '%.3f..%.3f' % cover if cover else '-', f['t_cut_s'], f['t_stop_s'] or float('nan')))
ok = ok and n > 0
out('csv-run', ok, '; '.join(msgs) + PRE)

# ---------------- silent-bench / replugged-bench ----------------
def first_after(t0, pred, limit):
    for ts, s in room:
        if ts >= t0 and ts <= t0 + limit and pred(tile(s, KILLED) or {}):
            return ts
    return None
live_word = re.compile(r'\bok\b|(?<!dis)connected', re.I)
if not t_kill:
    out('silent-bench', False, 'the bridge was not killed (runner: %s)' % obs.get('notes'))
    out('replugged-bench', False, 'the bridge was not killed')
else:
    ts = first_after(t_kill, lambda t: t.get('state') == 'silent', SILENT_MS)
    br = (tile(state_at('room', (t_restart or t_kill + SILENT_MS) - 10), KILLED) or {}).get('bridge')
    T0 = float(status.get('t0_ms') or 0)
    others = sorted({'%s@%+.0fs' % (t['id'], (tt - t_kill) / 1000) for tt, s in room for t in s.get('tiles', [])
                     if t.get('state') == 'silent' and T0 and tt > T0 + 8000 and
                     ((t['id'] != KILLED and tt < (t_end or 0)) or (t['id'] == KILLED and tt < t_kill))})
    ok = ts is not None and br is not None and not live_word.search(br) and not others
    out('silent-bench', ok, '%s bridge SIGKILLed: data-state "silent" %s (<= %d s); bridge field before the restart %r (truth: not ok/connected); wrongly silent: %s'
        % (KILLED, 'after %.1f s' % ((ts - t_kill) / 1000) if ts else 'never', SILENT_MS // 1000, br, others[:4] or 'none'))
    if not t_restart:
        out('replugged-bench', False, 'the bridge was not restarted')
    else:
        tb = first_after(t_restart, lambda t: t.get('state') in STATES - {'silent'} and t.get('bridge') and not re.search('silent', t['bridge'], re.I), BACK_MS)
        fin = tile(room[-1][1], KILLED) if room else {}
        out('replugged-bench', tb is not None, 'bridge restarted: live state and bridge field without "silent" %s (<= %d s); at the end state %r, bridge %r'
            % ('after %.1f s' % ((tb - t_restart) / 1000) if tb else 'never', BACK_MS // 1000, (fin or {}).get('state'), (fin or {}).get('bridge')))

# ---------------- phone-width ----------------
msgs = []; ok = True
def visible(v, width):
    return bool(v) and v['w'] > 0 and v['h'] > 0 and v['display'] != 'none' and v['visibility'] == 'visible' and \
        v['opacity'] > 0.1 and v['x'] >= -1 and v['right'] <= width + 1 and bool(v['text'])
for k in ('phone_room', 'phone_bench'):
    P = F.get(k) or {}
    if not P or 'error' in P:
        ok = False; msgs.append('%s: %s' % (k, P.get('error'))); continue
    els = [(t['id'] + ' ' + q, t.get(q)) for t in P.get('tiles', []) for q in ('c3', 'c4')] if k == 'phone_room' else [('c3', P.get('c3')), ('c4', P.get('c4'))]
    bad = [n for n, v in els if not visible(v, 390)]
    good = P.get('scrollWidth', 9999) <= 391 and els and not bad and P.get('waited_ok') and (k != 'phone_room' or len(P.get('tiles', [])) == 3)
    ok = ok and bool(good)
    msgs.append('%s: scrollWidth %s (<= 391), c3/c4 not visible within 390 px: %s, fields filled %s' % (k, P.get('scrollWidth'), bad or 'none', P.get('waited_ok')))
out('phone-width', ok, '; '.join(msgs))

# ---------------- print-layout ----------------
P = F.get('print') or {}
msgs = []; ok = bool(P) and 'error' not in P
if ok:
    counts = {}
    for fn in P.get('pdf', []):
        try:
            data = open(os.path.join(S, fn), 'rb').read()
            counts[fn] = len(re.findall(rb'/Type\s*/Page(?![A-Za-z])', data))
        except OSError:
            counts[fn] = None
    vis = {k: visible(P.get(k), 10 ** 6) for k in ('c3', 'c4', 'plot')} if P else {}
    vis['plot'] = bool(P.get('plot')) and P['plot']['w'] > 0 and P['plot']['h'] > 0 and P['plot']['display'] != 'none' and P['plot']['visibility'] == 'visible'
    ok = bool(P.get('printRule')) and counts and all(c is not None and 1 <= c <= 2 for c in counts.values()) and all(vis.values())
    msgs.append('@media print rule %s; PDF pages %s (<= 2); visible in print media %s; the page showed a fitted run: %s' % (P.get('printRule'), counts, vis, P.get('waited_ok')))
else:
    msgs.append(str(P.get('error')))
out('print-layout', ok, '; '.join(msgs))

# ---------------- projector ----------------
R = F.get('room') or {}
msgs = []; ok = len(R.get('tiles', [])) == 3
for t in R.get('tiles', []):
    bx = t.get('box') or {}
    inside = bx and bx['x'] >= -1 and bx['y'] >= -1 and bx['right'] <= 1921 and bx['bottom'] <= 1081 and bx['w'] > 0
    fonts = [(t.get(k) or {}).get('font_px') or 0 for k in ('c3', 'c4')]
    good = bool(inside) and min(fonts) >= 18
    ok = ok and good
    if not good or len(msgs) < 1:
        msgs.append('%s: tile %s inside 1920x1080 %s; c3/c4 font %s px (>= 18)' % (
            t['id'], '(%.0f,%.0f)-(%.0f,%.0f)' % (bx['x'], bx['y'], bx['right'], bx['bottom']) if bx else '-', bool(inside), fonts))
out('projector', ok, '%d tiles; ' % len(R.get('tiles', [])) + '; '.join(msgs))

# ---------------- dead-clients ----------------
tst = []
for k in (1, 2):
    try:
        tst.append(int(open(os.path.join(S, 'stalled-%d.txt' % k)).read().split()[1]))
    except Exception:
        pass
A = F.get('api_state') or {}
late = [f for f in eligible if tst and f['t_ms'] > max(tst) + 20000]
lats = []
for f in late:
    first, _ = fit_shown('room', f, True)
    lats.append(None if first is None else first - f['t_ms'])
ok = len(tst) == 2 and status.get('web_alive_at_end') == 'yes' and late and all(d is not None and d <= FIT_MS for d in lats) \
    and A.get('status') == 200 and (A.get('ms') or 9e9) <= 1000
out('dead-clients', ok, '%d stalled /events clients; %d FITs > 20 s after they stalled shown after %s ms (<= %d); /api/state in %s ms (<= 1000); web alive at end: %s'
    % (len(tst), len(late), ['-' if d is None else '%.0f' % d for d in lats], FIT_MS, '%.0f' % A['ms'] if A.get('ms') is not None else '-', status.get('web_alive_at_end')))

# ---------------- api-state ----------------
msgs = []; j = A.get('json')
ok = A.get('status') == 200 and isinstance(j, dict) and isinstance(j.get('benches'), list)
if ok:
    ids = sorted(str(b.get('id')) for b in j['benches'])
    ok = ids == BENCHES and 'json' in str(A.get('ctype', '')).lower()
    msgs.append('ids %s (truth %s), content-type %r' % (ids, BENCHES, A.get('ctype')))
    for b in j['benches']:
        bid = b.get('id')
        fs = [f for f in FITS if f['bench'] == bid]
        due = [f for f in fs if f['t_ms'] <= A['t'] - 1000]
        lf = b.get('last_fit')
        good = b.get('state') in STATES and isinstance(b.get('bridge'), dict) and due and isinstance(lf, dict)
        if good:
            cands = [f for f in fs if f['t_ms'] >= due[-1]['t_ms']]
            try:
                good = any(lf.get('run') == f['run'] and lf.get('best') == f['best'] and eq(lf['c3']['value'], f['c3']) and eq(lf['c3']['stderr'], f['c3se'])
                           and eq(lf['c4']['value'], f['c4']) and eq(lf['c4']['stderr'], f['c4se']) and isinstance(lf.get('doubts'), list) for f in cands)
            except (KeyError, TypeError):
                good = False
        ok = ok and bool(good)
        if not good or len(msgs) < 2:
            msgs.append('%s: state %r, last_fit run %s c3 %s c4 %s vs latest FIT run %s c3 %s c4 %s' % (
                bid, b.get('state'), (lf or {}).get('run'), ((lf or {}).get('c3') or {}).get('value'), ((lf or {}).get('c4') or {}).get('value'),
                due[-1]['run'] if due else None, due[-1]['c3'] if due else None, due[-1]['c4'] if due else None))
else:
    msgs.append('GET /api/state: %s %r %s' % (A.get('status'), A.get('body_head'), A.get('error') or ''))
out('api-state', ok, '; '.join(msgs[:5]) + PRE)

# ---------------- read-only ----------------
msgs = []; ok = bool(events)
allowed = set()
for b in BENCHES:
    for k in ('SAMPLE', 'CONFIG', 'STATUS', 'RUN', 'FIT', 'EXPLAIN'):
        allowed.add('SPINDOWN.%s.%s' % (b, k))
strange = sorted({e[1] for e in events if e[1] not in allowed and not re.fullmatch(r'SPINDOWN\.[A-Za-z0-9_-]{1,32}\.STATUS', e[1])})
seen = {}; dups = 0
for e in events:
    if e[1] in allowed:
        key = (e[1], e[2])
        dups += key in seen
        seen[key] = 1
runs_twice = []
for b in BENCHES:
    rr = [f['run'] for f in fits_by_bench[b]]
    runs_twice += ['%s run %d' % (b, r) for r in set(rr) if rr.count(r) > 1]
during = []
if t_kill and t_restart:
    during = sorted({e[1] for e in events if e[1] in ('SPINDOWN.%s.SAMPLE' % KILLED, 'SPINDOWN.%s.CONFIG' % KILLED, 'SPINDOWN.%s.STATUS' % KILLED)
                     and t_kill + 300 < e[0] / 1000 < t_restart - 50})
ok = ok and not strange and dups == 0 and not runs_twice and not during and bool(t_kill)
out('read-only', ok, '%d LCM events: unexpected channels %s, byte-identical repeats on bench channels %d, FITs twice for a run %s, '
    'messages on %s SAMPLE/CONFIG/STATUS while its bridge was dead %s' % (len(events), strange[:3] or 'none', dups, runs_twice or 'none', KILLED, during or 'none'))

finish()
