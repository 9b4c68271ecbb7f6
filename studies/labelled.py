"""The hand-labelled COLREG cases under every scoring profile: which verdicts each profile reproduces.

``mmg-casadi study labelled --out DIR`` simulates every case of :mod:`mmg_casadi.scenarios.colregs_cases` once and
judges it under every profile of :data:`mmg_casadi.colregs.profiles.SCORING_PROFILES`. It writes ``labelled.csv``
(one row per labelled verdict: case, own, other, item, the label and each profile's verdict), ``labelled.md`` (per
profile the cases and verdicts it agrees with, and per case the rule that decides it) and ``metrics.json``.
"""

from __future__ import annotations

import csv
import sys
from pathlib import Path

from mmg_casadi.colregs.profiles import SCORING_PROFILES
from mmg_casadi.io import atomic_open, write_json, write_text
from mmg_casadi.scenarios.colregs_cases import CASES, agreement, outcomes, simulate_case, verdicts

COLUMNS = ("case", "point", "own", "other", "item", "label", *SCORING_PROFILES)
"""Columns of ``labelled.csv``."""


def run(out) -> dict:
    """Judge every labelled case under every profile and write the tables (module docstring).

    Parameters
    ----------
    out : str or Path
        Output directory.

    Returns
    -------
    dict
        ``{"profiles": {profile: {"cases_agreed", "cases", "verdicts_agreed", "verdicts"}}, "cases": {...}}``.
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    tracks = {name: simulate_case(case) for name, case in CASES.items()}
    judged = {p: agreement(p, tracks) for p in SCORING_PROFILES}
    got = {p: {name: verdicts(outcomes(tracks[name], p)) for name in CASES} for p in SCORING_PROFILES}
    rows = []
    for name, case in CASES.items():
        for key, label in verdicts(case.labels).items():
            rows.append({"case": name, "point": case.point, "own": key[0], "other": key[1], "item": key[2],
                         "label": label, **{p: got[p][name].get(key) for p in SCORING_PROFILES}})
    with atomic_open(out / "labelled.csv", "w", encoding="utf-8", newline="") as f:
        writer = csv.DictWriter(f, COLUMNS, lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)
    totals = {p: {"cases_agreed": sum(1 for a in judged[p].values() if not a[2]), "cases": len(CASES),
                  "verdicts_agreed": sum(a[0] for a in judged[p].values()),
                  "verdicts": sum(a[1] for a in judged[p].values())} for p in SCORING_PROFILES}
    lines = ["| profile | cases agreed | verdicts agreed |", "|:---|---:|---:|"]
    lines += [f"| {p} | {t['cases_agreed']} / {t['cases']} | {t['verdicts_agreed']} / {t['verdicts']} |"
              for p, t in totals.items()]
    lines += ["", "| case | what it tests | " + " | ".join(SCORING_PROFILES) + " | decided by |",
              "|:---|:---|" + ":---:|" * len(SCORING_PROFILES) + ":---|"]
    for name, case in CASES.items():
        marks = ["agrees" if not judged[p][name][2] else f"{len(judged[p][name][2])} differ" for p in SCORING_PROFILES]
        lines.append(f"| {name} | {case.point} | " + " | ".join(marks) + f" | {case.rule} |")
    write_text(out / "labelled.md", "\n".join(lines) + "\n")
    metrics = {"profiles": totals,
               "cases": {name: {p: {"agreed": judged[p][name][0], "labelled": judged[p][name][1],
                                    "differences": [list(d) for d in judged[p][name][2]]}
                                for p in SCORING_PROFILES} for name in CASES}}
    write_json(out / "metrics.json", metrics)
    for p, t in totals.items():
        print(f"  {p:>10s}: {t['cases_agreed']}/{t['cases']} cases, {t['verdicts_agreed']}/{t['verdicts']} "
              "labelled verdicts", file=sys.stderr)
    return metrics
