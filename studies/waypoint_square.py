"""Waypoint tracking on a square (paper, section "Waypoint Tracking"): ILOS + PD, CE and MCTE.

The paper does not give the square's size; we use a 25 L square starting at the origin, heading north, with
four waypoints (the last one back at the start; :func:`mmg_casadi.scenarios.encounters.waypoint_square`).
Paper: CE = 0.1203, MCTE = 0.2655 L.
"""

from __future__ import annotations

import sys
from pathlib import Path

from mmg_casadi.scenarios.encounters import SQUARE_SIDE, waypoint_square
from mmg_casadi.io import write_json
from mmg_casadi.scenarios.run import run_scenario, write_outputs

PAPER = {"ce": 0.1203, "mcte": 0.2655}


def run(out, *, params=None) -> dict:
    """Track the square with ``params`` (e.g. ``ilos_delta``, ``ilos_k``, ``kp``, ``kd``); write the figure and
    ``metrics.json`` into ``out``.

    Parameters
    ----------
    out : str or Path
        Output directory: ``waypoint_square.png``, the trajectory files and ``metrics.json``.
    params : dict, optional
        Parameter overrides by name (:data:`mmg_casadi.params.PARAMETERS`).

    Returns
    -------
    dict
        CE, MCTE, time to goal, the paper's values, the ILOS gains, the parameters and the run's metrics.
    """
    res = run_scenario(waypoint_square(), params=params)
    out = Path(out)
    write_outputs(res, out, figure_name="waypoint_square.png", tracking=True)
    own = res.metrics["ships"][0]
    p = res.params
    m = {"ce": own["ce"], "mcte": own["mcte"], "time_to_goal": own["time_to_goal"],
         "reached_goal": own["reached_goal"], "paper": PAPER, "side_L": SQUARE_SIDE,
         "gains": {"kp_g": 1.0 / p["ilos_delta"], "ki_g": p["ilos_k"] / p["ilos_delta"]},
         "params": p, "scenario": res.metrics}
    write_json(out / "metrics.json", m)
    print(f"  waypoint square: CE {m['ce']:.4f} (paper 0.1203), MCTE {m['mcte']:.4f} L (paper 0.2655), "
          f"time to goal {m['time_to_goal']}", file=sys.stderr)
    return m
