"""Head-on encounter in a 10 L wide channel along the diagonal (paper, section "Narrow Waterways"): ship 1
(0,0)->(50,50), ship 2 (50,50)->(0,0), both heading for their goals; walls are line sources (Λ = 10) acting
within 2 L, 5 L either side of the diagonal and extended 10 L beyond both ends.
"""

from __future__ import annotations

import math

from ._common import methods_for, params_for, run_cases, scenario, ship

HALF_WIDTH = 5.0
EXTEND = 10.0


def walls():
    n = (-1 / math.sqrt(2), 1 / math.sqrt(2))  # normal to the diagonal
    e = (1 / math.sqrt(2), 1 / math.sqrt(2))
    out = []
    for side in (-1, 1):
        a = [-EXTEND * e[0] + side * HALF_WIDTH * n[0], -EXTEND * e[1] + side * HALF_WIDTH * n[1]]
        b = [50 + EXTEND * e[0] + side * HALF_WIDTH * n[0], 50 + EXTEND * e[1] + side * HALF_WIDTH * n[1]]
        out.append({"points": [a, b]})
    return out


def cases() -> dict:
    return {"head-on": scenario([ship("ship1", (0, 0), 45.0, 1.0, [(50, 50)]),
                                 ship("ship2", (50, 50), -135.0, 1.0, [(0, 0)])], walls=walls())}


def run(args, out) -> dict:
    return run_cases(cases(), methods_for(args, ("modified-vortex", "inverse-square", "velocity-obstacle")),
                     out, params_for(args), title="narrow channel")
