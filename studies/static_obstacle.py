"""Static obstacle (paper, section "Reactive Guidance"): own ship from the origin heading north, obstacle of
radius L/2 at (25, 0) L, goal at (50, 0) or (60, 0) L; the paper's three fields and the velocity obstacle.
A third case puts the obstacle just off the starboard bow, (25, 1.5) L, the paper's sink-vortex failure mode.
"""

from __future__ import annotations

from ._common import ALL_METHODS, methods_for, params_for, run_cases, scenario, ship


def cases() -> dict:
    obs = [{"position": [25.0, 0.0], "radius": 0.5}]
    return {
        "goal-50": scenario([ship("own", (0, 0), 0.0, 1.0, [(50, 0)])], obs),
        "goal-60": scenario([ship("own", (0, 0), 0.0, 1.0, [(60, 0)])], obs),
        "starboard-bow": scenario([ship("own", (0, 0), 0.0, 1.0, [(50, 0)])],
                                  [{"position": [25.0, 1.5], "radius": 0.5}]),
    }


def run(args, out) -> dict:
    return run_cases(cases(), methods_for(args, ALL_METHODS), out, params_for(args), title="static obstacle")
