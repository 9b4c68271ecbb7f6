"""Explain one run of a statistical study: re-run it exactly and show every encounter of its own ship, rule by rule.

A study's ``study.json`` (its resolved parameters and disturbance ranges) and ``runs.csv`` (the seed of each run)
fix a run completely: :func:`explain_run` samples the same scenario
(:func:`~mmg_casadi.montecarlo.execution.sampled_scenario`), rolls it out through the same batch rollout as the study
(:func:`~mmg_casadi.montecarlo.execution.run_batch`, a batch of one run) and recomputes its row. The COLREG verdicts of every profile are compared
with the stored row, cell by cell (:attr:`RunExplanation.reproduced`), and the own ship's encounters are scored again
with their full detail (:class:`~mmg_casadi.colregs.scorer.Encounter`) for the figures of :func:`plot_encounter`:
both tracks with time marks, the onset of risk, the closest point of approach, the role, each rule's verdict and
score, and where each broken rule broke.

``mmg-casadi explain STUDY_DIR --run N [--env E --method M --profile P] --out DIR`` writes ``explain.json``,
``scenario.toml`` (the run's scenario, which ``mmg-casadi simulate`` replays) and one ``encounter<k>_<other>.png``
per encounter of the own ship.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mmg_casadi.closed_loop.simulation import sailing_mask
from mmg_casadi.colregs.profiles import scoring_profile
from mmg_casadi.colregs.scorer import Encounter, score_encounters
from mmg_casadi.colregs.verdict import RULES
from mmg_casadi.errors import InputError
from mmg_casadi.montecarlo.disturbance_sampling import DisturbanceRanges
from mmg_casadi.montecarlo.execution import (DEFAULT_CHUNK, PROFILE_COLUMNS, _non_default, profile_columns,
                                             run_batch)
from mmg_casadi.montecarlo.results import ResultsTable
from mmg_casadi.montecarlo.sampling import ALL_ENVIRONMENTS
from mmg_casadi.params import resolve

VERDICT_COLUMNS: tuple[str, ...] = ("colregs_verdicts", *PROFILE_COLUMNS.values())
"""The cells of a run's row that :attr:`RunExplanation.reproduced` compares (those the study filled:
:func:`~mmg_casadi.montecarlo.execution.profile_columns`)."""


@dataclass
class RunExplanation:
    """One re-run of a study's run and its own ship's encounters.

    Parameters
    ----------
    environment, method, run, seed : int, str, int, int
        Which run.
    scenario : Scenario
        The sampled scenario (with the study's parameters and the run's disturbance).
    params : dict
        The study's resolved parameters.
    t : numpy.ndarray (K,)
        Times of the history the scorer reads (L/U).
    states : numpy.ndarray (K, N, 4)
        ``x``, ``y``, ``psi``, ``status`` of every ship at those times.
    row : dict
        The run's recomputed row of ``runs.csv``.
    stored : dict or None
        The row ``runs.csv`` holds for the run (None if the study has not run it).
    encounters : list of Encounter
        The own ship's encounters with a risk of collision under ``profile`` (judged or unfinished).
    profile : ScoringProfile
        The profile of ``encounters`` and the figures.
    """

    environment: int
    method: str
    run: int
    seed: int
    scenario: object
    params: dict
    t: np.ndarray
    states: np.ndarray
    row: dict
    stored: dict | None
    encounters: list = field(default_factory=list)
    profile: object = None

    @property
    def reproduced(self) -> dict:
        """``{column: bool}``: whether each verdict cell (:data:`VERDICT_COLUMNS`) equals the stored one
        character for character (empty when the study has no row for the run)."""
        if self.stored is None:
            return {}
        columns = ("colregs_verdicts", *profile_columns(self.params).values())
        return {c: (self.row.get(c) or "") == (self.stored.get(c) or "") for c in columns}

    def to_dict(self) -> dict:
        """JSON-ready summary: the run, whether it reproduces, its row and every encounter (``Encounter.to_dict``).

        Returns
        -------
        dict
            Keys ``environment``, ``method``, ``run``, ``seed``, ``profile``, ``reproduced``, ``row``, ``stored``
            and ``encounters``.
        """
        return {"environment": self.environment, "method": self.method, "run": self.run, "seed": self.seed,
                "profile": self.profile.name, "reproduced": self.reproduced, "row": self.row, "stored": self.stored,
                "encounters": [e.to_dict() for e in self.encounters]}

    def plot(self, k: int = 0, ax=None):
        """The figure of encounter ``k`` (:func:`plot_encounter`).

        Parameters
        ----------
        k : int, default 0
            Index into :attr:`encounters`.
        ax : matplotlib Axes, optional
            Axes to draw in.

        Returns
        -------
        matplotlib.figure.Figure
            The figure.
        """
        return plot_encounter(self, k, ax=ax)


def _study_record(study_dir: Path) -> tuple[dict, DisturbanceRanges, dict]:
    """The study's resolved parameters, disturbance ranges and configuration (``metrics.json``'s, once written)."""
    try:
        record = json.loads((study_dir / "study.json").read_text(encoding="utf-8"))
        params = resolve(record["params"], cls=InputError, prefix="study.json params.")
        ranges = DisturbanceRanges(**{k: None if v is None else tuple(v)
                                      for k, v in (record.get("disturbance") or {}).items()})
    except (OSError, ValueError, KeyError, TypeError) as err:
        raise InputError("STUDY_DIR", "a directory written by `mmg-casadi study statistics` (with its study.json)",
                         f"{study_dir} ({err})") from None
    config = {}
    if (study_dir / "metrics.json").exists():
        try:
            config = json.loads((study_dir / "metrics.json").read_text(encoding="utf-8"))["config"]
        except (OSError, ValueError, KeyError, TypeError):
            config = {}
    return params, ranges, config


def explain_run(study_dir, run: int, *, environment: int | None = None, method: str | None = None,
                profile=None) -> RunExplanation:
    """Re-run run ``run`` of the study in ``study_dir`` exactly and score its own ship's encounters.

    Parameters
    ----------
    study_dir : str or Path
        Output directory of ``mmg-casadi study statistics``.
    run : int
        The run index.
    environment, method : int, str, optional
        The cell; needed only when the study's ``runs.csv`` holds that run in more than one cell.
    profile : str or ScoringProfile, optional
        Profile of the encounters and figures (default: the study's ``colregs_profile``).

    Returns
    -------
    RunExplanation
        The re-run, its recomputed and stored rows and its encounters.
    """
    study_dir = Path(study_dir)
    params, ranges, config = _study_record(study_dir)
    chunk = int(config.get("chunk") or DEFAULT_CHUNK)
    if isinstance(run, bool) or not isinstance(run, (int, np.integer)) or run < 0:
        raise InputError("--run", "a run index >= 0", run)
    rows = ResultsTable(study_dir / "runs.csv").read() if (study_dir / "runs.csv").exists() else []
    cells = sorted({(r["environment"], r["method"]) for r in rows if r["run"] == run
                    and environment in (None, r["environment"]) and method in (None, r["method"])})
    if len(cells) > 1:
        raise InputError("--env/--method", "one cell of the study: " + ", ".join(f"{e}/{m}" for e, m in cells),
                         f"{environment}/{method}")
    if cells:
        environment, method = cells[0]
    elif environment is None or method is None:
        raise InputError("--run", f"a run stored in {study_dir / 'runs.csv'} (or name --env and --method)", run)
    if environment not in ALL_ENVIRONMENTS:
        raise InputError("--env", f"one of {', '.join(map(str, ALL_ENVIRONMENTS))}", environment)
    stored = next((r for r in rows if (r["environment"], r["method"], r["run"]) == (environment, method, run)), None)
    seed = int(stored["seed"]) if stored is not None else int(config.get("base_seed") or 0)
    histories: dict = {}
    (row,) = run_batch(environment, method, [run], seed, params=_non_default(params), chunk=chunk,
                       disturbance=ranges, histories=histories)
    scenario, t, states = histories[0]
    prof = scoring_profile(params["colregs_profile"] if profile is None else profile)
    mask = sailing_mask(states[:, :, 3])
    encounters = [] if len(t) < 2 else [
        e for e in score_encounters(t, states[:, :, :2], states[:, :, 2], active=mask, profile=prof, own=0,
                                    names=[s.name for s in scenario.ships]) if e.applicable]
    return RunExplanation(environment, method, run, seed, scenario, params, np.asarray(t), np.asarray(states), row,
                          stored, encounters, prof)


def plot_encounter(explanation: RunExplanation, k: int = 0, *, ax=None, every: float = 5.0):
    """One encounter of the own ship: both tracks (marine view) with time marks, the onset of risk, the closest
    point of approach and where each broken rule broke, with the role and each rule's verdict and score.

    Parameters
    ----------
    explanation : RunExplanation
        The re-run.
    k : int, default 0
        Index into ``explanation.encounters``.
    ax : matplotlib Axes, optional
        Axes to draw in (default: a new figure).
    every : float, default 5.0
        Spacing of the time marks (L/U).

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    from matplotlib.figure import Figure

    from mmg_casadi.plotting import COLORS, marine_axes

    if not 0 <= k < len(explanation.encounters):
        raise InputError("encounter", f"an index in [0, {len(explanation.encounters)})", k)
    e: Encounter = explanation.encounters[k]
    if ax is None:
        fig = Figure(figsize=(7.0, 6.0), layout="constrained")
        ax = fig.add_subplot()
    else:
        fig = ax.figure
    t, st = explanation.t, explanation.states
    mask = sailing_mask(st[:, :, 3])
    t0 = e.onset["t"] - 10.0
    t1 = (e.release["t"] if e.release else t[-1]) + 5.0
    span = (t >= t0) & (t <= t1)
    for i, colour, name in ((e.own, COLORS[0], e.own_name), (e.other, COLORS[1], e.other_name)):
        sel = span & mask[:, i]
        ax.plot(st[sel, i, 1], st[sel, i, 0], "-", color=colour, lw=1.6, label=name)
        for tm in np.arange(math.ceil(t0 / every) * every, t1, every):
            j = int(np.argmin(np.abs(t - tm)))
            if sel[j]:
                ax.plot(st[j, i, 1], st[j, i, 0], "o", ms=3, color=colour)
                ax.annotate(f"{tm:g}", (st[j, i, 1], st[j, i, 0]), fontsize=6, color=colour,
                            xytext=(3, 3), textcoords="offset points")
    for moment, marker, label in ((e.onset["t"], "s", "onset of risk"), (e.closest["t"], "D", "closest approach")):
        j = int(np.argmin(np.abs(t - moment)))
        for i, colour in ((e.own, COLORS[0]), (e.other, COLORS[1])):
            ax.plot(st[j, i, 1], st[j, i, 0], marker, ms=7, mfc="none", mec=colour)
        ax.plot(st[j, [e.own, e.other], 1], st[j, [e.own, e.other], 0], ":", color="0.4", lw=1,
                label=f"{label}, t = {moment:.1f}")
    lines = [f"{e.role} ({e.encounter}), CPA {e.closest['range']:.2f} L at t = {e.closest['t']:.1f}",
             "unfinished: not judged" if e.unfinished else f"compliant: {e.compliant}, score {e.score:.2f}"]
    for rule in RULES:
        if rule in e.rules:
            r = e.rules[rule]
            broke = r.terms.get("t_broken")
            lines.append(f"Rule {rule}: {'kept' if r.verdict else 'BROKEN'} ({r.score:.2f})"
                         + (f", broke at t = {broke:.1f}" if broke is not None else ""))
            if broke is not None:
                j = int(np.argmin(np.abs(t - broke)))
                ax.plot(st[j, e.own, 1], st[j, e.own, 0], "x", ms=9, mew=2, color="k")
                ax.annotate(rule, (st[j, e.own, 1], st[j, e.own, 0]), fontsize=7, xytext=(4, -10),
                            textcoords="offset points")
    ax.text(0.01, 0.01, "\n".join(lines), transform=ax.transAxes, fontsize=7, va="bottom", ha="left",
            bbox={"boxstyle": "round", "fc": "white", "alpha": 0.85})
    marine_axes(ax)
    ax.legend(fontsize=7, loc="upper right")
    ax.set_title(f"env {explanation.environment}, {explanation.method}, run {explanation.run}: "
                 f"{e.own_name} and {e.other_name} ({explanation.profile.name})", fontsize=9)
    return fig


def write_explanation(explanation: RunExplanation, out) -> list[Path]:
    """Write ``explain.json``, ``scenario.toml`` and one figure per encounter into ``out``.

    Parameters
    ----------
    explanation : RunExplanation
        The re-run.
    out : str or Path
        Output directory.

    Returns
    -------
    list of pathlib.Path
        The files written.
    """
    from mmg_casadi.io import write_json
    from mmg_casadi.scenarios.scenario import dump_scenario

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    paths = [write_json(out / "explain.json", explanation.to_dict())]
    scenario = out / "scenario.toml"
    scenario.write_text(dump_scenario(explanation.scenario), encoding="utf-8")
    paths.append(scenario)
    for k, e in enumerate(explanation.encounters):
        path = out / f"encounter{k}_{e.other_name}.png"
        plot_encounter(explanation, k).savefig(path, dpi=150)
        paths.append(path)
    return paths
