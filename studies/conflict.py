"""Conflicting responsibility (paper): ship 1 (0,0)->(60,0) at half speed, ship 2 (-20,0)->(100,0) and ship 3
(60,0)->(0,0) at twice ship 1's speed (design speed). Without avoidance all three meet near (20, 0).
"""

from __future__ import annotations

from mmg_casadi.scenarios.encounters import conflict_cases

from ._common import APF_AND_VO, run_cases


def run(out, *, methods=None, params=None) -> dict:
    """Run the three-ship conflict for ``methods`` (default: the paper's APFs and the VO) with ``params``.

    Parameters
    ----------
    out : str or Path
        Output directory: ``<case>/<method>/`` per run, ``<case>.png`` per case, ``metrics.json``.
    methods : iterable of str, optional
        Methods to compare (names in :data:`mmg_casadi.guidance.methods.METHODS`); default: the paper's APFs and the VO.
    params : dict, optional
        Parameter overrides by name (:data:`mmg_casadi.params.PARAMETERS`) for every run.

    Returns
    -------
    dict
        The resolved parameters and, per case and method, the metrics of :func:`mmg_casadi.scenarios.run.run_scenario`.
    """
    return run_cases(conflict_cases(), methods or APF_AND_VO, out, params, title="conflict")
