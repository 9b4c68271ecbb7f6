"""Head-on encounter in a 10 L wide channel along the diagonal (paper, section "Narrow Waterways"): ship 1
(0,0)->(50,50), ship 2 (50,50)->(0,0), both heading for their goals; walls are line sources (Λ = 10) acting
within 2 L, 5 L either side of the diagonal (``data/scenarios/narrow_channel.toml``).
"""

from __future__ import annotations

from ._common import methods_for, packaged, params_for, run_cases

HALF_WIDTH = 5.0  #: L, half the channel width of the shipped scenario


def cases() -> dict:
    return {"head-on": packaged("narrow_channel")}


def run(args, out) -> dict:
    return run_cases(cases(), methods_for(args, ("modified-vortex", "inverse-square", "velocity-obstacle")),
                     out, params_for(args), title="narrow channel")
