"""Land: the shipped scenarios with coastlines (a strait with a crossing, a fjord entrance with an island, the
paper's narrow channel with its banks as land) and the land library of issue 43 (an island on the track, an
island off the track, a headland to round, a strait with traffic, a channel bend), every method, figures with the
land filled.

``mmg-casadi study land [--methods a,b] [PARAMS] --out DIR`` writes ``<case>/<method>/`` per run,
``<case>.png`` per case and ``metrics.json``; a ship touching land grounds (``collision_kind`` ``"land"``).
"""

from __future__ import annotations

from mmg_casadi.scenarios.run import packaged_scenario

from ._common import ALL_METHODS, run_cases

CASES = ("strait_crossing", "fjord_island", "narrow_channel_land", "land_island_on_track", "land_island_off_track",
         "land_headland", "land_strait_traffic", "land_channel_bend")
"""Shipped scenarios of the land study (``mmg_casadi/data/scenarios/<name>.toml``)."""


def run(out, *, methods=None, params=None) -> dict:
    """Run the land scenarios for ``methods`` (default: every avoiding method) with ``params``.

    Parameters
    ----------
    out : str or Path
        Output directory.
    methods : iterable of str, optional
        Methods to compare (names in :data:`mmg_casadi.guidance.methods.METHODS`).
    params : dict, optional
        Parameter overrides by name for every run.

    Returns
    -------
    dict
        The resolved parameters and, per case and method, the metrics of :func:`mmg_casadi.scenarios.run.run_scenario`.
    """
    return run_cases({name: packaged_scenario(name) for name in CASES}, methods or ALL_METHODS, out, params,
                     title="Land")
