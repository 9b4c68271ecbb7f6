"""The land cases before (main) and after (branch i43), per method: the own ship's status and Rule 9 verdict.

Usage: python docs/results/issue43/land_table.py AFTER_LAND_DIR BEFORE_LAND_DIR BEFORE_ISLAND_DIR > land.md
(AFTER/BEFORE_LAND_DIR: `mmg-casadi study land --out DIR` on each; BEFORE_ISLAND_DIR/<method>: main's
`mmg-casadi simulate land_island_on_track.toml --method M --out DIR/M`).
"""

import json
import sys
from pathlib import Path


def cell(d):
    f = Path(d) / "metrics.json"
    if not f.exists():
        return "–"
    m = json.loads(f.read_text())
    s = m["ships"][0]
    st = s.get("status") or ("reached" if s.get("reached_goal") else "?")
    if s.get("collided"):
        st = f"{st} ({s['collision_kind']} t={s['collision_time']:g})"
        if s.get("reached_goal"):
            st += ", then 'reached'"
    r9 = s.get("rule9")
    if r9:
        st += f"; R9 {'kept' if r9['verdict'] else 'not'} {100 * r9['score']:.0f} %"
    others = [o for o in m["ships"][1:] if o.get("collided")]
    if others:
        st += f"; {len(others)} other(s) in contact"
    return st


def main(after, before, island_before):
    after, before, island_before = Path(after), Path(before), Path(island_before)
    cases = sorted(p.name for p in after.iterdir() if p.is_dir())
    methods = sorted({m.name for c in cases for m in (after / c).iterdir() if m.is_dir() and not m.name.startswith(".")})
    print("| case | method | before (main) | after (i43) |")
    print("|:---|:---|:---|:---|")
    for c in cases:
        for m in methods:
            b = island_before / m if c == "land_island_on_track" else before / c / m
            print(f"| {c} | {m} | {cell(b)} | {cell(after / c / m)} |")


if __name__ == "__main__":
    main(*sys.argv[1:4])
