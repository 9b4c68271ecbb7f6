"""Tables of the issue-45 measurements from the outputs of run.sh and merge.sh (``python tabulate.py OUT``).

Per method and search: simulations, failures (with the Wilson 95 % interval of the failure rate), distinct failures,
least robustness, seconds; the ratio of the best search's distinct failures to random sampling's, with an exact
95 % interval (conditional binomial on the two counts, taken as Poisson); every failure's reproduction by
``simulate``; the hardest-20 suites (``suite.md`` of ``study hardest``).
"""

import csv
import json
import sys
from pathlib import Path

from scipy.stats import beta

from mmg_casadi.montecarlo.stats import wilson

METHODS = ("colregs-vortex", "modified-vortex", "velocity-obstacle")


def ratio_interval(a: int, b: int, confidence: float = 0.95) -> tuple[float, float]:
    """Exact interval of the ratio of two Poisson means from counts ``a`` and ``b`` (Clopper-Pearson on a/(a+b))."""
    n, q = a + b, (1 - confidence) / 2
    lo = beta.ppf(q, a, b + 1) if a > 0 else 0.0
    hi = beta.ppf(1 - q, a + 1, b) if b > 0 else 1.0
    return lo / (1 - lo), (hi / (1 - hi) if hi < 1 else float("inf"))


def main(out: Path) -> str:
    lines = ["| method | search | simulations | failures | failure rate (95 % CI) | distinct | least robustness (L) "
             "| seconds |", "|---|---|---:|---:|---|---:|---:|---:|"]
    ratios = ["| method | best search | its distinct | random's distinct | ratio (95 % CI) | pooled distinct "
              "| found by one search only | failures reproduced by simulate |", "|---|---|---:|---:|---|---:|---|---|"]
    suites = []
    for m in METHODS:
        path = out / m / "summary.json"
        if not path.exists():
            lines.append(f"| {m} | (not run) | | | | | | |")
            continue
        s = json.loads(path.read_text())
        for name, r in s["searches"].items():
            lo, hi = wilson(r["failures"], r["simulations"])
            lines.append(f"| {m} | {name} | {r['simulations']} | {r['failures']} | {r['failures'] / r['simulations']:.3f} "
                         f"({lo:.3f}–{hi:.3f}) | {r['distinct']} | {r['least_robustness']:.2f} | {r['seconds']:.0f} |")
        best = max((n for n in s["searches"] if n != "random"), key=lambda n: s["searches"][n]["distinct"])
        a, b = s["searches"][best]["distinct"], s["searches"]["random"]["distinct"]
        lo, hi = ratio_interval(a, b)
        ratio = f"{a / b:.2f}" if b else "∞"
        with open(out / m / "distinct.csv", newline="") as fh:
            groups = list(csv.DictReader(fh))
        only = ", ".join(f"{n} {sum(int(g[f'found_by_{n}']) > 0 and all(int(g[f'found_by_{o}']) == 0 for o in s['searches'] if o != n) for g in groups)}"
                         for n in s["searches"])
        ratios.append(f"| {m} | {best} | {a} | {b} | {ratio} ({lo:.2f}–{hi:.2f}) | {s['pooled_distinct']} | {only} | "
                      f"{s['reproduced']} of {s['failures_written']} |")
        suite = out / f"hardest_{m}" / "suite.md"
        if suite.exists():
            suites += [f"### Hardest 20 of {m}", "", suite.read_text().strip(), ""]
    return "\n".join(lines + [""] + ratios + [""] + suites) + "\n"


if __name__ == "__main__":
    print(main(Path(sys.argv[1])), end="")
