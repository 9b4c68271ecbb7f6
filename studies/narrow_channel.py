"""Head-on encounter in a 10 L wide channel along the diagonal (paper, section "Narrow Waterways"): ship 1
(0,0)->(50,50), ship 2 (50,50)->(0,0), both heading for their goals; walls are line sources (Λ = 10) acting
within 2 L, 5 L either side of the diagonal (``data/scenarios/narrow_channel.toml``).
"""

from __future__ import annotations

from mmg_casadi.scenarios.encounters import narrow_channel_cases

from ._common import APF_AND_VO, run_cases

HALF_WIDTH = 5.0  #: L, half the channel width of the shipped scenario


def run(out, *, methods=None, params=None) -> dict:
    """Run the channel case for ``methods`` (default: the paper's APFs and the VO) with ``params``.

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
    return run_cases(narrow_channel_cases(), methods or APF_AND_VO, out, params, title="narrow channel")
