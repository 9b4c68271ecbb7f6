"""Every study of the paper and a claim-by-claim reproduction report (``claims.md``, ``claims.json``).

``mmg-casadi study paper [--runs N] [--seed S] [--workers W] [--params P.toml] --out DIR`` runs the waypoint
square, the static obstacle (goal at 50 L and 60 L), the three COLREG encounters, the conflicting-responsibility
case, the narrow channel and the statistical analysis (``N`` runs per environment and method, the paper's 5000
by default) into sub-directories of ``DIR``, then checks every checkable statement of the paper's results
sections against the measurements (:data:`CLAIMS`).

Each claim is ``{"id", "section", "claim", "paper", "measured", "ci", "verdict"}`` with a verdict from
:data:`VERDICTS`. Rules, fixed before looking at the numbers:

* a number the paper quotes ("about 6 L", "CE = 0.1203") is *reproduced* within 25 % of it, *partly* within
  50 %, else *not reproduced*;
* a yes/no outcome (collision, which way a ship turns) is *reproduced* or *not reproduced*; a claim with
  several parts is *partly* when some parts hold;
* a statistical ordering ("A is better than B in every environment") is *reproduced* when it holds in every
  environment at the 5 % level (paired exact McNemar test for success rates, disjoint 95 % intervals for
  means), *partly* when it holds in some environments or only without significance, else *not reproduced*;
* a statement about something we cannot measure (e.g. a figure's unlabelled run) is *not testable*.

With a small ``--runs`` the intervals are wide and significance is rare: the ``ci`` column says how little the
verdict proves.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

from mmg_casadi.montecarlo.comparisons import compare_methods
from mmg_casadi.closed_loop.problem import build_problem
from mmg_casadi.colregs.scorer import judged_encounters
from mmg_casadi.io import write_json, write_text
from mmg_casadi.scenarios import encounters
from mmg_casadi.guidance.methods import AVOIDING, PAPER_STATISTICS, run_of
from mmg_casadi.montecarlo.study import check_resumable, check_study_args, run_study
from mmg_casadi.montecarlo.results import ResultsTable

from . import colregs, conflict, narrow_channel, static_obstacle, waypoint_square

VERDICTS = ("reproduced", "partly", "not reproduced", "not testable")
"""Allowed verdicts."""
PAPER_RUNS = 5000
"""Runs per environment and method in the paper's statistical analysis."""
MV, IS, VO = "modified-vortex", "inverse-square", "velocity-obstacle"
TURN_DEG = 5.0
"""Heading change (degrees) below which a ship "does not turn" (the COLREG profile's starboard_min_deg)."""


def run(out, *, runs: int = PAPER_RUNS, base_seed: int = 0, params=None, workers=None, envs="1-5",
        progress: bool = True) -> dict:
    """Run every study of the paper into ``out`` and write ``claims.md`` and ``claims.json``.

    Parameters
    ----------
    out : str or Path
        Output directory (one sub-directory per study).
    runs : int
        Runs per environment and method of the statistical analysis (≥ 1; the paper: 5000).
    base_seed : int
        Base seed of the scenario sampler.
    params : dict, optional
        Parameter overrides for every study.
    workers : int, optional
        Worker processes of the statistical analysis.
    envs : str or iterable of int
        Environments of the statistical analysis.
    progress : bool
        Show the statistical analysis's progress bar.

    Returns
    -------
    dict
        ``{"runs", "claims"}``.
    """
    with run_of((*AVOIDING, "none"), params):  # the quick studies run every avoiding method
        return _run(out, runs=runs, base_seed=base_seed, params=params, workers=workers, envs=envs,
                    progress=progress)


def _run(out, *, runs, base_seed, params, workers, envs, progress) -> dict:
    args = check_study_args(runs=runs, envs=envs, methods=PAPER_STATISTICS, base_seed=base_seed, params=params,
                            workers=workers)  # before the quick studies: bad input is refused at once
    check_resumable(Path(out) / "statistics", runs=args["runs"], envs=args["envs"], methods=args["methods"],
                    base_seed=args["base_seed"], params=args["params"], ranges=args["ranges"])
    for sc in _quick_scenarios():  # every run's steps and parameters, before the first run
        build_problem(sc, params)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    quick = {
        "waypoint-square": waypoint_square.run(out / "waypoint-square", params=params),
        "static-obstacle": static_obstacle.run(out / "static-obstacle", params=params),
        "colregs": colregs.run(out / "colregs", params=params),
        "conflict": conflict.run(out / "conflict", params=params),
        "narrow-channel": narrow_channel.run(out / "narrow-channel", params=params),
    }
    envs = args["envs"]
    summary = run_study(out / "statistics", runs=runs, envs=envs, methods=PAPER_STATISTICS, base_seed=base_seed,
                        params=params, workers=workers, progress=progress)
    rows = [r for r in ResultsTable(out / "statistics" / "runs.csv").read()
            if r["run"] < runs and r["environment"] in envs and r["method"] in PAPER_STATISTICS]
    claims = evaluate_claims(quick, summary.rows, rows)
    write_json(out / "claims.json", claims)
    write_text(out / "claims.md", claims_markdown(claims, runs=runs))
    print(claims_markdown(claims, runs=runs), file=sys.stderr)
    return {"runs": runs, "claims": claims}


# ------------------------------------------------------------------------------------------------ helpers

def _quick_scenarios() -> list:
    """The scenarios of the quick studies (each is run with several methods and the same parameters)."""
    return [encounters.waypoint_square(), *encounters.static_obstacle_cases().values(),
            *encounters.colregs_cases().values(), *encounters.conflict_cases().values(),
            *encounters.narrow_channel_cases().values()]


def _claim(cid, section, claim, paper, measured, ci, verdict) -> dict:
    assert verdict in VERDICTS, verdict
    return {"id": cid, "section": section, "claim": claim, "paper": paper, "measured": measured, "ci": ci,
            "verdict": verdict}


def _near(measured, paper) -> str:
    """Verdict of a quoted number: within 25 % reproduced, 50 % partly."""
    if measured is None or not math.isfinite(measured):
        return "not reproduced"
    rel = abs(measured - paper) / abs(paper)
    return "reproduced" if rel <= 0.25 else "partly" if rel <= 0.5 else "not reproduced"


def _all_some(flags) -> str:
    flags = list(flags)
    return "reproduced" if flags and all(flags) else "partly" if any(flags) else "not reproduced"


def _worst(*verdicts) -> str:
    order = {"reproduced": 0, "partly": 1, "not reproduced": 2}
    v = [x for x in verdicts if x in order]
    if not v:
        return "not testable"
    if all(x == "reproduced" for x in v):
        return "reproduced"
    return "not reproduced" if all(x == "not reproduced" for x in v) else "partly"


def _case(quick, study, case, method):
    return quick[study]["cases"][case][method]


def _pair(metrics, a="ship1", b="ship2"):
    for p in metrics["pairs"]:
        if p["a"] == a and p["b"] == b:
            return p
    raise KeyError((a, b))


def _kept(encounters):
    """Whether a ship kept every rule in all of its encounters with a risk of collision (``None`` without one)."""
    judged = [e["compliant"] for e in judged_encounters(encounters)]
    return all(judged) if judged else None


def _turn(pair, side) -> str:
    """Dominant turn of one side of a ship pair in its encounter window: starboard, port or none."""
    rules = pair.get("rules") or {}
    q = (rules.get(side) or {}).get("quantities") or {}
    stbd, port = q.get("starboard_change_deg") or 0.0, q.get("port_change_deg") or 0.0
    if max(stbd, port) < TURN_DEG:
        return "none"
    return "starboard" if stbd >= port else "port"


def _f(x, digits=3):
    return None if x is None or (isinstance(x, float) and not math.isfinite(x)) else round(float(x), digits)


def _cell(summary_rows, env, method):
    for r in summary_rows:
        if r["environment"] == env and r["method"] == method:
            return r
    return None


def _ci(r, metric, scale=1.0, digits=3):
    if r is None:
        return None
    lo, hi = (r["success_ci_low"], r["success_ci_high"]) if metric == "success" else (
        r[f"{metric}_ci_low"], r[f"{metric}_ci_high"])
    return [_f(scale * lo, digits), _f(scale * hi, digits)]


def _mean(r, metric):
    if r is None:
        return math.nan
    return r["success_rate"] if metric == "success" else r[f"{metric}_mean"]


def _below(ra, rb, metric) -> tuple[bool, bool]:
    """(mean of a below mean of b, and their 95 % intervals disjoint)."""
    a, b = _mean(ra, metric), _mean(rb, metric)
    if not (math.isfinite(a) and math.isfinite(b)):
        return False, False
    ha = ra["success_ci_high"] if metric == "success" else ra[f"{metric}_ci_high"]
    lb = rb["success_ci_low"] if metric == "success" else rb[f"{metric}_ci_low"]
    return a < b, bool(a < b and math.isfinite(ha) and math.isfinite(lb) and ha < lb)


def _ordering(summary_rows, envs, low, high, metric) -> tuple[str, dict, dict]:
    """Verdict of "``low`` has a smaller ``metric`` than ``high`` in every environment" by disjoint intervals."""
    measured, ci, flags, sig = {}, {}, [], []
    for e in envs:
        rl, rh = _cell(summary_rows, e, low), _cell(summary_rows, e, high)
        if rl is None or rh is None:
            continue
        below, disjoint = _below(rl, rh, metric)
        measured[f"env{e}"] = [_f(_mean(rl, metric)), _f(_mean(rh, metric))]
        ci[f"env{e}"] = [_ci(rl, metric), _ci(rh, metric)]
        flags.append(below)
        sig.append(disjoint)
    if flags and all(sig):
        verdict = "reproduced"
    elif any(flags):
        verdict = "partly"
    else:
        verdict = "not reproduced"
    return verdict, measured, ci


def _success_better(comparisons, envs, better, worse) -> tuple[str, dict, dict]:
    measured, ci, flags, sig = {}, {}, [], []
    for e in envs:
        c = next((c for c in comparisons if c["environment"] == e and {c["method_a"], c["method_b"]} ==
                  {better, worse}), None)
        if c is None:
            continue
        sign = 1 if c["method_a"] == better else -1
        d = sign * c["difference"]
        lo, hi = sorted((sign * c["ci_low"], sign * c["ci_high"]))
        measured[f"env{e}"] = {"difference_pp": _f(100 * d, 2), "p": float(f"{c['p_value']:.3g}")}
        ci[f"env{e}"] = [_f(100 * lo, 2), _f(100 * hi, 2)]
        flags.append(d > 0)
        sig.append(d > 0 and c["p_value"] < 0.05)
    verdict = "reproduced" if flags and all(sig) else "partly" if any(flags) else "not reproduced"
    return verdict, measured, ci


# ------------------------------------------------------------------------------------------------- claims

def evaluate_claims(quick: dict, summary_rows: list, rows: list) -> list[dict]:
    """The paper's checkable statements with what we measured and a verdict (see the module notes).

    Parameters
    ----------
    quick : dict
        ``metrics.json`` of the quick studies by name: ``waypoint-square``, ``static-obstacle``, ``colregs``,
        ``conflict``, ``narrow-channel``.
    summary_rows : list of dict
        ``rows`` of the :class:`mmg_casadi.montecarlo.results.Summary` of the statistical analysis.
    rows : list of dict
        Its run rows (for the paired comparisons and the failure mechanisms).

    Returns
    -------
    list of dict
        One dict per claim (keys ``id``, ``section``, ``claim``, ``paper``, ``measured``, ``ci``, ``verdict``).
    """
    c = []
    # ---------------------------------------------------------------- waypoint tracking
    wp = quick["waypoint-square"]
    c.append(_claim("W1", "Waypoint tracking", "ILOS + PD tracks the square with controller effort CE = 0.1203",
                    0.1203, _f(wp["ce"], 4), None, _near(wp["ce"], 0.1203)))
    c.append(_claim("W2", "Waypoint tracking", "mean cross-track error MCTE = 0.2655 L on the square",
                    0.2655, _f(wp["mcte"], 4), None, _near(wp["mcte"], 0.2655)))
    # ---------------------------------------------------------------- static obstacle
    so = "static-obstacle"
    is50, is60 = _case(quick, so, "goal-50", IS), _case(quick, so, "goal-60", IS)
    own50 = is50["ships"][0]
    c.append(_claim("S1", "Inverse square potential", "goal at 50 L: the inverse-square APF avoids the obstacle "
                    "at (25, 0) and reaches the goal, coming close to the 2 L threshold; CE = 0.2015",
                    {"collision": False, "ce": 0.2015},
                    {"collision": is50["collision"], "reached": own50["reached_goal"], "ce": _f(own50["ce"], 4),
                     "min_distance": _f(own50["min_distance"])}, None,
                    _worst("reproduced" if not is50["collision"] and own50["reached_goal"] else "not reproduced",
                           _near(own50["ce"], 0.2015))))
    own60 = is60["ships"][0]
    c.append(_claim("S2", "Inverse square potential", "goal at 60 L: the goal's attraction dwarfs the obstacle's "
                    "repulsion; the ship enters the 2 L collision threshold and does not reach the goal",
                    {"collision": True, "reached": False},
                    {"collision": is60["collision"], "reached": own60["reached_goal"],
                     "min_distance": _f(own60["min_distance"])}, None,
                    _all_some([is60["collision"], not own60["reached_goal"]])))
    sv50 = _case(quick, so, "goal-50", "sink-vortex")
    d_is, d_sv = own50["min_distance"], sv50["ships"][0]["min_distance"]
    c.append(_claim("S3", "Harmonic potential functions", "sink-vortex (K = −10, Λ = −100): rudder almost at once, "
                    "closest approach about twice the inverse square's, CE = 0.0852",
                    {"ce": 0.0852, "distance_ratio": 2.0},
                    {"ce": _f(sv50["ships"][0]["ce"], 4), "distance_ratio": _f(d_sv / d_is)}, None,
                    _worst(_near(sv50["ships"][0]["ce"], 0.0852), _near(d_sv / d_is, 2.0))))
    sb_sv, sb_mv = _case(quick, so, "starboard-bow", "sink-vortex"), _case(quick, so, "starboard-bow", MV)
    c.append(_claim("S4", "Harmonic potential functions", "an obstacle approached on the starboard side draws the "
                    "sink-vortex ship into a collision; the modified vortex reaches the goal (our obstacle at "
                    "(25, 1.5) L: the paper gives no coordinates)",
                    {"sink-vortex collision": True, "modified-vortex collision": False},
                    {"sink-vortex collision": sb_sv["collision"], "modified-vortex collision": sb_mv["collision"]},
                    None, _all_some([sb_sv["collision"], not sb_mv["collision"]])))
    mv50 = _case(quick, so, "goal-50", MV)
    c.append(_claim("S5", "Harmonic potential functions", "the modified sink-vortex avoids the obstacle (goal 50 L) "
                    "with a margin between the inverse square's and the sink-vortex's", {"collision": False},
                    {"collision": mv50["collision"], "min_distance": _f(mv50["ships"][0]["min_distance"]),
                     "inverse-square": _f(d_is), "sink-vortex": _f(d_sv)}, None,
                    _all_some([not mv50["collision"],
                               min(d_is, d_sv) <= mv50["ships"][0]["min_distance"] <= max(d_is, d_sv)])))
    # ---------------------------------------------------------------- COLREG encounters
    cr = "colregs"
    want = {MV: {"overtaking": (8.0, None, None, "starboard"), "head-on": (6.0, "starboard", "starboard", None),
                 "crossing": (6.0, "starboard", "none", None)},
            VO: {"overtaking": (4.0, None, None, None), "head-on": (6.0, "port", "port", None),
                 "crossing": (6.0, "port", "port", None)}}
    texts = {MV: {"overtaking": "the overtaking ship passes on the overtaken ship's starboard side, min distance "
                                "a little over 8 L",
                  "head-on": "both ships turn to starboard, min distance about 6 L",
                  "crossing": "the give-way ship (ship 1) turns to starboard, the stand-on ship does not deviate "
                              "significantly, min distance about 6 L"},
             VO: {"overtaking": "both ships change heading (the overtaken ship does not stand on), no collision, "
                                "min distance 4 L",
                  "head-on": "both ships turn to port, no collision, min distance about 6 L",
                  "crossing": "both ships turn to port, no collision, min distance about 6 L"}}
    k = 0
    for method in (MV, VO):
        for case in ("overtaking", "head-on", "crossing"):
            k += 1
            m = _case(quick, cr, case, method)
            p = _pair(m)
            d_paper, turn_a, turn_b, side = want[method][case]
            meas = {"collision": m["collision"], "min_distance": _f(p["min_distance"]),
                    "ship1_turns": _turn(p, "a"), "ship2_turns": _turn(p, "b")}
            parts = [not m["collision"], _near(p["min_distance"], d_paper) == "reproduced"]
            if turn_a:
                parts.append(meas["ship1_turns"] == turn_a)
            if turn_b:
                parts.append(meas["ship2_turns"] == turn_b)
            if method == VO and case == "overtaking":
                parts.append(meas["ship2_turns"] != "none")
            if side:
                q = (p["rules"] or {}).get("a", {}).get("quantities", {})
                meas["overtaken_ship_on_the_overtakers"] = q.get("other_side_at_cpa")
                parts.append(q.get("other_side_at_cpa") == "port")  # overtaker passes on the overtaken's starboard
            c.append(_claim(f"C{k}", "Dynamic obstacle avoidance", f"{method}, {case}: {texts[method][case]}",
                            {"collision": False, "min_distance": d_paper, "ship1": turn_a, "ship2": turn_b},
                            meas, None, _all_some(parts)))
    inv = {case: _case(quick, cr, case, IS) for case in ("overtaking", "head-on", "crossing")}
    p_ov = _pair(inv["overtaking"])
    q_ov = (p_ov["rules"] or {}).get("a", {}).get("quantities", {})
    c.append(_claim("C7", "Dynamic obstacle avoidance", "inverse square: the overtaking ship passes on the overtaken "
                    "ship's port side (min distance about 3 L); head-on and crossing end in collisions",
                    {"overtaking side": "port", "min_distance": 3.0, "head-on collision": True,
                     "crossing collision": True},
                    {"overtaken_ship_on_the_overtakers": q_ov.get("other_side_at_cpa"),
                     "min_distance": _f(p_ov["min_distance"]), "head-on collision": inv["head-on"]["collision"],
                     "crossing collision": inv["crossing"]["collision"]}, None,
                    _all_some([q_ov.get("other_side_at_cpa") == "starboard",
                               _near(p_ov["min_distance"], 3.0) == "reproduced",
                               inv["head-on"]["collision"], inv["crossing"]["collision"]])))
    mv_ok = []
    for case in ("overtaking", "head-on", "crossing"):
        p = _pair(_case(quick, cr, case, MV))
        mv_ok.append({"case": case, "ship1": _kept(p["encounters"]["a"]), "ship2": _kept(p["encounters"]["b"])})
    flags = [x is not False for d in mv_ok for x in (d["ship1"], d["ship2"])]
    c.append(_claim("C8", "Dynamic obstacle avoidance", "the modified sink-vortex follows COLREG rules 13, 14 and 15 "
                    "(both ships of each encounter; encounter scorer, risky encounters, profile colregs_profile)",
                    True, mv_ok, None, _all_some(flags)))
    # ---------------------------------------------------------------- conflict
    cf = {m: _case(quick, "conflict", "three-ships", m) for m in (MV, IS, VO)}

    def _collided(m, name):
        return next(s for s in m["ships"] if s["name"] == name)["collided"]

    is_parts = [_collided(cf[IS], "ship1") and _collided(cf[IS], "ship3"), not _collided(cf[IS], "ship2")]
    c.append(_claim("K1", "Conflicting responsibility", "inverse square: ships 1 and 3 collide, ship 2 avoids in the "
                    "nick of time", {"1-3 collide": True, "ship 2 collides": False},
                    {"1-3 collide": is_parts[0], "ship 2 collides": _collided(cf[IS], "ship2")}, None,
                    _all_some(is_parts)))

    def _min_own(m):
        return min(p["min_distance"] for p in m["pairs"] if "ship1" in (p["a"], p["b"]) and
                   not str(p["b"]).startswith("obstacle"))

    def _compliant_all(m):
        vals = [_kept(p["encounters"][side]) for p in m["pairs"] if "encounters" in p for side in ("a", "b")]
        vals = [v for v in vals if v is not None]
        return all(vals) if vals else None

    c.append(_claim("K2", "Conflicting responsibility", "velocity obstacle: collision free, min distance of ship 1 "
                    "about 4 L, not following the COLREGs", {"collision": False, "min_distance": 4.0,
                                                             "compliant": False},
                    {"collision": cf[VO]["collision"], "min_distance": _f(_min_own(cf[VO])),
                     "compliant": _compliant_all(cf[VO])}, None,
                    _all_some([not cf[VO]["collision"], _near(_min_own(cf[VO]), 4.0) == "reproduced",
                               _compliant_all(cf[VO]) is False])))
    c.append(_claim("K3", "Conflicting responsibility", "modified sink-vortex: collision free, following the "
                    "COLREGs, min distance of ship 1 about 6 L", {"collision": False, "min_distance": 6.0,
                                                                  "compliant": True},
                    {"collision": cf[MV]["collision"], "min_distance": _f(_min_own(cf[MV])),
                     "compliant": _compliant_all(cf[MV])}, None,
                    _all_some([not cf[MV]["collision"], _near(_min_own(cf[MV]), 6.0) == "reproduced",
                               _compliant_all(cf[MV]) is True])))
    # ---------------------------------------------------------------- narrow channel
    nc = _case(quick, "narrow-channel", "head-on", MV)
    dnc = _pair(nc)["min_distance"]
    c.append(_claim("N1", "Narrow waterways", "modified sink-vortex head-on in a 10 L channel: no collision, min "
                    "distance a little over 2 L", {"collision": False, "min_distance": 2.0},
                    {"collision": nc["collision"], "min_distance": _f(dnc)}, None,
                    _all_some([not nc["collision"], 2.0 <= dnc <= 3.0])))
    # ---------------------------------------------------------------- statistics
    envs = sorted({r["environment"] for r in summary_rows})
    comps = compare_methods(rows, PAPER_STATISTICS)
    v, meas, ci = _success_better(comps, envs, MV, IS)
    c.append(_claim("T1", "Statistical analysis", "success: the modified sink-vortex beats the inverse square in "
                    "every environment (paired, exact McNemar)", "MV > IS in env 1-5", meas, ci, v))
    v, meas, ci = _success_better(comps, envs, MV, VO)
    c.append(_claim("T2", "Statistical analysis", "success: the modified sink-vortex beats the velocity obstacle "
                    "in every environment (paired, exact McNemar)", "MV > VO in env 1-5", meas, ci, v))
    low_envs = [e for e in envs if e <= 2]
    mv_low = {f"env{e}": _f(_cell(summary_rows, e, MV)["success_rate"], 4) for e in low_envs}
    ci_low = {f"env{e}": _ci(_cell(summary_rows, e, MV), "success", digits=4) for e in low_envs}
    c.append(_claim("T3", "Statistical analysis", "the modified sink-vortex keeps over 99 % success in the less "
                    "congested environments (1, 2)", "> 0.99", mv_low, ci_low,
                    _all_some([_cell(summary_rows, e, MV)["success_rate"] > 0.99 for e in low_envs])
                    if low_envs else "not testable"))
    r5 = _cell(summary_rows, 5, MV)
    if r5 is not None:
        lo, hi = r5["success_ci_low"], r5["success_ci_high"]
        v = "reproduced" if lo <= 0.97 <= hi or abs(r5["success_rate"] - 0.97) <= 0.005 else (
            "partly" if abs(r5["success_rate"] - 0.97) <= 0.015 else "not reproduced")
        c.append(_claim("T4", "Statistical analysis", "in environment 5 (4 static, 9 dynamic obstacles) the modified "
                        "sink-vortex reaches 97 % success (conclusion: about 3 % still collide)", 0.97,
                        _f(r5["success_rate"], 4), [_f(lo, 4), _f(hi, 4)], v))
    first, last = (envs[0], envs[-1]) if envs else (1, 5)
    for cid, method in (("T5", IS), ("T6", VO)):
        r1, rl = _cell(summary_rows, first, method), _cell(summary_rows, last, method)
        if r1 is None or rl is None or first == last:
            continue
        below, disjoint = _below(rl, r1, "success")
        c.append(_claim(cid, "Statistical analysis", f"{method}: success decreases as the environment becomes more "
                        "congested" + (" — 'significantly' in environments 3, 4 and 5" if method == VO else ""),
                        f"env{last} < env{first}", {f"env{first}": _f(r1["success_rate"], 4),
                                                    f"env{last}": _f(rl["success_rate"], 4)},
                        {f"env{first}": _ci(r1, "success", digits=4), f"env{last}": _ci(rl, "success", digits=4)},
                        "reproduced" if disjoint else "partly" if below else "not reproduced"))
    # computation cost
    v1, m1, ci1 = _ordering(summary_rows, envs, MV, VO, "guidance_call_us")
    v2, m2, _ = _ordering(summary_rows, envs, IS, VO, "guidance_call_us")
    c.append(_claim("T7", "Statistical analysis", "both APFs have a significantly lower computation cost per "
                    "guidance call than the velocity obstacle", "APF < VO in env 1-5",
                    {"MV vs VO [µs]": m1, "IS vs VO [µs]": m2}, ci1, _worst(v1, v2)))
    growth = {}
    for m in (MV, IS, VO):
        r1, rl = _cell(summary_rows, first, m), _cell(summary_rows, last, m)
        if r1 and rl:
            growth[m] = rl["guidance_call_us_mean"] / r1["guidance_call_us_mean"] - 1.0
    if VO in growth:
        c.append(_claim("T8", "Statistical analysis", "the velocity obstacle's computation time grows by more than "
                        "100 % as the environment gets more congested", "> +100 %",
                        {f"env{first}->env{last}": _f(100 * growth[VO], 1)}, None,
                        "reproduced" if growth[VO] > 1.0 else "partly" if growth[VO] > 0.5 else "not reproduced"))
    if MV in growth and IS in growth:
        apf_ok = [growth[m] < 0.5 for m in (MV, IS)]
        c.append(_claim("T9", "Statistical analysis", "the APFs' computation cost does not increase significantly "
                        "with congestion (we read: by less than 50 %, and far less than the VO's)", "< +50 %",
                        {m: _f(100 * growth[m], 1) for m in (MV, IS)}, None, _all_some(apf_ok)))
    ratio = {f"env{e}": _f(_cell(summary_rows, e, MV)["guidance_call_us_mean"]
                           / _cell(summary_rows, e, IS)["guidance_call_us_mean"], 3) for e in envs}
    in_band = [1.2 <= x <= 1.35 for x in ratio.values()]
    c.append(_claim("T10", "Statistical analysis", "a modified sink-vortex call costs 25-30 % more than an inverse "
                    "square call", "ratio 1.25-1.30", ratio, None,
                    "reproduced" if in_band and all(in_band) else "partly" if any(x > 1 for x in ratio.values())
                    else "not reproduced"))
    # time to goal
    inc = {}
    for m in (MV, IS, VO):
        r1, rl = _cell(summary_rows, first, m), _cell(summary_rows, last, m)
        inc[m] = (r1["time_to_goal_mean"], rl["time_to_goal_mean"], _below(r1, rl, "time_to_goal"))
    c.append(_claim("T11", "Statistical analysis", "the mean time to goal increases in more congested environments "
                    "for all three methods", f"env{last} > env{first}",
                    {m: [_f(a), _f(b)] for m, (a, b, _) in inc.items()}, None,
                    _worst(*("reproduced" if s[1] else "partly" if s[0] else "not reproduced"
                             for _, _, s in inc.values()))))
    rel = {m: inc[m][1] / inc[m][0] - 1.0 for m in inc}
    c.append(_claim("T12", "Statistical analysis", "the velocity obstacle's time to goal rises sharply with "
                    "congestion, the APFs' only mildly", "VO increase >> APF increases",
                    {m: _f(100 * v_, 1) for m, v_ in rel.items()}, None,
                    "reproduced" if rel[VO] > 2 * max(rel[MV], rel[IS]) else
                    "partly" if rel[VO] > max(rel[MV], rel[IS]) else "not reproduced"))
    margin = {}
    for e in envs:
        tv, tm = _cell(summary_rows, e, VO)["time_to_goal_mean"], _cell(summary_rows, e, MV)["time_to_goal_mean"]
        margin[f"env{e}"] = _f(100 * (tv - tm) / tv, 1)
    band = [10 <= x <= 30 for x in margin.values() if x is not None]
    c.append(_claim("T13", "Statistical analysis / conclusion", "the modified sink-vortex beats the velocity obstacle "
                    "in time to goal by a 10-30 % margin", "10-30 %", margin,
                    {f"env{e}": [_ci(_cell(summary_rows, e, MV), "time_to_goal"),
                                 _ci(_cell(summary_rows, e, VO), "time_to_goal")] for e in envs},
                    "reproduced" if band and all(band) else
                    "partly" if any(x > 0 for x in margin.values() if x is not None) else "not reproduced"))
    # control effort
    v, meas, ci = _ordering(summary_rows, envs, MV, IS, "ce")
    c.append(_claim("T14", "Statistical analysis", "the modified sink-vortex's control effort is significantly "
                    "lower than the inverse square's", "CE MV < IS", meas, ci, v))
    v1, m1, ci1 = _ordering(summary_rows, envs, VO, MV, "ce")
    v2, m2, _ = _ordering(summary_rows, envs, VO, IS, "ce")
    c.append(_claim("T15", "Statistical analysis", "the velocity obstacle's control effort is consistently lower "
                    "than the APFs'", "CE VO < MV, IS", {"VO vs MV": m1, "VO vs IS": m2}, ci1, _worst(v1, v2)))
    # cross-track error
    grows = []
    meas = {}
    for m in (MV, IS):
        r1, rl = _cell(summary_rows, first, m), _cell(summary_rows, last, m)
        b, dis = _below(r1, rl, "mcte")
        meas[m] = [_f(r1["mcte_mean"]), _f(rl["mcte_mean"])]
        grows.append("reproduced" if dis else "partly" if b else "not reproduced")
    c.append(_claim("T16", "Statistical analysis", "the mean cross-track error of both APFs increases in more "
                    "congested environments", f"env{last} > env{first}", meas, None, _worst(*grows)))
    cong = [e for e in envs if e >= 3]
    diff = {f"env{e}": _f(100 * (_cell(summary_rows, e, MV)["mcte_mean"] / _cell(summary_rows, e, IS)["mcte_mean"]
                                 - 1), 1) for e in cong}
    ok = [x is not None and 0 < x <= 25 for x in diff.values()]
    c.append(_claim("T17", "Statistical analysis", "in congested environments (3-5) the modified sink-vortex's MCTE "
                    "is marginally higher than the inverse square's (we read: 0-25 % higher)", "0 to +25 %", diff,
                    None, _all_some(ok) if ok else "not testable"))
    v1, m1, ci1 = _ordering(summary_rows, envs, MV, VO, "mcte")
    v2, m2, _ = _ordering(summary_rows, envs, IS, VO, "mcte")
    c.append(_claim("T18", "Statistical analysis", "the velocity obstacle's mean cross-track error is significantly "
                    "larger than both APFs'", "MCTE VO > MV, IS", {"MV vs VO": m1, "IS vs VO": m2}, ci1,
                    _worst(v1, v2)))
    # failure mechanisms
    failed = [r for r in rows if r["method"] == MV and not r["success"]]
    named = {m: sum(1 for r in failed if r["failure_mechanism"] == m)
             for m in ("started-too-close", "near-goal", "obstacle-near-goal")}
    share = sum(named.values()) / len(failed) if failed else math.nan
    c.append(_claim("L1", "Limitations", "the modified sink-vortex's failures come from two mechanisms: ships "
                    "starting too close to avoid each other, and encounters near a ship's goal (we read: most "
                    "failures are of these two kinds)", "two main mechanisms",
                    {"failed": len(failed), **named, "share": _f(share)}, None,
                    "not testable" if not failed else "reproduced" if share >= 0.5 else
                    "partly" if share >= 0.25 else "not reproduced"))
    c.append(_claim("X1", "Statistical analysis", "the environment-1 sample case (figure env_01): the VO's second "
                    "ship flips the rudder between ±35° and collides with the first", "collision",
                    None, None, "not testable"))
    return c


def claims_markdown(claims, *, runs: int | None = None) -> str:
    """``claims`` as a Markdown report: one table row per claim, counts of verdicts first.

    Parameters
    ----------
    claims : list of dict
        Output of :func:`evaluate_claims`.
    runs : int, optional
        Runs per environment and method of the statistical analysis (stated in the header).

    Returns
    -------
    str
        The report, ending with a newline.

    Examples
    --------
    >>> print(claims_markdown([_claim("W1", "Waypoint tracking", "CE", 0.12, 0.13, None, "reproduced")]))
    ... # doctest: +NORMALIZE_WHITESPACE
    # Reproduction of the paper, claim by claim
    <BLANKLINE>
    reproduced: 1, partly: 0, not reproduced: 0, not testable: 0
    <BLANKLINE>
    | id | section | claim | paper | measured | 95 % CI | verdict |
    |---|---|---|---|---|---|---|
    | W1 | Waypoint tracking | CE | 0.12 | 0.13 | – | reproduced |
    """
    head = ["# Reproduction of the paper, claim by claim", ""]
    if runs is not None:
        head += [f"Statistical analysis: {runs} runs per environment and method (the paper: {PAPER_RUNS}).", ""]
    counts = ", ".join(f"{v}: {sum(1 for c in claims if c['verdict'] == v)}" for v in VERDICTS)
    lines = head + [counts, "", "| id | section | claim | paper | measured | 95 % CI | verdict |",
                    "|---|---|---|---|---|---|---|"]

    def cell(x):
        if x is None:
            return "–"
        return (x if isinstance(x, str) else json.dumps(x, ensure_ascii=False)).replace("|", "\\|")

    for c in claims:
        lines.append(f"| {c['id']} | {c['section']} | {cell(c['claim'])} | {cell(c['paper'])} | "
                     f"{cell(c['measured'])} | {cell(c['ci'])} | {c['verdict']} |")
    return "\n".join(lines) + "\n"
