"""The one results file: every number that README.md and the documentation show is read from
``docs/results/current.toml``, which this module writes from study outputs and renders into the pages.

Collect (each part is replaced only when it is given, so one study can be added or redone alone)::

    python -m studies.results collect --quick DIR          # mmg-casadi study all --out DIR
    python -m studies.results collect --statistics DIR ... # mmg-casadi study statistics ... --out DIR, one per profile
    python -m studies.results collect --imazu DIR ...      # mmg-casadi study imazu ... --out DIR, one per profile
    python -m studies.results collect --claims docs/claims.md
    python -m studies.results collect --labelled DIR       # mmg-casadi study labelled --out DIR
    python -m studies.results collect --tasks              # runs README's five tasks, records what they print
    python -m studies.results render                       # rewrites README's generated blocks from the file

Rows are keyed by what they are, never by position: a ``[[statistics]]`` row per (profile, method), an
``[[imazu]]`` row per (profile, targets, method). A new scoring profile or a new planner is a new row after
``collect`` of its study; the tables grow a column or a row by themselves (:func:`statistics_table`), the
default profile first (the parameter table's ``colregs_profile``). README's generated blocks sit between
``<!-- results:NAME -->`` and ``<!-- /results -->``; ``tests/test_results_file.py`` fails when one differs from
the file's rendering, and the docs build includes the same renderings (``docs/_generated/results_*.md``).
"""

from __future__ import annotations

import argparse
import csv
import datetime
import json
import os
import re
import subprocess
import sys
import tempfile
import tomllib
from pathlib import Path

import tomli_w

ROOT = Path(__file__).resolve().parents[1]
FILE = ROOT / "docs" / "results" / "current.toml"
"""The results file."""
README = ROOT / "README.md"
ROLES = ("head-on", "give-way", "stand-on", "overtaking")
"""Roles shown in the per-encounter table (the default profile's columns)."""

TASKS = (
    ("simulate", "Run a shipped encounter and read the verdicts",
     "mmg-casadi simulate head_on --out out/head_on"),
    ("method", "The same kind of encounter with another method, in SI units, animated",
     "mmg-casadi simulate crossing --method colregs-vortex --units si --animate crossing.gif --out out/crossing"),
    ("manoeuvre", "A standard manoeuvre of the bare hull",
     "mmg-casadi maneuver turning --rudder 35 --out out/turning"),
    ("study", "Reproduce a figure of the paper (here two of its methods)",
     "mmg-casadi study colregs --methods modified-vortex,colregs-vortex --out out/colregs"),
    ("python", "The same from Python",
     "python -c \"import mmg_casadi as mc; r = mc.run_scenario('overtaking', method='colregs-vortex'); "
     "print(r.to_pandas()[['status', 'time_to_goal', 'min_distance']].round(2))\""),
)
"""README's five tasks: (id, title, command). Their output (stdout, and the study's lines on stderr, compile
notices left out) is recorded by ``collect --tasks``."""


def load(path: Path = FILE) -> dict:
    """The results file as a dict (empty when it does not exist).

    Parameters
    ----------
    path : Path
        The file.

    Returns
    -------
    dict
        Its tables.
    """
    return tomllib.loads(path.read_text(encoding="utf-8")) if path.exists() else {}


def _save(data: dict, path: Path = FILE) -> None:
    head = ("# Every number of README.md and of the documentation's results pages comes from this file.\n"
            "# Written by `python -m studies.results collect ...` (studies/results.py); do not edit by hand.\n")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(head + tomli_w.dumps(data), encoding="utf-8")


def _command_of(out: Path, fallback: str) -> str:
    log = out / "command.txt"
    return log.read_text(encoding="utf-8").strip() if log.exists() else fallback


# ------------------------------------------------------------------------------------------------- collect


def collect_quick(out: Path) -> dict:
    """The quick studies of ``mmg-casadi study all --out OUT``: the waypoint square's CE and MCTE, and per study,
    case and method the collision and closest approach.

    Parameters
    ----------
    out : Path
        The output directory of ``mmg-casadi study all``.

    Returns
    -------
    dict
        The ``[quick]`` table of the results file.
    """
    ws = json.loads((out / "waypoint-square" / "metrics.json").read_text())
    cases = []
    for study in ("static-obstacle", "colregs", "conflict", "narrow-channel"):
        m = json.loads((out / study / "metrics.json").read_text())
        for case, by_method in m["cases"].items():
            for method, r in by_method.items():
                d = min((p["min_distance"] for p in r["pairs"]), default=None)
                cases.append({"study": study, "case": case, "method": method, "collision": r["collision"],
                              "min_distance": round(d, 2)})
    return {"command": "mmg-casadi study all --out DIR", "profile": ws["params"]["colregs_profile"],
            "waypoint_square": {"ce": round(ws["ce"], 4), "mcte": round(ws["mcte"], 4),
                                "paper_ce": ws["paper"]["ce"], "paper_mcte": ws["paper"]["mcte"]},
            "cases": cases}


def collect_statistics(out: Path) -> list[dict]:
    """Rows of a statistics study (``summary.csv`` and ``colregs.csv``): one per method and environment.

    Parameters
    ----------
    out : Path
        The output directory of ``mmg-casadi study statistics``; a ``command.txt`` in it is recorded as the
        command that made it.

    Returns
    -------
    list of dict
        ``[[statistics]]`` rows: profile, method, environment, runs, success and interval, risky encounters, share
        kept and interval, mean score, share kept by role, command.
    """
    study = json.loads((out / "study.json").read_text())
    params = study.get("params", {})
    with open(out / "summary.csv", newline="") as f:
        summary = list(csv.DictReader(f))
    with open(out / "colregs.csv", newline="") as f:
        groups = list(csv.DictReader(f))
    config = {}
    if (out / "metrics.json").exists():
        config = json.loads((out / "metrics.json").read_text()).get("config", {})
    # colregs.csv has a row group per scoring profile the study scored (colregs_all_profiles: all three)
    profiles = list(dict.fromkeys(r.get("profile") or params.get("colregs_profile") for r in groups))
    rows = []
    for profile in profiles:
        for s in summary:
            env, method = int(s["environment"]), s["method"]
            g = {r["group"]: r for r in groups if int(r["environment"]) == env and r["method"] == method
                 and (r.get("profile") or params.get("colregs_profile")) == profile}
            rows.append({
                "profile": profile, "method": method, "environment": env, "runs": int(s["runs"]),
                "seed": config.get("base_seed", study.get("config", {}).get("base_seed", 0)),
                "success": round(float(s["success_rate"]), 4),
                "success_ci": [round(float(s["success_ci_low"]), 4), round(float(s["success_ci_high"]), 4)],
                "encounters": int(g["all"]["n"]), "kept": round(float(g["all"]["rate"]), 4),
                "kept_ci": [round(float(g["all"]["ci_low"]), 4), round(float(g["all"]["ci_high"]), 4)],
                "score": round(float(g["all"]["score_mean"]), 3),
                "roles": {r: round(float(g[r]["rate"]), 4) for r in ROLES
                          if r in g and g[r]["rate"] not in ("", "nan")},
                "command": _command_of(out, f"mmg-casadi study statistics --runs {s['runs']} --envs {env} --methods "
                                            f"... --set colregs_all_profiles=true --out DIR"),
            })
    return rows


def collect_labelled(out: Path) -> dict:
    """The agreement of every scoring profile with the hand-labelled COLREG cases (``mmg-casadi study labelled``).

    Parameters
    ----------
    out : Path
        The output directory of ``mmg-casadi study labelled``.

    Returns
    -------
    dict
        ``profiles``: per profile the cases and labelled verdicts it agrees with; ``command``.
    """
    m = json.loads((out / "metrics.json").read_text())
    return {"profiles": m["profiles"], "command": "mmg-casadi study labelled --out DIR"}


def collect_imazu(out: Path) -> list[dict]:
    """Rows of an Imazu study (``metrics.json``): one per target behaviour and method.

    Parameters
    ----------
    out : Path
        The output directory of ``mmg-casadi study imazu``.

    Returns
    -------
    list of dict
        ``[[imazu]]`` rows: profile, targets, method, safe cases, cases, risky encounters, kept, unsafe cases,
        command.
    """
    m = json.loads((out / "metrics.json").read_text())
    profile = m["params"]["colregs_profile"]
    return [{"profile": profile, "targets": targets, "method": method, "safe": r["safe"], "cases": len(r["cases"]),
             "encounters": r["encounters"], "kept": r["kept"],
             "unsafe": [c["case"] for c in r["cases"] if not c["safe"]],
             "command": _command_of(out, f"mmg-casadi study imazu --set colregs_profile={profile} --out DIR")}
            for targets, by_method in m["results"].items() for method, r in by_method.items()]


def collect_claims(path: Path) -> dict:
    """The verdict counts of a claim-by-claim report (``claims.md`` of ``mmg-casadi study paper``).

    Parameters
    ----------
    path : Path
        The report.

    Returns
    -------
    dict
        The ``[claims]`` table: command, runs and the count of each verdict.
    """
    text = path.read_text(encoding="utf-8")
    counts = dict(re.findall(r"(reproduced|partly|not reproduced|not testable): (\d+)", text.split("\n|")[0]))
    runs = re.search(r"(\d+) runs per environment and method", text)
    return {"command": "mmg-casadi study paper --runs 5000 --workers 2 --out DIR",
            "runs": int(runs.group(1)) if runs else None,
            **{k.replace(" ", "_"): int(v) for k, v in counts.items()}}


def run_task(command: str, cwd: Path) -> str:
    """What README's task ``command`` prints, run in ``cwd`` with this interpreter's ``mmg-casadi`` and ``python``:
    stdout, then the lines of a study on stderr; compile notices (which depend on the cache) left out.

    Parameters
    ----------
    command : str
        A shell command of :data:`TASKS`.
    cwd : Path
        Working directory.

    Returns
    -------
    str
        The output as README shows it.
    """
    bin_dir = str(Path(sys.executable).parent)
    env = dict(os.environ, PATH=bin_dir + os.pathsep + os.environ.get("PATH", ""), MPLBACKEND="Agg",
               COLUMNS="100")
    proc = subprocess.run(command, shell=True, cwd=cwd, env=env, capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"{command} failed ({proc.returncode}):\n{proc.stderr[-2000:]}")
    keep = [ln for ln in proc.stderr.splitlines() if ln.startswith("  ") and not ln.startswith("  [")]
    return "\n".join([*proc.stdout.rstrip("\n").splitlines(), *keep]).rstrip() + "\n"


def collect_tasks() -> list[dict]:
    """Run README's five tasks (:data:`TASKS`) in a temporary folder and record their output.

    Returns
    -------
    list of dict
        ``[[tasks]]`` rows: id, title, command, output.
    """
    with tempfile.TemporaryDirectory() as tmp:
        return [{"id": i, "title": title, "command": cmd, "output": run_task(cmd, Path(tmp))}
                for i, title, cmd in TASKS]


# ------------------------------------------------------------------------------------------------- render


def _pct(x) -> str:
    return "–" if x is None else f"{100 * x:.1f} %"


def _ci(ci) -> str:
    return f"[{100 * ci[0]:.1f}, {100 * ci[1]:.1f}]"


def default_profile() -> str:
    """The scoring profile of the parameter table (``colregs_profile``), shown first.

    Returns
    -------
    str
        The profile's name.
    """
    from mmg_casadi.params import PARAMETERS
    return PARAMETERS["colregs_profile"].default


def statistics_table(data: dict) -> str:
    """Environment-5 table: per method its success and, per scoring profile (the default first), the share of
    risky encounters kept; the default profile also by role. Rows and columns come from the file's rows.

    Parameters
    ----------
    data : dict
        The results file (:func:`load`).

    Returns
    -------
    str
        A Markdown table and the note under it.
    """
    rows = data.get("statistics", [])
    if not rows:
        return "_No statistics in the results file yet._\n"
    default = default_profile()
    profiles = sorted({r["profile"] for r in rows}, key=lambda p: (p != default, p))
    methods = list(dict.fromkeys(r["method"] for r in rows))
    by = {(r["profile"], r["method"]): r for r in rows}
    head = ["method", "success [95 % CI]"]
    for p in profiles:
        head.append(f"`{p}` kept [95 % CI] (encounters)")
        if p == profiles[0]:
            head += [f"{role}" for role in ROLES]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for m in methods:
        first = next(by[(p, m)] for p in profiles if (p, m) in by)
        cells = [m, f"{_pct(first['success'])} {_ci(first['success_ci'])}"]
        for p in profiles:
            r = by.get((p, m))
            cells.append("–" if r is None else f"{_pct(r['kept'])} {_ci(r['kept_ci'])} ({r['encounters']})")
            if p == profiles[0]:
                cells += [_pct((r or {}).get("roles", {}).get(role)) for role in ROLES]
        lines.append("| " + " | ".join(cells) + " |")
    r0 = rows[0]
    commands = dict.fromkeys([r0["command"], *(by[(p, methods[0])]["command"] for p in profiles[1:]
                                                 if (p, methods[0]) in by)])
    note = (f"\nEnvironment {r0['environment']}, {r0['runs']} runs per method, seed {r0['seed']}; a risky encounter "
            f"is kept when every rule the scorer applies is kept (`{profiles[0]}` is the default profile). "
            "Made by: " + "; ".join(f"`{c}`" for c in commands) + ".\n")
    return "\n".join(lines) + "\n" + note


def labelled_table(data: dict) -> str:
    """How many hand-labelled COLREG cases and verdicts each scoring profile reproduces (the default first).

    Parameters
    ----------
    data : dict
        The results file (:func:`load`).

    Returns
    -------
    str
        A Markdown table and the note under it.
    """
    lab = data.get("labelled")
    if not lab:
        return "_No labelled cases in the results file yet._\n"
    default = default_profile()
    profiles = sorted(lab["profiles"], key=lambda p: (p != default, p))
    lines = ["| profile | cases agreed | labelled verdicts agreed |", "|---|---|---|"]
    for p in profiles:
        t = lab["profiles"][p]
        lines.append(f"| `{p}` | {t['cases_agreed']}/{t['cases']} | {t['verdicts_agreed']}/{t['verdicts']} |")
    return "\n".join(lines) + f"\n\nMade by: `{lab['command']}`.\n"


def imazu_table(data: dict) -> str:
    """Imazu table: per method, for each target behaviour, the safe cases and the risky encounters kept under
    each profile (the default first).

    Parameters
    ----------
    data : dict
        The results file (:func:`load`).

    Returns
    -------
    str
        A Markdown table and the note under it.
    """
    rows = data.get("imazu", [])
    if not rows:
        return "_No Imazu results in the results file yet._\n"
    default = default_profile()
    profiles = sorted({r["profile"] for r in rows}, key=lambda p: (p != default, p))
    targets = list(dict.fromkeys(r["targets"] for r in rows))
    methods = list(dict.fromkeys(r["method"] for r in rows))
    by = {(r["profile"], r["targets"], r["method"]): r for r in rows}
    head = ["method"]
    for t in targets:
        head += [f"targets {t}: safe"] + [f"kept (`{p}`)" for p in profiles]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for m in methods:
        cells = [m]
        for t in targets:
            r = by.get((profiles[0], t, m))
            cells.append("–" if r is None else f"{r['safe']}/{r['cases']}" +
                         (f" (not {', '.join(map(str, r['unsafe']))})" if r["unsafe"] else ""))
            for p in profiles:
                q = by.get((p, t, m))
                cells.append("–" if q is None else f"{q['kept']}/{q['encounters']}")
        lines.append("| " + " | ".join(cells) + " |")
    made = "; ".join(f"`{c}`" for c in dict.fromkeys(r["command"] for r in rows))
    return "\n".join(lines) + "\n\nThe 22 Imazu problems; safe: the own ship reached her goal and never came within " \
                              f"the collision distance. Made by: {made}.\n"


def quick_table(data: dict) -> str:
    """The paper's cases (``mmg-casadi study all``): closest approach per case and method, collisions marked.

    Parameters
    ----------
    data : dict
        The results file (:func:`load`).

    Returns
    -------
    str
        A Markdown table and the note under it.
    """
    q = data.get("quick")
    if not q:
        return "_No quick-study results in the results file yet._\n"
    methods = list(dict.fromkeys(c["method"] for c in q["cases"]))
    cases = list(dict.fromkeys((c["study"], c["case"]) for c in q["cases"]))
    by = {(c["study"], c["case"], c["method"]): c for c in q["cases"]}
    lines = ["| study | case | " + " | ".join(methods) + " |", "|---|---|" + "---:|" * len(methods)]
    for study, case in cases:
        cells = []
        for m in methods:
            c = by.get((study, case, m))
            cells.append("–" if c is None else f"{c['min_distance']:.2f}" + (" ✗" if c["collision"] else ""))
        lines.append(f"| {study} | {case} | " + " | ".join(cells) + " |")
    ws = q["waypoint_square"]
    return ("\n".join(lines) + f"\n\nClosest approach of any two ships or a ship and an obstacle [L]; ✗ a collision "
            f"(centres closer than 2 L). Waypoint square: CE {ws['ce']:.4f} (paper {ws['paper_ce']}), MCTE "
            f"{ws['mcte']:.4f} L (paper {ws['paper_mcte']}). Made by: `{q['command']}`.\n")


def claims_line(data: dict) -> str:
    """The claim-by-claim verdict counts as one sentence.

    Parameters
    ----------
    data : dict
        The results file (:func:`load`).

    Returns
    -------
    str
        One Markdown line.
    """
    c = data.get("claims")
    if not c:
        return "_No claim-by-claim report in the results file yet._\n"
    return (f"**{c.get('reproduced', 0)} claims reproduced, {c.get('partly', 0)} partly, "
            f"{c.get('not_reproduced', 0)} not reproduced, {c.get('not_testable', 0)} not testable** "
            f"({c['runs']} Monte Carlo runs per environment and method; `{c['command']}`).\n")


def task_block(data: dict, task_id: str) -> str:
    """A task of README: its command and the output the file recorded.

    Parameters
    ----------
    data : dict
        The results file (:func:`load`).
    task_id : str
        The task's id (:data:`TASKS`).

    Returns
    -------
    str
        Two Markdown code blocks: the command and its output.
    """
    t = next((t for t in data.get("tasks", []) if t["id"] == task_id), None)
    if t is None:
        return "_Not in the results file yet._\n"
    return f"```sh\n{t['command']}\n```\n\n```text\n{t['output'].rstrip()}\n```\n"


BLOCKS = {"statistics": statistics_table, "imazu": imazu_table, "quick": quick_table, "claims": claims_line,
          "labelled": labelled_table,
          **{f"task-{i}": (lambda d, i=i: task_block(d, i)) for i, _, _ in TASKS}}
"""Renderings by block name (``<!-- results:NAME -->``)."""
_BLOCK = re.compile(r"(<!-- results:([\w-]+) -->\n)(.*?)(<!-- /results -->)", re.S)


def render_text(text: str, data: dict) -> str:
    """``text`` with every generated block replaced by its rendering from ``data``.

    Parameters
    ----------
    text : str
        A page with ``<!-- results:NAME -->`` ... ``<!-- /results -->`` blocks.
    data : dict
        The results file (:func:`load`).

    Returns
    -------
    str
        The page with its blocks rendered.
    """
    def sub(m):
        if m.group(2) not in BLOCKS:
            raise KeyError(f"unknown results block {m.group(2)!r}; known: {', '.join(BLOCKS)}")
        return m.group(1) + BLOCKS[m.group(2)](data) + m.group(4)
    return _BLOCK.sub(sub, text)


def blocks(text: str) -> dict:
    """The generated blocks of a page: name → content.

    Parameters
    ----------
    text : str
        The page.

    Returns
    -------
    dict
        Block name to its current content.
    """
    return {m.group(2): m.group(3) for m in _BLOCK.finditer(text)}


def main(argv=None) -> int:
    """The command line of this module, ``python -m studies.results``: ``collect`` or ``render`` (module notes).

    Parameters
    ----------
    argv : list of str, optional
        Arguments (default ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit status.
    """
    p = argparse.ArgumentParser(prog="python -m studies.results", description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="what", required=True)
    c = sub.add_parser("collect")
    c.add_argument("--quick", type=Path)
    c.add_argument("--statistics", type=Path, nargs="*", default=[])
    c.add_argument("--imazu", type=Path, nargs="*", default=[])
    c.add_argument("--claims", type=Path)
    c.add_argument("--labelled", type=Path)
    c.add_argument("--tasks", action="store_true")
    sub.add_parser("render")
    a = p.parse_args(argv)
    if a.what == "collect":
        data = load()
        import mmg_casadi
        data["meta"] = {"version": mmg_casadi.__version__, "default_profile": default_profile(),
                        "updated": datetime.date.today().isoformat()}
        if a.quick:
            data["quick"] = collect_quick(a.quick)
        for out in a.statistics:
            new = collect_statistics(out)
            keys = {(r["profile"], r["method"], r["environment"]) for r in new}
            data["statistics"] = [r for r in data.get("statistics", [])
                                  if (r["profile"], r["method"], r["environment"]) not in keys] + new
        for out in a.imazu:
            new = collect_imazu(out)
            keys = {(r["profile"], r["targets"], r["method"]) for r in new}
            data["imazu"] = [r for r in data.get("imazu", []) if (r["profile"], r["targets"], r["method"])
                             not in keys] + new
        if a.claims:
            data["claims"] = collect_claims(a.claims)
        if a.labelled:
            data["labelled"] = collect_labelled(a.labelled)
        if a.tasks:
            data["tasks"] = collect_tasks()
        _save(data)
    README.write_text(render_text(README.read_text(encoding="utf-8"), load()), encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
