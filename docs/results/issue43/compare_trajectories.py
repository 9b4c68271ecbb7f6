import json, numpy as np, pathlib, sys
b, a = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
for f in sorted(b.rglob("trajectory.npz")):
    g = a / f.relative_to(b)
    X, Y = np.load(f), np.load(g)
    keys = X.files
    same = all(X[k].shape == Y[k].shape and np.array_equal(X[k], Y[k], equal_nan=X[k].dtype.kind == "f") for k in keys)
    if same: continue
    m = json.load(open(f.parent / "metrics.json")); ma = json.load(open(g.parent / "metrics.json"))
    t = X["t"]
    # first differing time
    first = None
    for k in keys:
        if k == "t": continue
        A, B = X[k], Y[k]
        n = min(len(A), len(B))
        D = (A[:n] != B[:n]) & ~(np.isnan(A[:n]) & np.isnan(B[:n])) if A.dtype.kind == "f" else (A[:n] != B[:n]); d = np.where(np.any(D.reshape(n, -1), axis=1))[0]
        if len(d): first = d[0] if first is None else min(first, d[0])
    ct = [(s["name"], s["collision_time"], s["collision_kind"], s["status"]) for s in m["ships"] if s["collided"]]
    cta = [(s["name"], s["collision_time"], s["collision_kind"], s["status"]) for s in ma["ships"] if s["collided"]]
    print(f.parent.relative_to(b), "first diff t =", None if first is None else t[first], "| before", ct, "| after", cta, "| keys", keys, X["t"].shape, Y["t"].shape)
