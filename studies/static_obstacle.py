"""Static obstacle (paper, section "Reactive Guidance"): own ship from the origin heading north, obstacle of
radius L/2 at (25, 0) L, goal at (50, 0) L (``data/scenarios/static_obstacle.toml``) or (60, 0) L; the paper's
three fields and the velocity obstacle. A third case puts the obstacle just off the starboard bow, (25, 1.5) L,
the paper's sink-vortex failure mode (its coordinates are not given).
"""

from __future__ import annotations

import dataclasses

from ._common import ALL_METHODS, methods_for, packaged, params_for, run_cases


def cases() -> dict:
    base = packaged("static_obstacle")
    own = base.ships[0]
    return {
        "goal-50": base,
        "goal-60": dataclasses.replace(base, ships=(dataclasses.replace(own, waypoints=((60.0, 0.0),)),)),
        "starboard-bow": dataclasses.replace(base, obstacles=(dataclasses.replace(base.obstacles[0],
                                                                                   position=(25.0, 1.5)),)),
    }


def run(args, out) -> dict:
    return run_cases(cases(), methods_for(args, ALL_METHODS), out, params_for(args), title="static obstacle")
