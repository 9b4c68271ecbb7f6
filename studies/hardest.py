"""``study hardest``: the K hardest situations a falsification found for one method, and every method on them.

The suite is the least robust failure of each distinct failure
(:meth:`~mmg_casadi.falsify.falsifier.Falsification.hardest`), least robust first, topped up with the least robust runs
that did not fail; it is taken
from an output of ``mmg-casadi falsify`` (``--from DIR``) or searched here for the first of ``--methods``. Every
method then sails every situation of the suite (every ship with the method, as in the study), judged by the same
objective; methods are compared pairwise on the same situations with McNemar's exact test on the discordant ones
(:func:`~mmg_casadi.montecarlo.stats.paired_comparison`): the suite a user takes to compare methods where they
differ. Outputs: ``suite/<k>.toml`` (the situations, with the searched method), ``suite.csv`` (each situation's
robustness and failure under every method), ``comparisons.csv``, ``suite.md`` and ``summary.json``.
"""

from __future__ import annotations

import itertools
from pathlib import Path

from mmg_casadi.falsify.falsifier import falsify, load_falsification
from mmg_casadi.falsify.robustness import evaluate
from mmg_casadi.falsify.search import SEARCHES
from mmg_casadi.guidance import methods as registry
from mmg_casadi.io import write_json, write_text
from mmg_casadi.montecarlo.stats import paired_comparison
from mmg_casadi.scenarios.scenario import dump_scenario

METHODS = ("colregs-vortex", "modified-vortex", "velocity-obstacle")
"""The methods compared by default (the issue's three)."""


def run(out, *, methods=None, params=None, k: int = 20, source=None, environment: int = 5, budget: int = 2000,
        objective: str = "collision", searches=SEARCHES, seed: int = 0, disturbance=None) -> dict:
    """Build the hardest-``k`` suite of one method and run every method on it, paired (module docstring).

    Parameters
    ----------
    out : str or Path
        Output directory.
    methods : sequence of str, optional
        The methods compared; the first is falsified unless ``source`` is given (default :data:`METHODS`).
    params : dict, optional
        Parameter overrides of every run (with ``source``: those of the falsification win).
    k : int, default 20
        Size of the suite.
    source : str or Path, optional
        An output directory of ``mmg-casadi falsify`` to take the situations from.
    environment, budget, objective, searches, seed, disturbance
        The falsification's settings when it runs here (:func:`~mmg_casadi.falsify.falsifier.falsify`).

    Returns
    -------
    dict
        The summary written to ``summary.json``.
    """
    out = Path(out)
    methods = list(registry.parse_list(methods or METHODS))
    if isinstance(k, bool) or not isinstance(k, int) or k < 1:
        from mmg_casadi.errors import InputError
        raise InputError("--k", "an integer >= 1", k)
    if source is not None:
        f = load_falsification(source)
    else:
        with registry.run_of(methods, params):
            f = falsify(methods[0], environment, budget=budget, objective=objective, searches=searches, seed=seed,
                        params=params, disturbance=disturbance, checkpoint=out / "falsify",
                        report=lambda line: print(line, flush=True))
            f.save(out / "falsify", figures="distinct")
    if f.method not in methods:
        methods.insert(0, f.method)
    suite = f.hardest(k)
    names = [f"situation{i:02d}" for i in range(len(suite))]
    for name, e in zip(names, suite):
        write_text(out / "suite" / f"{name}.toml", dump_scenario(f.scenario(e, label=name)))
    thetas = [e.theta for e in suite]
    results = {}
    with registry.run_of(methods, f.params):
        for m in methods:
            results[m] = evaluate(f.envelope, thetas, m, f.objective, f.params)
    rows = []
    for i, name in enumerate(names):
        row = {"situation": name, "file": f"suite/{name}.toml", "found_robustness": suite[i].robustness}
        for m in methods:
            e = results[m][i]
            row[f"robustness_{m}"] = e.robustness
            row[f"failure_{m}"] = e.failure
            row[f"outcome_{m}"] = e.row["failure"] or "success"
        rows.append(row)
    comparisons = []
    for a, b in itertools.combinations(methods, 2):
        c = paired_comparison([not e.failure for e in results[a]], [not e.failure for e in results[b]])
        comparisons.append({"a": a, "b": b, **c.to_dict(), "verdict": c.verdict()})
    _write_csv(out / "suite.csv", rows)
    _write_csv(out / "comparisons.csv", comparisons)
    write_text(out / "suite.md", to_markdown(f, methods, rows, comparisons))
    summary = {"falsified": f.method, "environment": f.envelope.environment, "objective": f.objective,
               "budget": f.config.budget, "k": len(suite), "methods": methods,
               "failures": {m: sum(e.failure for e in results[m]) for m in methods},
               "comparisons": comparisons, "source": str(source) if source is not None else "falsify"}
    write_json(out / "summary.json", summary)
    return summary


def to_markdown(f, methods, rows, comparisons) -> str:
    """The suite and the paired comparisons as Markdown tables.

    Parameters
    ----------
    f : Falsification
        The falsification the suite comes from.
    methods : list of str
        The methods run on the suite.
    rows : list of dict
        The rows of ``suite.csv``.
    comparisons : list of dict
        The rows of ``comparisons.csv``.

    Returns
    -------
    str
        Markdown.
    """
    lines = [f"Hardest {len(rows)} situations of {f.method} (environment {f.envelope.environment}, objective "
             f"{f.objective}, {f.config.budget} simulations per search); robustness under each method "
             "(negative: failed).", "",
             "| situation | " + " | ".join(methods) + " |", "|---|" + "---:|" * len(methods)]
    for r in rows:
        cells = [f"{r[f'robustness_{m}']:.2f}" + (" ✗" if r[f"failure_{m}"] else "") for m in methods]
        lines.append(f"| {r['situation']} | " + " | ".join(cells) + " |")
    lines.append("| failures | " + " | ".join(str(sum(r[f"failure_{m}"] for r in rows)) for m in methods) + " |")
    lines += ["", "| A | B | A fails | B fails | A only fails | B only fails | McNemar p |",
              "|---|---|---:|---:|---:|---:|---:|"]
    for c in comparisons:
        lines.append(f"| {c['a']} | {c['b']} | {c['n'] - c['both'] - c['a_only']} | "
                     f"{c['n'] - c['both'] - c['b_only']} | {c['b_only']} | {c['a_only']} | {c['p_value']:.3g} |")
    return "\n".join(lines) + "\n"


def _write_csv(path: Path, rows: list[dict]) -> None:
    import csv
    import io

    buf = io.StringIO()
    if rows:
        w = csv.DictWriter(buf, fieldnames=list(rows[0]), lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
    write_text(path, buf.getvalue())
