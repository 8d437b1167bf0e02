#!/usr/bin/python3
"""The lab's three benches: physics chosen first, truth computed here from the physics
(independently of the project's simulator), then handed to spindown-virtual-bench.

A brushed motor with flywheel, J = 1.12687602e-5 kg*m^2, K_b = 1/123.569311 V*s/rad (the lab's,
design.md sec. 1). Supply cut at back-EMF e0, so w0 = e0/K_b. Combined friction
T = c_v*w + c_c: J dw/dt = -(c_v w + c_c) until w = 0, then it stays 0 (c_c holds it), so
    w(t) = -c_c/c_v + (w0 + c_c/c_v) exp(-c_v t / J),   t_stop = (J/c_v) ln(1 + c_v w0 / c_c).
The fitter's combined model c3*w + c4 is exactly this, so the truth is c3 = c_v, c4 = c_c.
Usage: benches.py OUT.json   (deterministic: fixed seeds, no randomness here)."""
import json, math, sys

J = 1.12687602e-5
KB = 1 / 123.569311
COMMON = dict(lead_in_s=3.0, tail_s=3.0, idle_s=1.0, noise=0.003, period_ms=20.0)
BENCHES = [
    # bench-a records 6 s after each stop (not 3): the final looks at its bench page happen after its
    # second FIT and before its third cut, so the page shows a fitted run when it is printed.
    dict(id='bench-a', viscous=2.0e-7, coulomb=2.5e-4, e0=3.0, seed=3401, runs=4, tail_s=6.0),
    dict(id='bench-b', viscous=3.0e-7, coulomb=3.0e-4, e0=3.0, seed=3402, runs=5),
    dict(id='bench-c', viscous=4.0e-7, coulomb=3.5e-4, e0=2.8, seed=3403, runs=6),
]

def truth(b):
    w0 = b['e0'] / KB
    t_stop = (J / b['viscous']) * math.log(1 + b['viscous'] * w0 / b['coulomb'])
    # Bench timeline (bench seconds; the bench boots 0.5 s before its first line, design of the
    # virtual bench as its --help says: lead-in, cut, coast, stop, tail, idle, next run).
    return dict(w0=w0, t_stop_s=t_stop, c3=b['viscous'], c4=b['coulomb'])

out = dict(J=J, Kb=KB, common=COMMON, benches=[])
for b in BENCHES:
    d = dict(COMMON); d.update(b); d['truth'] = truth(b)
    out['benches'].append(d)
json.dump(out, open(sys.argv[1], 'w'), indent=1)
