"""Conflicting responsibility (paper): ship 1 (0,0)->(60,0) at half speed, ship 2 (-20,0)->(100,0) and ship 3
(60,0)->(0,0) at twice ship 1's speed (design speed). Without avoidance all three meet near (20, 0).
"""

from __future__ import annotations

from mmg_casadi.encounters import conflict_cases

from ._common import APF_AND_VO, run_cases


def run(out, *, methods=None, params=None) -> dict:
    """Run the three-ship conflict for ``methods`` (default: the paper's APFs and the VO) with ``params``."""
    return run_cases(conflict_cases(), methods or APF_AND_VO, out, params, title="conflict")
