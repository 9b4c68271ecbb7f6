"""Judge a parameter set against a baseline on paired Monte Carlo runs (the statistics study's ``runs.csv``).

Both sets run the same sampled scenarios (same environments, runs and seed), so each environment gives paired
success vectors: :func:`mmg_casadi.montecarlo.stats.paired_comparison` (exact McNemar p-value, Newcombe interval of the
difference). CE and MCTE are compared on the runs where *both* sets succeeded (paired differences, mean with a
normal 95 % interval), since their means over each set's own successes compare different scenario mixes.

The verdict is ``"improvement"`` only when every one of these holds at level ``alpha``:

* in the target environment(s) the candidate's success rate is significantly higher (McNemar p < alpha and a
  positive difference);
* in no environment is its success rate significantly lower;
* in no environment is its mean CE or mean MCTE significantly higher (the lower bound of the paired
  difference's interval above zero).

Anything else is ``"no improvement"``, with the reasons. A difference the paired test does not support is
never reported as an improvement.

Examples
--------
>>> import numpy as np
>>> base = {"success": np.array([True] * 95 + [False] * 5), "ce": np.full(100, 0.1), "mcte": np.full(100, 1.0)}
>>> worse = {"success": np.array([True] * 90 + [False] * 10), "ce": np.full(100, 0.1), "mcte": np.full(100, 1.0)}
>>> judge({5: worse}, {5: base}, target=(5,))["verdict"]
'no improvement'
"""

from __future__ import annotations

import math

import numpy as np

from mmg_casadi.errors import InputError
from mmg_casadi.io import write_text
from mmg_casadi.montecarlo.stats import paired_comparison, wilson

Z_95 = 1.959963984540054


def paired_mean(a, b) -> dict:
    """Mean of ``a − b`` over the entries where both are finite, with a normal 95 % interval.

    Parameters
    ----------
    a, b : sequence of float
        Paired values (``nan`` where a run has none).

    Returns
    -------
    dict
        ``n`` (pairs), ``mean`` of ``a − b``, ``ci`` (``[low, high]``, ``inf`` half-width for one pair; ``nan``
        without any), ``mean_a`` and ``mean_b``.

    Examples
    --------
    >>> d = paired_mean([1.0, 2.0, 3.0, float("nan")], [1.0, 1.0, 1.0, 2.0])
    >>> d["n"], d["mean"]
    (3, 1.0)
    """
    a, b = np.asarray(a, float), np.asarray(b, float)
    ok = np.isfinite(a) & np.isfinite(b)
    d = a[ok] - b[ok]
    n = int(d.size)
    if n == 0:
        return {"n": 0, "mean": math.nan, "ci": [math.nan, math.nan], "mean_a": math.nan, "mean_b": math.nan}
    m = float(d.mean())
    h = Z_95 * float(d.std(ddof=1)) / math.sqrt(n) if n > 1 else math.inf
    return {"n": n, "mean": m, "ci": [m - h, m + h], "mean_a": float(a[ok].mean()), "mean_b": float(b[ok].mean())}


def compare_env(cand: dict, base: dict, alpha: float = 0.05) -> dict:
    """Paired comparison of one environment: success (McNemar), CE and MCTE on joint successes.

    Parameters
    ----------
    cand, base : dict
        ``{"success": bool array, "ce": float array, "mcte": float array}`` over the same runs, in the same order.
    alpha : float
        Significance level.

    Returns
    -------
    dict
        ``runs``, ``success`` (:meth:`~mmg_casadi.montecarlo.stats.PairedComparison.to_dict`), ``verdict``,
        ``success_candidate``, ``success_baseline`` with their Wilson intervals, and ``ce``, ``mcte``
        (:func:`paired_mean` over the joint successes).
    """
    s_a = np.asarray(cand["success"], bool)
    s_b = np.asarray(base["success"], bool)
    pc = paired_comparison(s_a, s_b)
    both = s_a & s_b
    out = {"runs": pc.n, "success": pc.to_dict(), "verdict": pc.verdict(alpha),
           "success_candidate": float(s_a.mean()), "success_candidate_ci": list(wilson(int(s_a.sum()), pc.n)),
           "success_baseline": float(s_b.mean()), "success_baseline_ci": list(wilson(int(s_b.sum()), pc.n))}
    for key in ("ce", "mcte"):
        a = np.where(both, np.asarray(cand[key], float), np.nan)
        b = np.where(both, np.asarray(base[key], float), np.nan)
        out[key] = paired_mean(a, b)
    return out


def judge(cand: dict, base: dict, *, target=(5,), alpha: float = 0.05) -> dict:
    """Per-environment paired comparisons and the verdict (see the module docstring).

    Parameters
    ----------
    cand, base : dict
        Environment → ``{"success", "ce", "mcte"}`` arrays over the same runs (see :func:`compare_env`).
    target : tuple of int
        Environments where the candidate must be significantly better.
    alpha : float
        Significance level.

    Returns
    -------
    dict
        ``{"verdict": "improvement" | "no improvement", "reasons": [...], "alpha": alpha, "target": [...],
        "environments": {env: compare_env(...)}}``.
    """
    if set(cand) != set(base):
        raise InputError("cand", f"the environments of the baseline {sorted(base)}", sorted(cand))
    missing = [e for e in target if e not in cand]
    if missing:
        raise InputError("target", f"environments among {sorted(cand)}", missing)
    envs = {e: compare_env(cand[e], base[e], alpha) for e in sorted(cand)}
    reasons = []
    for e in target:
        c = envs[e]["success"]
        if not (c["p_value"] < alpha and c["difference"] > 0):
            reasons.append(f"environment {e}: success {c['rate_a']:.4f} vs {c['rate_b']:.4f} "
                           f"(difference {c['difference']:+.4f}, McNemar p = {c['p_value']:.3g}) is not a "
                           f"significant gain")
    for e, r in envs.items():
        c = r["success"]
        if c["p_value"] < alpha and c["difference"] < 0:
            reasons.append(f"environment {e}: success significantly lower ({c['difference']:+.4f}, "
                           f"p = {c['p_value']:.3g})")
        for key in ("ce", "mcte"):
            lo = r[key]["ci"][0]
            if r[key]["n"] > 1 and math.isfinite(lo) and lo > 0:
                reasons.append(f"environment {e}: {key.upper()} significantly higher on joint successes "
                               f"({r[key]['mean']:+.4g}, 95 % CI [{lo:.4g}, {r[key]['ci'][1]:.4g}])")
    return {"verdict": "no improvement" if reasons else "improvement", "reasons": reasons, "alpha": alpha,
            "target": list(target), "environments": envs}


def outcomes_from_rows(rows, method: str) -> dict:
    """Environment → ``{"success", "ce", "mcte", "run"}`` arrays (sorted by run) from ``runs.csv`` rows.

    Parameters
    ----------
    rows : list of dict
        Rows of :class:`mmg_casadi.montecarlo.results.ResultsTable`.
    method : str
        The method whose rows are used.

    Returns
    -------
    dict
        Environment to ``{"run", "success", "ce", "mcte"}`` arrays and a ``failure`` list, in run order.
    """
    out: dict = {}
    for r in rows:
        if r["method"] == method:
            out.setdefault(int(r["environment"]), []).append(r)
    res = {}
    for e, rs in out.items():
        rs.sort(key=lambda r: r["run"])
        res[e] = {"run": np.array([r["run"] for r in rs]), "success": np.array([bool(r["success"]) for r in rs]),
                  "ce": np.array([r["ce"] for r in rs], float), "mcte": np.array([r["mcte"] for r in rs], float),
                  "failure": [r["failure"] for r in rs]}
    return res


def write_params(path, values: dict, *, title: str, baseline: str, caveat: str, verdict: str, summary: str) -> None:
    """A tuner's ``params.toml``: the values in a ``[params]`` table, the held-out verdict in comments above.

    Parameters
    ----------
    path : str or Path
        Output file (its directory is made).
    values : dict
        Parameter name to value, in the order to write.
    title : str
        First comment line (what wrote the file).
    baseline : str
        What the values were judged against ("the paper's values").
    caveat : str
        Written after "these values are NOT shown to be better than" unless the verdict is an improvement.
    verdict : str
        ``"improvement"``, ``"no improvement"`` or ``"not judged"``.
    summary : str
        Comment lines.
    """
    lines = [f"# {title}", f"# held-out verdict against {baseline}: {verdict.upper()}"]
    if verdict != "improvement":
        lines.append(f"# these values are NOT shown to be better than {caveat}")
    lines += [f"# {s}" for s in summary.splitlines() if s.strip()]
    lines += ["[params]", *[f"{k} = {float(v)!r}" for k, v in values.items()]]
    write_text(path, "\n".join(lines) + "\n")

