"""Waypoint tracking on a square (paper, section "Waypoint Tracking"): ILOS + PD, CE and MCTE.

The paper does not give the square's size; we use a 25 L square starting at the origin, heading north, with
four waypoints (the last one back at the start). Paper: CE = 0.1203, MCTE = 0.2655 L.
"""

from __future__ import annotations

import sys
from pathlib import Path

from mmg_casadi.cli import write_json
from mmg_casadi.control import PdHeadingParams
from mmg_casadi.guidance import IlosParams
from mmg_casadi.scenario_run import run_scenario, write_outputs

from ._common import scenario, ship

SIDE = 25.0
PAPER = {"ce": 0.1203, "mcte": 0.2655}


def square_scenario(side: float = SIDE, **settings):
    wps = [(side, 0.0), (side, side), (0.0, side), (0.0, 0.0)]
    return scenario([ship("own", (0.0, 0.0), 0.0, 1.0, wps)], method="none", t_max=600.0, **settings)


def run(args, out) -> dict:
    ilos = IlosParams(delta=args.ilos_delta if getattr(args, "ilos_delta", None) is not None else 2.0,
                      k=args.ilos_k if getattr(args, "ilos_k", None) is not None else 0.05)
    pd = PdHeadingParams(kp=args.kp if getattr(args, "kp", None) is not None else 3.5,
                         kd=args.kd if getattr(args, "kd", None) is not None else 4.0)
    params = {"ilos_delta": ilos.delta, "ilos_k": ilos.k, "kp": pd.kp, "kd": pd.kd}
    res = run_scenario(square_scenario(), params=params)
    out = Path(out)
    write_outputs(res, out, figure_name="waypoint_square.png", tracking=True)
    own = res.metrics["ships"][0]
    m = {"ce": own["ce"], "mcte": own["mcte"], "time_to_goal": own["time_to_goal"],
         "reached_goal": own["reached_goal"], "paper": PAPER, "side_L": SIDE,
         "parameters": {"ilos_delta": ilos.delta, "ilos_k": ilos.k, "kp_g": ilos.kp_g, "ki_g": ilos.ki_g,
                        "kp": pd.kp, "kd": pd.kd, "r_tol": 3.0},
         "scenario": res.metrics}
    write_json(out / "metrics.json", m)
    print(f"  waypoint square: CE {m['ce']:.4f} (paper 0.1203), MCTE {m['mcte']:.4f} L (paper 0.2655), "
          f"time to goal {m['time_to_goal']}", file=sys.stderr)
    return m
