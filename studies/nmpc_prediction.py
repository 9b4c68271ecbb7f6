"""The ``nmpc`` planner's predicted trajectory at a decision: a figure for the how-to (issue 42).

The packaged crossing (Rule 15) with the own ship on ``nmpc`` and the target holding course and speed: the run is
simulated, its solves re-posed (:func:`mmg_casadi.closed_loop.nmpc_solves.solves_of_run`), and at the first solve
that turns the rudder by more than ``--rudder`` degrees (the decision to give way) the figure shows the plan the
solver started from (the previous plan, shifted), the plan it returned (the prediction model's track,
:func:`mmg_casadi.guidance.nmpc_ocp.rollout`), the target's constant-velocity prediction over the same horizon,
and the tracks both ships then sailed.

Usage: ``python -m studies.nmpc_prediction --out docs/results/issue42/nmpc_prediction.png``
"""

from __future__ import annotations

import argparse
import dataclasses

import casadi as ca
import numpy as np

from mmg_casadi.closed_loop.problem import build_problem
from mmg_casadi.closed_loop.simulation import simulate
from mmg_casadi.guidance.nmpc import HORIZON, shape_of
from mmg_casadi.guidance.nmpc_ocp import SHIP_FIELDS, nlp_solver, param_layout, rollout
from mmg_casadi.closed_loop.nmpc_solves import solves_of_run
from mmg_casadi.scenarios.run import packaged_scenario
from mmg_casadi.scenarios.scenario import with_method


def crossing_scenario():
    """The packaged crossing with the own ship on ``nmpc`` and the target on ``none`` (holding).

    Returns
    -------
    Scenario
        The scenario.
    """
    sc = with_method(packaged_scenario("crossing"), "nmpc")
    return dataclasses.replace(sc, ships=(sc.ships[0], dataclasses.replace(sc.ships[1], method="none")))


def decision(scenario=None, rudder_deg: float = 5.0) -> dict:
    """The first solve that turns the rudder by more than ``rudder_deg`` and its predictions.

    Parameters
    ----------
    scenario : Scenario, optional
        Ship 0 on ``nmpc`` (default :func:`crossing_scenario`).
    rudder_deg : float, default 5
        Rudder command (deg) that marks the decision.

    Returns
    -------
    dict
        ``t`` (L/U), ``own`` (x, y of the own ship then), ``plan`` and ``start`` (the predicted tracks, (N+1, 2),
        absolute), ``targets`` (list of (N+1, 2)), ``tracks`` (per ship, the sailed (T, 2)), ``solve`` (the
        re-posed solve's record), ``h`` (the planning interval).
    """
    sc = scenario or crossing_scenario()
    problem = build_problem(sc)
    lay = problem.layout
    traj = simulate(lay, problem.x0, problem.p)
    solves = solves_of_run(sc, keep_inputs=True)
    pick = next(s for s in solves if abs(s["rudder_deg"]) > rudder_deg)
    w0, p, lbw, ubw = pick["inputs"]
    shape = shape_of(lay)
    w = np.array(nlp_solver(shape, int(lay.option("nmpc_max_iter")))(x0=w0, p=p, lbx=lbw, ubx=ubw)["x"]).ravel()
    roll = rollout(shape)
    k = int(np.argmin(np.abs(traj.t - pick["t"])))
    col = {n: lay.column(n) for n in ("x", "y")}
    own = np.array([traj.states[k][0, col["x"]], traj.states[k][0, col["y"]]])
    plan = np.array(roll(w, p))[0:2].T + own
    start = np.array(roll(w0, p))[0:2].T + own
    pl = param_layout(shape)
    h = float(p[pl["h"]][0])
    ships = np.asarray(p[pl["ships"]]).reshape(shape.ships, len(SHIP_FIELDS))  # column-major: one row per slot
    f = {n: i for i, n in enumerate(SHIP_FIELDS)}
    tgrid = h * np.arange(HORIZON + 1)[:, None]
    targets = [own + row[[f["px"], f["py"]]] + tgrid * row[[f["vx"], f["vy"]]]
               for row in ships if np.hypot(row[f["vx"]], row[f["vy"]]) > 0 or np.hypot(row[f["px"]], row[f["py"]]) > 0]
    tracks = [np.stack([[X[i, col["x"]], X[i, col["y"]]] for X in traj.states]) for i in range(lay.n_ships)]
    return {"t": float(pick["t"]), "own": own, "plan": plan, "start": start, "targets": targets,
            "tracks": tracks, "solve": {k_: v for k_, v in pick.items() if k_ != "inputs"}, "h": h,
            "rudder_plan_deg": np.degrees(w[:HORIZON])}


def plot(d: dict, ax=None):
    """Draw :func:`decision`'s result on ``ax`` (a new figure without).

    Parameters
    ----------
    d : dict
        :func:`decision`'s result.
    ax : matplotlib.axes.Axes, optional
        Where to draw.

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    import matplotlib.pyplot as plt
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 6))
    # the scene's y axis points to starboard of a ship heading along x (north-east-down): plot east right, north up
    for n, tr in enumerate(d["tracks"]):
        ax.plot(tr[:, 1], tr[:, 0], color="0.7", lw=1, label="sailed tracks" if n == 0 else None)
    ax.plot(d["start"][:, 1], d["start"][:, 0], "--", color="C0", lw=1, label="start of the solve (warm start)")
    ax.plot(d["plan"][:, 1], d["plan"][:, 0], "o-", color="C0", ms=3, label=f"predicted own track ({HORIZON} "
            f"× {d['h']:g} L/U)")
    for n, q in enumerate(d["targets"]):
        ax.plot(q[:, 1], q[:, 0], "s-", color="C3", ms=3, label="target, constant velocity" if n == 0 else None)
        ax.plot(q[0, 1], q[0, 0], "s", color="C3", ms=8)
    ax.plot(d["own"][1], d["own"][0], "o", color="C0", ms=8)
    s = d["solve"]
    ax.set_title(f"nmpc at t = {d['t']:.2f} L/U: rudder {s['rudder_deg']:.1f}°, propeller {s['nu']:.2f} of "
                 f"design\n{s['iterations']} SQP iterations, {s['status']}", fontsize=10)
    ax.set_xlabel("east (L)")
    ax.set_ylabel("north (L)")
    ax.set_aspect("equal")
    ax.legend(fontsize=8, loc="best")
    return ax


def main(argv=None) -> None:
    """The command line: write the figure to ``--out``.

    Parameters
    ----------
    argv : list of str, optional
        Arguments (default ``sys.argv[1:]``).
    """
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="PNG file")
    ap.add_argument("--rudder", type=float, default=5.0, help="rudder command (deg) that marks the decision")
    a = ap.parse_args(argv)
    import matplotlib
    matplotlib.use("Agg")
    d = decision(rudder_deg=a.rudder)
    ax = plot(d)
    ax.figure.savefig(a.out, dpi=150, bbox_inches="tight")
    print(f"t = {d['t']:.2f} L/U, rudder plan (deg): {np.round(d['rudder_plan_deg'], 1).tolist()}, "
          f"solve: {d['solve']}")


if __name__ == "__main__":
    main()
