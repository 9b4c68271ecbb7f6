"""COLREG rules 13-15 (paper, section "Dynamic Obstacle Avoidance"), from the shipped scenario files.

Head-on: (0,0)->(50,0) and (50,0)->(0,0), both at design speed. Crossing: (0,0)->(50,0) and (25,25)->(25,-25).
Overtaking: the paper gives no positions; the overtaken ship runs at half speed 12 L ahead on the same course
((12,0)->(70,0)) while the overtaking ship goes (0,0)->(100,0) at design speed.
"""

from __future__ import annotations

from ._common import ALL_METHODS, methods_for, packaged, params_for, run_cases


def cases() -> dict:
    return {"overtaking": packaged("overtaking"), "head-on": packaged("head_on"), "crossing": packaged("crossing")}


def run(args, out) -> dict:
    return run_cases(cases(), methods_for(args, ALL_METHODS), out, params_for(args), title="COLREGs")
