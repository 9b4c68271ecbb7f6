"""Static obstacle (paper, section "Reactive Guidance"): own ship from the origin heading north, obstacle of
radius L/2 at (25, 0) L, goal at (50, 0) L (``data/scenarios/static_obstacle.toml``) or (60, 0) L; the paper's
three fields and the velocity obstacle. A third case puts the obstacle just off the starboard bow, (25, 1.5) L,
the paper's sink-vortex failure mode (its coordinates are not given).
"""

from __future__ import annotations

from mmg_casadi.scenarios.encounters import static_obstacle_cases

from ._common import ALL_METHODS, run_cases


def run(out, *, methods=None, params=None) -> dict:
    """Run the three static-obstacle cases for ``methods`` (default: every avoiding method) with ``params``.

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
    return run_cases(static_obstacle_cases(), methods or ALL_METHODS, out, params, title="static obstacle")
