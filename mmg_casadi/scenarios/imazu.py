"""The 22 Imazu encounter problems, scaled to the KCS, as scenario dicts; a runner and a figure of all 22.

Geometry. Imazu's problems (H. Imazu, 1987; reproduced in Sawada, Sato, Majima, J. Mar. Sci. Technol. 26 (2021)
1243) put the own ship and one to three target ships on straight courses that all pass through one point at the
same time if nobody manoeuvres. The target headings and which targets are slow were read from the public
encoding in MarWaltz/TUD_RL, ``tud_rl/envs/_envs/Imazu.py`` (commit 9000de0, "the 22 ship encounter situations
of Imazu (1987) as detailed in Sawada et al. (2021, JMST)"): the own ship heads north (0°); cases 1–4 have one
target, 5–12 two, 13–22 three. In that encoding cases 5 and 8 are identical (a head-on and a crossing target
from starboard); kept as read. A later file of the same repository (``MMG_Imazu.py``) gives case 12 a third,
head-on target; the two-target form used here agrees with an independent encoding of the same table.

Scaling to the KCS: in Imazu's problems every ship starts 6 NM from the meeting point (about 48 KCS lengths of
230 m); here the range is ``MEET_DISTANCE`` = 40 L. The own ship starts at (0, 0) with heading 0° and the
design speed, the meeting point is (40 L, 0); every target starts at ``meeting − speed × 40 × (cos χ, sin χ)``,
i.e. it reaches the meeting point at t = 40 (L/U) like the own ship. Targets run at the design speed except the ship
being overtaken, which runs at ``SLOW_SPEED`` = 0.5 (the lower end of the paper's target speeds, U_des/2; the
sources differ: propeller revolutions 0.7/1.8 in TUD_RL, a 0.7 speed ratio in others). Every ship's goal lies
on its course ``GOAL_PAST`` = 30 L (scaled by its speed) past the meeting point, so without manoeuvres all ships
reach their goals together at t = 70.

Examples
--------
>>> d = imazu_case(1, method="modified-vortex", targets="hold")
>>> [s["start"] for s in d["ships"]], d["ships"][1]["heading"], d["ships"][1]["method"]
([[0.0, 0.0], [80.0, 0.0]], 180.0, 'none')
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.figure import Figure

from mmg_casadi.colregs.geometry import bearing
from mmg_casadi.colregs.profiles import scoring_profile
from mmg_casadi.colregs.roles import classify_roles
from mmg_casadi.colregs.scorer import judged_encounters
from mmg_casadi.errors import InputError, check_range
from mmg_casadi.io import save_figure
from mmg_casadi.plotting import COLORS, FIGURE_DPI, draw_goal, draw_path, marine_axes
from mmg_casadi.guidance import methods as registry
from mmg_casadi.params import PARAMETERS
from mmg_casadi.scenarios.run import run_scenario
from mmg_casadi.scenarios.scenario import scenario_from_dict
from mmg_casadi.vessel.maneuvers import last_moment_manoeuvre, turning_circle

MEET_DISTANCE = 40.0  #: L, own ship start to the common meeting point
GOAL_PAST = 30.0  #: L, own ship goal beyond the meeting point (targets: scaled by their speed)
SLOW_SPEED = 0.5  #: fraction of design speed of the ship being overtaken
T_MAX = 200.0  #: horizon (L/U); an unhindered own ship needs 70
TARGET_MODES = ("hold", "avoid")

#: case -> target headings (degrees, from north towards east); a ``"slow"`` suffix marks the overtaken ship
CASES = {
    1: (180,), 2: (270,), 3: ("0slow",), 4: (45,),
    5: (180, 270), 6: (-10, -45), 7: ("0slow", -45), 8: (180, 270), 9: (-30, -90), 10: (-90, 15),
    11: (90, -30), 12: (-45, -10),
    13: (180, 10, 45), 14: (-10, -45, -90), 15: ("0slow", -45, -90), 16: (45, 90, -90), 17: ("0slow", 10, -45),
    18: (-135, -15, -30), 19: (15, -15, -135), 20: ("0slow", -15, -90), 21: (-15, 15, -90),
    22: ("0slow", -45, -90),
}


def _targets(k: int) -> list[tuple[float, float]]:
    """(heading in degrees, speed) of each target of case ``k``."""
    out = []
    for h in CASES[k]:
        if isinstance(h, str):
            out.append((float(h.removesuffix("slow")), SLOW_SPEED))
        else:
            out.append((float(h), 1.0))
    return out


def _track(head: float, speed: float) -> tuple[np.ndarray, np.ndarray]:
    """Start (L) and unit direction of a target on ``head`` (degrees) at ``speed`` that reaches the meeting point
    at t = ``MEET_DISTANCE`` without manoeuvres."""
    e = np.array([math.cos(math.radians(head)), math.sin(math.radians(head))])
    return np.array([MEET_DISTANCE, 0.0]) - speed * MEET_DISTANCE * e, e


def _check_case(k) -> int:
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k not in CASES:
        raise InputError("case", "an integer from 1 to 22", k)
    return int(k)


def imazu_case(k: int, *, method: str, targets: str = "hold", t_max: float = T_MAX) -> dict:
    """Scenario dict (the scenario-file shape, see :mod:`mmg_casadi.scenarios.scenario`) of Imazu problem ``k``.

    Parameters
    ----------
    k : int
        Problem number, 1 to 22.
    method : str
        Guidance method of the own ship (one of :data:`mmg_casadi.guidance.methods.METHODS`).
    targets : str
        ``"hold"``: targets keep course and speed (method ``"none"``); ``"avoid"``: they use ``method`` too.
    t_max : float
        Horizon (L/U).

    Returns
    -------
    dict
        ``settings`` (``method``, ``t_max``) and ``ships``: the own ship from the origin heading north, then the
        targets (positions in L, headings in degrees, speeds as fractions of U_des).

    Examples
    --------
    >>> d = imazu_case(3, method="velocity-obstacle", targets="avoid")
    >>> d["ships"][1]["start"], d["ships"][1]["speed"], d["ships"][1]["method"]
    ([20.0, 0.0], 0.5, 'velocity-obstacle')
    >>> round(math.dist(d["ships"][0]["waypoints"][0], d["ships"][0]["start"]), 6)
    70.0
    """
    k = _check_case(k)
    registry.get(method, "method")
    if targets not in TARGET_MODES:
        raise InputError("targets", "one of: hold, avoid", targets)
    meet = np.array([MEET_DISTANCE, 0.0])
    ships = [{"name": "own", "start": [0.0, 0.0], "heading": 0.0, "speed": 1.0,
              "waypoints": [[MEET_DISTANCE + GOAL_PAST, 0.0]]}]
    for i, (head, speed) in enumerate(_targets(k)):
        start, e = _track(head, speed)
        goal = meet + speed * GOAL_PAST * e
        ships.append({"name": f"target{i + 1}", "start": [round(float(v), 9) + 0.0 for v in start],
                      "heading": head, "speed": speed, "waypoints": [[round(float(v), 9) + 0.0 for v in goal]],
                      "method": "none" if targets == "hold" else method})
    return {"settings": {"method": method, "t_max": float(t_max)}, "ships": ships}


def stand_on_bound(k: int, *, profile=None, rudder_deg: float = 35.0, step: float = 0.25) -> list[dict]:
    """What a stand-on own ship can still do in Imazu problem ``k`` when every target holds course and speed and she
    keeps hers as the scorer asks (Rule 17(a)): the widest passing of her last-moment manoeuvre.

    Every ship reaches the meeting point at t = 40 without manoeuvres, so the give-way ship's inaction becomes
    apparent at a known time: the scoring profile's ``late``, TCPA ``late_tcpa`` or range ``late_range``,
    whichever comes first (at the start if it has already come). A stand-on ship may act alone from then on; her
    action is her first change of course of ``course_tolerance_deg`` (Rule 17(a)(i) counts nothing smaller), so
    the earliest lawful hard-over turn is the one that reaches that change at ``late``. Each turn from then to the
    meeting time, in ``step`` steps, to either side (:func:`~mmg_casadi.vessel.maneuvers.last_moment_manoeuvre`,
    the KCS at full propeller speed), is tried; the best is reported. Below the collision distance no such turn
    keeps her safe: she must act before ``late``, which breaks 17(a)(ii) unless a give-way duty to another ship
    covers her manoeuvre (or slip under the scorer's tolerances from the onset, reading a measurement tolerance
    as leave).

    Parameters
    ----------
    k : int
        Problem number, 1 to 22.
    profile : str or ScoringProfile, optional
        Scoring profile (default ``published``, :func:`~mmg_casadi.colregs.profiles.scoring_profile`).
    rudder_deg : float
        Rudder angle of the turn (degrees, (0, 35]).
    step : float
        Spacing of the times of the turn tried (L/U, > 0).

    Returns
    -------
    list of dict
        One row per target: ``target``, ``role`` (the own ship's, at the onset, as the scorer judges it),
        ``t_late`` (L/U), ``range_late`` (L), ``passing`` (the widest closest approach, L), ``side`` and
        ``t_turn`` of that manoeuvre, and ``safe`` (``passing`` at least the collision distance).

    Examples
    --------
    Case 10 under the laboratory profile: the second target crosses from port at a fine angle, closing at 0.26 U;
    when her inaction is apparent (TCPA 4) she is 1.0 L away:

    >>> row = stand_on_bound(10, profile="iitm-lab")[1]
    >>> row["role"], round(row["range_late"], 2), row["safe"]
    ('stand-on', 1.04, False)
    """
    k = _check_case(k)
    prof = scoring_profile(profile)
    step = check_range("step", step, 0.0, None, low_open=True, unit="L/U")
    t_meet = MEET_DISTANCE
    turn = turning_circle(rudder_deg, t_end=10.0)
    t_tol = float(turn.t[np.argmax(np.abs(np.degrees(turn.state("psi"))) >= prof.course_tolerance_deg)])
    rows = []
    for i, (head, speed) in enumerate(_targets(k)):
        start, e = _track(head, speed)
        velocity = speed * e
        closing = float(np.hypot(*(velocity - np.array([1.0, 0.0]))))
        tcpa_late = min(max(prof.late_tcpa or 0.0, (prof.late_range or 0.0) / closing), t_meet)  # from the start
        t_late = t_meet - tcpa_late
        beta = bearing((0.0, 0.0), 0.0, start)
        alpha = bearing(start, math.radians(head), (0.0, 0.0))
        role = str(classify_roles(beta, alpha, 0.0, math.radians(head), 1.0, speed, prof))
        best = None
        for t_turn in np.arange(max(t_late - t_tol, 0.0), t_meet + step / 2, step):
            for port in (False, True):
                m = last_moment_manoeuvre(start, velocity, float(t_turn), port=port, rudder_deg=rudder_deg,
                                          t_end=t_meet + 20.0).metrics
                if best is None or m["min_distance"] > best["min_distance"]:
                    best = m
        rows.append({"target": f"target{i + 1}", "role": role, "t_late": t_late, "range_late": closing * tcpa_late,
                     "passing": best["min_distance"], "side": best["side"], "t_turn": best["t_turn"],
                     "safe": bool(best["min_distance"] >= PARAMETERS["collision_distance"].default)})
    return rows


def run_imazu(method: str, targets: str = "hold", *, cases=tuple(CASES), params: dict | None = None) -> list[dict]:
    """Simulate Imazu problems and assess the own ship.

    Returns one dict per case: ``case``, ``safe`` (own ship reached its goal and never came within the collision
    distance of any ship), ``reached_goal``, ``min_distance`` (L, own ship to its nearest target), ``collided``,
    ``encounters`` (the own ship's encounters with a risk of collision, :func:`own_encounters`) and ``result``
    (the :class:`~mmg_casadi.scenarios.run.ScenarioResult`).

    Parameters
    ----------
    method : str
        Guidance method of the own ship (one of :data:`mmg_casadi.guidance.methods.METHODS`).
    targets : str, optional
        ``"hold"`` (default): targets keep course and speed; ``"avoid"``: they use ``method`` too.
    cases : iterable of int, optional
        Problem numbers to run, each 1 to 22, in this order; default all 22.
    params : dict, optional
        Parameter overrides by name (:data:`mmg_casadi.params.PARAMETERS`), passed to
        :func:`~mmg_casadi.scenarios.run.run_scenario`.

    Returns
    -------
    list of dict
        One row per case, as described above.

    Examples
    --------
    >>> rows = run_imazu("modified-vortex", "hold", cases=(2,))
    >>> rows[0]["case"], rows[0]["safe"], rows[0]["min_distance"] > 2.0
    (2, True, True)
    >>> [(e["other"], e["role"]) for e in rows[0]["encounters"]]
    [('target1', 'give-way')]
    """
    out = []
    for k in cases:
        sc = scenario_from_dict(imazu_case(k, method=method, targets=targets), source=f"imazu{k}")
        res = run_scenario(sc, params)
        own = res.metrics["ships"][0]
        dmin = float(np.min(res.own_distance()))
        collided = own["collided"]  # the closed loop's judgement, as every runner's
        out.append({"case": int(k), "safe": bool(own["reached_goal"] and not collided),
                    "reached_goal": bool(own["reached_goal"]), "min_distance": dmin, "collided": bool(collided),
                    "encounters": own_encounters(res), "result": res})
    return out


def own_encounters(result) -> list[dict]:
    """The own ship's (first ship's) encounters with a risk of collision in a scenario result, as judged by the
    encounter scorer (:func:`mmg_casadi.colregs.scorer.score_encounters`; ``Encounter.to_dict()`` of the pairs in
    ``metrics.json``), in the order of the other ships.

    Parameters
    ----------
    result : ScenarioResult
        Result of :func:`~mmg_casadi.scenarios.run.run_scenario`.

    Returns
    -------
    list of dict
        The applicable, judged encounters (``compliant`` not None) as stored in ``metrics.json``.
    """
    own = result.metrics["ships"][0]["name"]
    out = []
    for pair in result.metrics["pairs"]:
        side = "a" if pair["a"] == own else "b" if pair["b"] == own else None
        if side is not None:
            out += judged_encounters(pair["encounters"][side])
    return out


def plot_imazu(rows: list[dict], path=None, *, title: str | None = None, ncols: int = 6) -> Figure:
    """Grid of small trajectory plots, one per case of :func:`run_imazu` (own ship blue), titled with the case,
    the own ship's minimum distance and whether it was safe.

    Parameters
    ----------
    rows : list of dict
        Rows of :func:`run_imazu` (each needs ``case``, ``safe``, ``collided``, ``min_distance`` and
        ``result``), one panel each, in order.
    path : str or os.PathLike, optional
        If given, the figure is also saved there (110 dpi; the format follows the suffix).
    title : str, optional
        Title above the grid.
    ncols : int, optional
        Panels per row (default 6); unused panels of the last row are blank.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (not attached to pyplot).

    Examples
    --------
    >>> fig = plot_imazu(run_imazu("modified-vortex", "hold", cases=(1, 2)), ncols=2)
    >>> [ax.get_title().split(":")[0] for ax in fig.axes]
    ['case 1', 'case 2']
    """
    n = len(rows)
    nrows = max(1, math.ceil(n / ncols))
    fig = Figure(figsize=(2.6 * ncols, 2.8 * nrows), layout="constrained")
    axes = fig.subplots(nrows, ncols, squeeze=False)
    for ax in axes.flat[n:]:
        ax.set_axis_off()
    for ax, row in zip(axes.flat, rows):
        res = row["result"]
        traj, sc = res.trajectory, res.scenario
        mask = traj.sailing_mask()
        for i in range(traj.layout.n_ships):
            m = mask[:, i]
            draw_path(ax, traj.state("x", i)[m], traj.state("y", i)[m], traj.state("psi", i)[m],
                      COLORS[i % len(COLORS)], n_outlines=3)
            g = sc.ships[i].goal
            draw_goal(ax, g[0], g[1], COLORS[i % len(COLORS)])
        marine_axes(ax)
        ax.set_xlabel("")
        ax.set_ylabel("")
        ax.tick_params(labelsize=6)
        verdict = "safe" if row["safe"] else ("collision" if row["collided"] else "goal not reached")
        ax.set_title(f"case {row['case']}: d_min {row['min_distance']:.1f} L, {verdict}", fontsize=7,
                     color="k" if row["safe"] else "r")
    fig.supxlabel("y (east) [L]", fontsize=8)  # one label per axis for the whole grid
    fig.supylabel("x (north) [L]", fontsize=8)
    if title:
        fig.suptitle(title, fontsize=10)
    if path:
        save_figure(fig, path, dpi=FIGURE_DPI)
    return fig
