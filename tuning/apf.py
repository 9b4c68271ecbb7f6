"""Training and held-out scenarios of the APF tuning (modified sink-vortex field), with their seeds.

The paper's encounters and Monte Carlo scenarios, every ship with the modified sink-vortex. ``mmg-casadi tune
apf`` (:mod:`tuning.cli_apf`) trains on :func:`training_scenarios` drawn with :data:`TRAIN_SEED` and judges the
result on held-out runs drawn with :data:`HOLDOUT_SEED`; its objective is :mod:`tuning.safety`, its search
:mod:`tuning.search` and its judgement :mod:`tuning.judge`. The superseded IPOPT tuner that used the same
scenarios is :mod:`tuning.apf_ipopt`.
"""

from __future__ import annotations

from mmg_casadi.errors import InputError
from mmg_casadi.montecarlo.sampling import sample_scenario
from mmg_casadi.scenarios import encounters
from mmg_casadi.scenarios.scenario import scenario_from_dict, with_method

METHOD = "modified-vortex"
TRAIN_SEED = 1000
"""Base seed of the sampled training scenarios (environments 1-2)."""
HOLDOUT_SEED = 2000
"""Base seed of the held-out scenarios (environments 1-5); disjoint from the training seeds."""


def paper_encounters() -> dict:
    """The paper's encounters used for training (:func:`mmg_casadi.scenarios.encounters.paper_encounters`), all with the
    modified sink-vortex.

    Returns
    -------
    dict of Scenario
        Name to scenario: ``static-obstacle``, ``overtaking``, ``head-on``, ``crossing``, ``conflict``.
    """
    return {k: with_method(v, METHOD) for k, v in encounters.paper_encounters().items()}


def sampled_scenario(env: int, run: int, base_seed: int):
    """Monte Carlo scenario ``run`` of environment ``env`` (modified sink-vortex for every ship).

    Parameters
    ----------
    env : int
        Monte Carlo environment (1-5, :func:`mmg_casadi.montecarlo.sampling.sample_scenario`).
    run : int
        Run index within the environment.
    base_seed : int
        Base seed of the draw (e.g. :data:`TRAIN_SEED` or :data:`HOLDOUT_SEED`).

    Returns
    -------
    Scenario
        The validated scenario, its source ``env<env>-run<run>-seed<base_seed>``.
    """
    return scenario_from_dict(sample_scenario(env, run, base_seed).to_scenario_dict(METHOD),
                              source=f"env{env}-run{run}-seed{base_seed}")


def training_scenarios(n_sampled: int, *, paper: bool = True, envs=(1, 2), base_seed: int = TRAIN_SEED) -> dict:
    """Training set: the paper's encounters (``paper``) plus ``n_sampled`` Monte Carlo scenarios drawn
    alternately from ``envs`` with ``base_seed``.

    Parameters
    ----------
    n_sampled : int
        Number of sampled Monte Carlo scenarios, >= 0.
    paper : bool
        Whether to include the paper's encounters.
    envs : sequence of int
        Environments the sampled scenarios are drawn from, in turn.
    base_seed : int
        Base seed of the sampled scenarios.

    Returns
    -------
    dict of Scenario
        Name to scenario: the paper's encounters first (if ``paper``), then ``env<e>-run<r>`` for the sampled ones.
    """
    if isinstance(n_sampled, bool) or not isinstance(n_sampled, int) or n_sampled < 0:
        raise InputError("train", "an integer >= 0", n_sampled)
    out = dict(paper_encounters()) if paper else {}
    for k in range(n_sampled):
        env = envs[k % len(envs)]
        run = k // len(envs)
        out[f"env{env}-run{run}"] = sampled_scenario(env, run, base_seed)
    return out
