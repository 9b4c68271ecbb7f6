"""Environment 6 before (main) and after (branch i43), paired run by run: success, grounding, Rule 9 kept.

Usage: python docs/results/issue43/env6_compare.py BEFORE_DIR AFTER_DIR OUT_DIR
(each DIR a `mmg-casadi study statistics --envs 6` output with runs.csv). Writes env6_compare.csv and .md.
"""

import csv
import sys
from pathlib import Path

from mmg_casadi.colregs.profiles import scoring_profile
from mmg_casadi.montecarlo.stats import paired_comparison, wilson

KEPT = scoring_profile("published").rule9_kept_share


def rows(d):
    with open(Path(d) / "runs.csv", newline="") as fh:
        return {(r["method"], int(r["run"])): r for r in csv.DictReader(fh) if r["environment"] == "6"}


def share(r):
    return None if r["colregs_rule9"] in ("", "nan") else float(r["colregs_rule9"])


def pct(x):
    return f"{100 * x:.1f}"


def main(before, after, out):
    b, a = rows(before), rows(after)
    keys = sorted(set(b) & set(a))
    methods = sorted({m for m, _ in keys})
    table = []
    for m in methods:
        ks = [k for k in keys if k[0] == m]
        sa = [b[k]["success"] == "True" for k in ks]
        sb = [a[k]["success"] == "True" for k in ks]
        ga = sum(b[k]["failure"] == "grounding" for k in ks)
        gb = sum(a[k]["failure"] == "grounding" for k in ks)
        succ = paired_comparison(sb, sa)  # after minus before
        ch = [k for k in ks if share(b[k]) is not None and share(a[k]) is not None]
        row = {"method": m, "runs": len(ks), "success_before": sum(sa), "success_after": sum(sb),
               "success_diff": succ.difference, "success_ci_low": succ.ci[0], "success_ci_high": succ.ci[1],
               "success_p": succ.p_value, "success_after_only": succ.a_only, "success_before_only": succ.b_only,
               "grounding_before": ga, "grounding_after": gb,
               "channel_runs_before": sum(share(b[k]) is not None for k in ks),
               "channel_runs_after": sum(share(a[k]) is not None for k in ks), "channel_runs_paired": len(ch)}
        if ch:
            kb = [share(b[k]) >= KEPT for k in ch]
            ka = [share(a[k]) >= KEPT for k in ch]
            r9 = paired_comparison(ka, kb)
            row.update(rule9_before=sum(kb), rule9_after=sum(ka), rule9_diff=r9.difference, rule9_ci_low=r9.ci[0],
                       rule9_ci_high=r9.ci[1], rule9_p=r9.p_value, rule9_after_only=r9.a_only,
                       rule9_before_only=r9.b_only)
        table.append(row)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    cols = list(dict.fromkeys(c for r in table for c in r))
    with open(out / "env6_compare.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, cols)
        w.writeheader()
        w.writerows(table)
    lines = ["| method | runs | success before → after [%] (95 % CI of after) | Δ success [pp] (95 % CI), McNemar p | "
             "groundings before → after | Rule 9 kept before → after [%] (runs with a channel in both) | "
             "Δ Rule 9 [pp] (95 % CI), McNemar p |", "|:---|---:|:---|:---|:---|:---|:---|"]
    for r in table:
        n = r["runs"]
        lo, hi = wilson(r["success_after"], n)
        s = (f"{pct(r['success_before'] / n)} → {pct(r['success_after'] / n)} [{pct(lo)}, {pct(hi)}]")
        d = (f"{100 * r['success_diff']:+.1f} [{100 * r['success_ci_low']:+.1f}, {100 * r['success_ci_high']:+.1f}]"
             f", p = {r['success_p']:.2g} ({r['success_after_only']} / {r['success_before_only']} discordant)")
        if r["channel_runs_paired"]:
            c = r["channel_runs_paired"]
            lo, hi = wilson(r["rule9_after"], c)
            k = f"{pct(r['rule9_before'] / c)} → {pct(r['rule9_after'] / c)} [{pct(lo)}, {pct(hi)}] ({c})"
            d9 = (f"{100 * r['rule9_diff']:+.1f} [{100 * r['rule9_ci_low']:+.1f}, {100 * r['rule9_ci_high']:+.1f}]"
                  f", p = {r['rule9_p']:.2g} ({r['rule9_after_only']} / {r['rule9_before_only']} discordant)")
        else:
            k, d9 = "no channel", ""
        lines.append(f"| {r['method']} | {n} | {s} | {d} | {r['grounding_before']} → {r['grounding_after']} | {k} | {d9} |")
    (out / "env6_compare.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main(*sys.argv[1:4])
