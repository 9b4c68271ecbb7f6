"""Where an environment's scenarios come from: a file, a generator or an environment of the Monte Carlo sampler.

A source is a callable ``seed -> Scenario`` (the seed an episode's reset draws from its random generator), so the
same seed gives the same scenario. :func:`as_source` accepts a :class:`~mmg_casadi.scenarios.scenario.Scenario`, a
scenario file or the name of a packaged scenario (always that scenario) or a callable.
"""

from __future__ import annotations

from pathlib import Path

from mmg_casadi.errors import InputError
from mmg_casadi.guidance import methods as registry
from mmg_casadi.montecarlo.execution import sampled_scenario
from mmg_casadi.montecarlo.sampling import sample_traffic
from mmg_casadi.scenarios.generate import generate, load_description, override, standard_description
from mmg_casadi.scenarios.run import packaged_names, packaged_scenario
from mmg_casadi.scenarios.scenario import Scenario, load_scenario, scenario_from_dict, with_method

SEED_RANGE = 2 ** 31 - 1
"""Seeds a reset draws for the source are in ``[0, SEED_RANGE)``."""


def as_source(scenario, method: str | None = None):
    """A source (``seed -> Scenario``) from a scenario, a file, a packaged scenario's name or a callable.

    Parameters
    ----------
    scenario : Scenario, str, Path or callable
        A scenario (used for every episode), the path of a scenario file, the name of a packaged scenario
        (``mmg-casadi scenarios``), or a callable ``seed -> Scenario``.
    method : str, optional
        The method of every ship but the own ship (replaces the scenario's ``settings.method``; ships that name
        their own keep it). The own ship is commanded whatever her method.

    Returns
    -------
    callable
        ``seed -> Scenario``.

    Examples
    --------
    >>> src = as_source("head_on", method="colregs-vortex")
    >>> src(0).settings.method, len(src(7).ships)
    ('colregs-vortex', 2)
    """
    if method is not None:
        registry.get(method, "method")
    if callable(scenario) and not isinstance(scenario, Scenario):
        base = scenario
    else:
        sc = _load(scenario)
        base = lambda seed: sc  # noqa: E731 - the same scenario for every seed
    if method is None:
        return base
    return lambda seed: with_method(base(seed), method)


def _load(scenario) -> Scenario:
    if isinstance(scenario, Scenario):
        return scenario
    if isinstance(scenario, (str, Path)):
        path = Path(scenario)
        if not path.exists() and path.suffix in ("", ".toml") and path.stem in packaged_names():
            return packaged_scenario(path.stem)
        return load_scenario(path)
    raise InputError("scenario", "a Scenario, a scenario file, a packaged scenario's name or a callable "
                     "seed -> Scenario", type(scenario).__name__)


def environment(number: int = 5, method: str = registry.DEFAULT, *, base_seed: int = 0):
    """Episodes from environment ``number`` of the Monte Carlo sampler: run ``seed`` of the statistical study.

    Parameters
    ----------
    number : int, default 5
        Environment 1-6 (:data:`mmg_casadi.montecarlo.sampling.ALL_ENVIRONMENTS`).
    method : str
        The target ships' method.
    base_seed : int, default 0
        Base seed of the sampler (the study's ``--seed``).

    Returns
    -------
    callable
        ``seed -> Scenario``: the scenario of run ``seed`` (so a reset with seed ``r`` meets the study's run
        ``r``; its targets use ``method``).

    Examples
    --------
    >>> src = environment(5, "modified-vortex")
    >>> sc = src(3)
    >>> len(sc.ships), len(sc.obstacles), sc.settings.method
    (10, 4, 'modified-vortex')
    """
    registry.get(method, "method")
    return lambda seed: sampled_scenario(number, method, int(seed), base_seed)


def traffic(ships: int, method: str = registry.DEFAULT, *, t_max: float | None = None):
    """Episodes of ``ships`` ships on random crossing routes at environment 5's density (``mmg-casadi traffic``).

    Parameters
    ----------
    ships : int
        Ships, the own ship first (fewer than the table's ``fleet_from_ships``: the commanded step is unrolled).
    method : str
        The target ships' method.
    t_max : float, optional
        Horizon (L/U; default the table's).

    Returns
    -------
    callable
        ``seed -> Scenario`` (:func:`~mmg_casadi.montecarlo.sampling.sample_traffic` with that seed).
    """
    registry.get(method, "method")
    kw = {} if t_max is None else {"t_max": float(t_max)}
    return lambda seed: scenario_from_dict(sample_traffic(ships, int(seed)).to_scenario_dict(method=method, **kw),
                                           source=f"traffic{ships}/seed{int(seed)}")


def encounters(description=None, method: str = "none"):
    """Episodes from a standard encounter set (``mmg-casadi generate``): one situation drawn per seed.

    Parameters
    ----------
    description : str, Path or None
        A description file (:func:`~mmg_casadi.scenarios.generate.load_description`); default the shipped standard
        set (one to three targets in requested COLREG encounters).
    method : str, default 'none'
        The targets' method (``"none"``: they hold course and speed, as in ``study encounters``).

    Returns
    -------
    callable
        ``seed -> Scenario``: a situation of the group ``seed`` modulo the number of groups, drawn with that seed.
        Groups differ in their number of targets, hence in their compiled step (a vectorised environment needs
        one shape).
    """
    d = standard_description() if description is None else load_description(description)
    registry.get(method, "method")

    def draw(seed: int) -> Scenario:
        k = int(seed) % len(d.groups)  # the seed picks the group, then draws its situation
        sit = generate(override(d, situations=k + 1, seed=int(seed))).situations[k]
        return with_method(sit.scenario, method)
    return draw
