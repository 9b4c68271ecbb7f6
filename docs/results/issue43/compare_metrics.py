import json, pathlib, sys
b, a = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
NEW = {"land_lookahead","land_clearance","route","route_clearance","channel_width","bank_clearance","route_warnings"}
TIMING = ("time", "seconds", "elapsed", "wall")
def strip(o):
    if isinstance(o, dict):
        return {k: strip(v) for k, v in o.items() if k not in NEW and not any(s in k for s in TIMING) or k in ("time_to_goal","collision_time")}
    if isinstance(o, list): return [strip(v) for v in o]
    return o
def diffs(x, y, p=""):
    if type(x) != type(y): yield p; return
    if isinstance(x, dict):
        for k in set(x) | set(y):
            if k not in x or k not in y: yield p + "/" + k + "(missing)"
            else: yield from diffs(x[k], y[k], p + "/" + k)
    elif isinstance(x, list):
        if len(x) != len(y): yield p + "(len)"; return
        for i,(u,v) in enumerate(zip(x,y)): yield from diffs(u, v, f"{p}[{i}]")
    elif x != y: yield p
for f in sorted(b.rglob("metrics.json")):
    d = sorted(set(diffs(strip(json.load(open(f))), strip(json.load(open(a / f.relative_to(b)))))))
    if d: print(f.relative_to(b), d[:8], len(d))
