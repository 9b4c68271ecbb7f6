"""COLREG rules 13-15 (paper, section "Dynamic Obstacle Avoidance"), from the shipped scenario files.

Head-on: (0,0)->(50,0) and (50,0)->(0,0), both at design speed. Crossing: (0,0)->(50,0) and (25,25)->(25,-25).
Overtaking: the paper gives no positions; the overtaken ship runs at half speed 12 L ahead on the same course
((12,0)->(70,0)) while the overtaking ship goes (0,0)->(100,0) at design speed.
"""

from __future__ import annotations

from mmg_casadi.scenarios.encounters import colregs_cases

from ._common import ALL_METHODS, run_cases


def run(out, *, methods=None, params=None) -> dict:
    """Run the three encounters for ``methods`` (default: every avoiding method) with ``params``.

    Parameters
    ----------
    out : str or Path
        Output directory: ``<case>/<method>/`` per run, ``<case>.png`` per case, ``metrics.json``.
    methods : iterable of str, optional
        Methods to compare (names in :data:`mmg_casadi.guidance.methods.METHODS`); default: every avoiding method.
    params : dict, optional
        Parameter overrides by name (:data:`mmg_casadi.params.PARAMETERS`) for every run.

    Returns
    -------
    dict
        The resolved parameters and, per case and method, the metrics of :func:`mmg_casadi.scenarios.run.run_scenario`.
    """
    return run_cases(colregs_cases(), methods or ALL_METHODS, out, params, title="COLREGs")
