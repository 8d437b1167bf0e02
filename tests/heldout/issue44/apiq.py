#!/usr/bin/env python3
"""apiq.py PORT EXPR: evaluate EXPR over spindown-web's /api/state (s = the state, b(id) = a bench or {}).
Prints the value as JSON; exit 0 when it is truthy, 1 otherwise (or when the server does not answer)."""
import json
import sys
import urllib.request

port, expr = sys.argv[1], sys.argv[2]
try:
    s = json.load(urllib.request.urlopen(f"http://127.0.0.1:{port}/api/state", timeout=3))
except Exception:
    print("null")
    sys.exit(1)
B = {x.get("id"): x for x in s.get("benches", [])}


def b(i):
    return B.get(i) or {}


try:
    v = eval(expr, {"s": s, "b": b, "B": B, "len": len, "any": any, "all": all})
except Exception:
    v = None
print(json.dumps(v))
sys.exit(0 if v else 1)
