"""Conflicting responsibility (paper): ship 1 (0,0)->(60,0) at half speed, ship 2 (-20,0)->(100,0) and ship 3
(60,0)->(0,0) at twice ship 1's speed (design speed). Without avoidance all three meet near (20, 0).
"""

from __future__ import annotations

from ._common import APF_AND_VO, methods_for, packaged, params_for, run_cases


def cases() -> dict:
    return {"three-ships": packaged("conflict")}


def run(args, out) -> dict:
    return run_cases(cases(), methods_for(args, APF_AND_VO), out, params_for(args), title="conflict")
