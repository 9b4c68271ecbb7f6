"""Run a :class:`~mmg_casadi.scenarios.scenario.Scenario` through the compiled closed loop and assess the result.

``metrics.json`` schema (stable; distances in L, times non-dimensional L/U_des)::

    {"method": str, "collision": bool, "t_end": float, "params": {every parameter of the table, resolved},
     "ships": [{"name", "method",
                "status": "reached"|"diverged"|"stalled"|"timeout"|"grounded"|"collided",
                "reached_goal": bool, "time_to_goal": float|null, "ce": float, "mcte": float,
                "collided": bool, "collision_time": float|null, "collision_with": str|null,
                "collision_kind": "ship"|"obstacle"|"wall"|"land"|null, "collision_position": [x, y]|null,
                "min_speed": float,
                "reduced_speed_time": float, "delay": float|null,
                "min_distance": float, "stalled_at": [x, y]|null, "reactive_time": float,
                "rule9": {"verdict", "score", "channel_time", ...}|null,
                "route": {"planned": bool, "waypoints": [[x, y], ...]}}],
     "route_warnings": [{"ship", "index", "leg", "from", "to", "land", "crosses", "distance", "clearance",
                         "where"}],
     "pairs": [{"a", "b", "min_distance", "t_min", "encounter", "compliant",
                "encounter_b", "compliant_b", "t_enter", "rules",
                "encounters": {"a": [Encounter.to_dict()], "b": [Encounter.to_dict()]}}]}

``encounters`` is the encounter scorer's judgement of a ship pair (:func:`mmg_casadi.colregs.scorer.score_encounters`,
under the parameter ``colregs_profile`` recorded in ``params``): per side, ``"a"`` from ship ``a``'s view and
``"b"`` from ``b``'s, a list of :meth:`~mmg_casadi.colregs.scorer.Encounter.to_dict` entries, one per stretch of
risk of collision (``applicable``, ``unfinished`` (it ended before its CPA and is not judged), ``onset``,
``release``, ``closest``, ``encounter``, ``role``, per rule of
:data:`~mmg_casadi.colregs.verdict.RULES` its ``verdict`` and ``score`` or ``null``, the total ``score``,
``compliant``, ``conflicting_duties`` and the ``quantities`` behind them), or a single entry with
``applicable: false`` if the side never had a risk of collision. A ship's duties towards several ships are judged
together over every ship it is paired with (all of them; in a fleet scenario those that came within R_safe), so
conflicting duties (Rule 2(b)) are flagged.

``rule9`` is the ship's COLREG Rule 9(a) verdict in a narrow channel (:mod:`mmg_casadi.colregs.narrow_channel`):
the share of her time in a narrow channel (walls or land on both sides across her track, at most the profile's
``rule9_width``, 20 L, apart) spent on the starboard side of its centre line, kept at the profile's
``rule9_kept_share`` (90 %), under the profile ``colregs_profile``; ``null`` for a ship never in a narrow channel.

``collision_kind`` ``"land"`` is a grounding (the ship touched an edge of a land polygon ``land<k>``);
``collision_position`` is where the ship was at its first collision or grounding. A collision or grounding ends
that ship's voyage (:func:`mmg_casadi.closed_loop.step.stop_on_contact`): she is held where it happened and her
``status`` is ``"grounded"`` (land) or ``"collided"`` (a ship, an obstacle or a channel wall), never
``"reached"``; ``time_to_goal`` is then null and CE and MCTE are over her voyage up to the contact.

``route`` is the route the ship sailed, ``planned`` when it was planned around the land (``route = "plan"``,
:mod:`mmg_casadi.scenarios.routes`); ``route_warnings`` lists the legs of the routes that cross land or pass within
the grounding clearance of it (:func:`mmg_casadi.scenarios.routes.check_routes`; ``simulate`` prints one line per
leg on stderr).

The other pair keys are the *legacy scorer*, kept unchanged for now: ``encounter``/``compliant`` are from ship
``a``'s side (``encounter_b``/``compliant_b`` from ``b``'s) and ``rules`` is the rule-by-rule scoring of
:func:`mmg_casadi.colregs.score.score_pair` under the legacy profile (the ``profile`` argument of
:func:`run_scenario`/:func:`assess`, not ``colregs_profile``). Static obstacles appear as ``b = "obstacle<k>"`` with
encounter ``"static"`` (no ``rules``, no ``encounters``).
Outcome, CE, MCTE and collisions (with a ship or any hazard, reported by kind) come from the closed loop's one
judgement, :func:`mmg_casadi.closed_loop.outcome.ship_outcomes` (``ce``/``mcte`` are null for a diverged ship).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np

from mmg_casadi.closed_loop.outcome import ship_outcomes
from mmg_casadi.closed_loop.problem import build_problem
from mmg_casadi.closed_loop.replay import REPLAY
from mmg_casadi.closed_loop.simulation import Trajectory, simulate
from mmg_casadi.closed_loop.state import tallies
from mmg_casadi.colregs.assess import assess_pair
from mmg_casadi.colregs.classify import get_profile
from mmg_casadi.colregs.narrow_channel import rule9
from mmg_casadi.colregs.scorer import score_encounters
from mmg_casadi.errors import InputError
from mmg_casadi.guidance.methods import run_of
from mmg_casadi.io import json_safe, staged_directory, write_json
from mmg_casadi.scenarios.routes import check_routes, plan_routes
from mmg_casadi.scenarios.scenario import Scenario, load_scenario, with_method
from mmg_casadi.vessel.library import pair_collision_distance, ship_size


@dataclass
class ScenarioResult:
    """A simulated scenario: the scenario, its trajectory and the assessed metrics (the JSON schema above).

    Parameters
    ----------
    scenario : Scenario
        The scenario that ran.
    trajectory : Trajectory
        Its rollout (states and auxiliary signals at every guidance step).
    metrics : dict
        The assessment (module docstring), JSON-ready.
    encounter_labels : dict
        Per ship index, the COLREG situations it met, for figure legends.
    """

    scenario: object
    trajectory: Trajectory
    metrics: dict
    encounter_labels: dict = field(default_factory=dict)

    @property
    def params(self) -> dict:
        """The resolved parameter set the scenario ran with."""
        return self.metrics["params"]

    def names(self) -> list[str]:
        """Ship names, own ship first.

        Returns
        -------
        list of str
            The ``name`` of each ship in scenario order.
        """
        return [s.name for s in self.scenario.ships]

    def plot(self, ax=None):
        """Draw the result; returns the figure.

        Parameters
        ----------
        ax : matplotlib Axes, optional
            Draw the ships' paths (marine view) into ``ax``; without it a new figure with paths, rudder and
            distance panels (as ``simulate`` saves) is made.

        Returns
        -------
        matplotlib.figure.Figure
            The new figure, or the figure of ``ax``.
        """
        from mmg_casadi.plotting import plot_paths, plot_scenario  # matplotlib: only when drawing
        if ax is None:
            return plot_scenario(self)
        plot_paths(self, ax)
        return ax.figure

    def to_pandas(self):
        """The per-ship metrics as a pandas DataFrame, one row per ship (index: ship name).

        Returns
        -------
        pandas.DataFrame
            The entries of ``metrics["ships"]`` except ``stalled_at``, indexed by ship name.
        """
        rows = [{k: v for k, v in s.items() if k != "stalled_at"} for s in self.metrics["ships"]]
        import pandas as pd  # about 0.3 s to import: only for to_pandas
        return pd.DataFrame(rows).set_index("name")

    def to_frame(self):
        """Alias of :meth:`to_pandas` (the name of 0.2; kept for one release).

        Returns
        -------
        pandas.DataFrame
            As :meth:`to_pandas`.
        """
        return self.to_pandas()

    def save(self, out, *, tracking: bool = False, units=None) -> Path:
        """Write the files ``simulate`` writes (``trajectory.npz``, ``trajectory.csv``, ``scenario.png``,
        ``metrics.json``) into directory ``out``; returns its path.

        Parameters
        ----------
        out : str or Path
            Output directory (created).
        tracking : bool
            Draw the waypoint-tracking figure instead of the encounter figure.
        units : mmg_casadi.units.Units or str, optional
            Units of the figure: ``"nd"`` (default: L, L/U, U) or ``"si"`` (m, s, kn).

        Returns
        -------
        pathlib.Path
            The output directory.
        """
        write_outputs(self, out, tracking=tracking, units=units)
        return Path(out)

    def pair_distances(self) -> dict:
        """Distance histories ``{(a, b): d(t)}`` for every ship pair and ship–obstacle pair (NaN while a ship is
        not sailing); in a fleet scenario (the fleet step) only for the pairs that came within R_safe.

        Returns
        -------
        dict
            ``(name_a, name_b)`` (``"obstacle<k>"`` for an obstacle) to a ``numpy.ndarray (T+1,)`` of distances (L) at
            the trajectory's times.
        """
        tr = self.trajectory
        mask = tr.sailing_mask()
        names = self.names()
        out = {}
        pairs, obstacle_pairs = _pairs(self.scenario, tr, mask, self.params["r_safe"])
        for i, j in pairs:
            d = np.hypot(tr.state("x", i) - tr.state("x", j), tr.state("y", i) - tr.state("y", j))
            out[(names[i], names[j])] = np.where(mask[:, i] & mask[:, j], d, np.nan)
        for i, k in obstacle_pairs:
            o = self.scenario.obstacles[k]
            d = np.hypot(tr.state("x", i) - o.position[0], tr.state("y", i) - o.position[1])
            out[(names[i], f"obstacle{k}")] = np.where(mask[:, i], d, np.nan)
        return out

    def own_distance(self) -> np.ndarray:
        """Distance from the own ship to its nearest other agent over time.

        Returns
        -------
        numpy.ndarray (T+1,)
            Distance (L) at the trajectory's times; ``inf`` where no other agent is present.
        """
        own = self.names()[0]
        ds = [d for (a, b), d in self.pair_distances().items() if a == own or b == own]
        if not ds:
            return np.full(len(self.trajectory.t), np.inf)
        d = np.vstack(ds)
        return np.min(np.where(np.isnan(d), np.inf, d), axis=0)


def run_scenario(scenario, params: dict | None = None, *, method: str | None = None,
                 profile=None) -> ScenarioResult:
    """Simulate a scenario in the compiled closed loop and assess it.

    Parameters
    ----------
    scenario : Scenario, str or Path
        A scenario, or the path of a scenario TOML file (:func:`~mmg_casadi.scenarios.scenario.load_scenario`); a
        name that is no file but names a shipped scenario (``"head_on"`` or ``"head_on.toml"``) loads that one
        (:func:`packaged_scenario`), as ``mmg-casadi simulate head_on`` does.
    params : dict, optional
        Parameter overrides by name (:data:`mmg_casadi.params.PARAMETERS`); they win over the scenario's
        ``[settings]``. A parameter of a method none of the ships uses is refused
        (:func:`~mmg_casadi.guidance.methods.check_used`; inside a study, against the study's methods).
    method : str, optional
        Replace the scenario's ``settings.method`` (per-ship overrides are kept).
    profile : ColregProfile or str, optional
        Legacy COLREG threshold profile of the pair keys ``encounter``/``compliant``/``rules`` or its name
        (default: the paper laboratory's); the encounter scorer's profile is the parameter ``colregs_profile``.

    Returns
    -------
    ScenarioResult
        ``.metrics`` (the schema above), ``.trajectory``, ``.plot()``, ``.to_frame()``, ``.save(dir)``.

    Examples
    --------
    >>> r = run_scenario(packaged_scenario("head_on"), params={"t_max": 5.0})
    >>> r.metrics["params"]["t_max"], r.metrics["ships"][0]["status"]
    (5.0, 'timeout')
    """
    if isinstance(scenario, Scenario):
        sc = scenario
    else:
        path = Path(scenario)
        shipped = path.suffix in (".toml", "") and path.parent == Path(".") and not path.exists()
        sc = packaged_scenario(path.stem) if shipped and path.stem in packaged_names() else load_scenario(path)
    if method is not None:
        sc = with_method(sc, method)
    sc = plan_routes(sc, sc.settings.resolved(params))
    problem = build_problem(sc, params)
    with run_of(problem.layout.methods, params):
        traj = simulate(problem.layout, problem.x0, problem.p)
    return assess(sc, traj, problem.params, profile=profile)


def packaged_names() -> list[str]:
    """Names of the scenarios shipped in ``mmg_casadi/data/scenarios/`` (file names without ``.toml``), sorted.

    Returns
    -------
    list of str
        Scenario names, sorted.

    Examples
    --------
    >>> "head_on" in packaged_names()
    True
    """
    return sorted(p.name[:-5] for p in _scenario_dir().iterdir() if p.name.endswith(".toml"))


def _scenario_dir():
    return resources.files("mmg_casadi").joinpath("data", "scenarios")


def packaged_scenarios() -> list[dict]:
    """What ``mmg-casadi scenarios`` lists: per shipped scenario its ``name``, number of ``ships`` and of
    ``obstacles``, ``method`` (``settings.method``, followed by the ships that override it) and ``description``
    (the file's header comment up to its first comma, colon or full stop outside parentheses; ``""`` without one).

    Returns
    -------
    list of dict
        One dict per scenario, in name order, with keys ``name``, ``ships``, ``obstacles``, ``method`` and
        ``description``.

    Examples
    --------
    >>> row = {r["name"]: r for r in packaged_scenarios()}["crossing"]
    >>> row["ships"], row["description"]
    (2, 'Crossing encounter (COLREG Rule 15)')
    """
    rows = []
    for name in packaged_names():
        sc = packaged_scenario(name)
        own = [f"{s.name}: {s.method}" for s in sc.ships if s.method not in (None, sc.settings.method)]
        text = _scenario_dir().joinpath(f"{name}.toml").read_text(encoding="utf-8")
        rows.append({"name": name, "ships": len(sc.ships), "obstacles": len(sc.obstacles),
                     "method": sc.settings.method + (f" ({', '.join(own)})" if own else ""),
                     "description": _first_clause(text)})
    return rows


def _first_clause(text: str) -> str:
    """The header comment of a scenario file up to its first comma, colon or full stop outside parentheses."""
    head = []
    for line in text.splitlines():
        if not line.startswith("#"):
            break
        head.append(line.lstrip("#").strip())
    words, depth = " ".join(head), 0
    for k, ch in enumerate(words):
        depth += (ch in "([") - (ch in ")]")
        if depth == 0 and ch in ",:." and (k + 1 == len(words) or words[k + 1] == " "):
            return words[:k]
    return words


def packaged_scenario(name: str) -> Scenario:
    """A scenario shipped in ``mmg_casadi/data/scenarios/<name>.toml`` (head_on, crossing, overtaking, conflict,
    static_obstacle, narrow_channel, ...; `mmg-casadi scenarios` lists them).

    Parameters
    ----------
    name : str
        File name without ``.toml``.

    Returns
    -------
    Scenario
        The validated scenario.

    Examples
    --------
    >>> [s.name for s in packaged_scenario("crossing").ships]
    ['ship1', 'ship2']
    """
    names = packaged_names()
    if name not in names:
        raise InputError("scenario", f"one of: {', '.join(names)}", name)
    return load_scenario(_scenario_dir().joinpath(f"{name}.toml"))


def assess(sc, traj: Trajectory, params: dict, *, profile=None) -> ScenarioResult:
    """Metrics of a trajectory: per-ship outcome, CE, MCTE, collisions; per-pair closest approach and COLREGs.

    Parameters
    ----------
    sc : Scenario
        The simulated scenario.
    traj : Trajectory
        Its rollout.
    params : dict
        The resolved parameter set it ran with (:func:`mmg_casadi.params.resolve`).
    profile : ColregProfile or str, optional
        Legacy COLREG threshold profile or its name (:data:`mmg_casadi.colregs.classify.PROFILES`; default: the
        paper laboratory's); the ``encounters`` of every pair use ``params["colregs_profile"]`` instead.

    Returns
    -------
    ScenarioResult
        The scenario, the trajectory, the ``metrics`` (``method``, ``collision``, ``t_end`` in L/U, ``params``,
        per-ship ``ships`` and per-pair ``pairs``) and the encounter labels of the figures.
    """
    profile = get_profile(profile)
    g = {k: params[k] for k in ("r_safe", "collision_distance")}
    names = [s.name for s in sc.ships]
    N = len(names)
    S = len(sc.obstacles)
    n_wall = traj.layout.n_walls - traj.layout.n_land
    agent_names = (names + [f"obstacle{k}" for k in range(S)] + [f"wall{k}" for k in range(n_wall)]
                   + [f"land{k}" for k in range(traj.layout.n_land)])
    mask = traj.sailing_mask()
    t_end = float(traj.t[-1])
    final = np.concatenate([[t_end], traj.final.ravel()])
    banks = scenario_segments(sc)
    unit = sc.ships[0].vessel or params["vessel"]
    sizes = [ship_size(s.vessel or params["vessel"], s.length_m, s.beam_m, unit=unit) for s in sc.ships]
    ships = []
    counts = tallies(traj.layout, final)  # a planner's counts over the run (Method.tallies), if any
    for i, (s, o) in enumerate(zip(sc.ships, ship_outcomes(traj.layout, final, params))):
        ships.append({
            "name": s.name,
            "method": REPLAY if i in traj.layout.replay else traj.layout.methods[i],
            "status": o["status"],
            "reached_goal": o["status"] == "reached",
            "time_to_goal": o["time_to_goal"],
            "ce": o["ce"],
            "mcte": o["mcte"],
            "collided": o["collision_time"] is not None,
            "collision_time": o["collision_time"],
            "collision_with": None if o["collision_with"] is None else agent_names[o["collision_with"]],
            "collision_kind": o["collision_kind"],
            "collision_position": _position_at(traj, i, o["collision_time"]),
            "min_distance": o["min_distance"],
            "stalled_at": None if o["stalled_at"] is None else list(o["stalled_at"]),
            "reactive_time": o["reactive_time"],
            "rule9": _rule9(traj, i, mask[:, i], banks, params["colregs_profile"]),
            "route": {"planned": getattr(s, "track", None) is None and (s.route or params["route"]) == "plan",
                      "waypoints": [list(w) for w in s.waypoints]},
            **(_speed_metrics(s, traj, i, mask[:, i], o["time_to_goal"], params["goal_tolerance"])
               if getattr(s, "track", None) is None else _replay_speed_metrics(traj, i, mask[:, i])),
            **({"tallies": counts[i]} if counts[i] else {}),
        })
    pairs = []
    labels: dict = {}
    ship_pairs, obstacle_pairs = _pairs(sc, traj, mask, g["r_safe"])
    partners = {i: [] for i in range(N)}
    for i, j in ship_pairs:
        partners[i].append(j)
    obstacles_of = {i: [] for i in range(N)}
    for i, k in obstacle_pairs:
        obstacles_of[i].append(k)
    judged = _encounters(traj, mask, names, ship_pairs, params["colregs_profile"])
    lengths = [size[0] for size in sizes]
    for i in range(N):
        pi = np.column_stack([traj.state("x", i), traj.state("y", i)])
        for j in partners[i]:
            pj = np.column_stack([traj.state("x", j), traj.state("y", j)])
            a = assess_pair(traj.t, pi, traj.state("psi", i), pj, traj.state("psi", j),
                            r_safe=g["r_safe"],
                            collision_distance=pair_collision_distance(g["collision_distance"], lengths[i],
                                                                       lengths[j]),
                            profile=profile, active_a=mask[:, i], active_b=mask[:, j])
            pairs.append({"a": names[i], "b": names[j], "min_distance": float(a.min_distance),
                          "t_min": float(a.t_min), "encounter": a.encounter, "compliant": a.compliant,
                          "encounter_b": a.encounter_b, "compliant_b": a.compliant_b,
                          "t_enter": None if a.t_enter is None else float(a.t_enter), "rules": a.rules,
                          "encounters": {"a": judged.get((i, j), []), "b": judged.get((j, i), [])}})
            for k, enc, ok in ((i, a.encounter, a.compliant), (j, a.encounter_b, a.compliant_b)):
                if enc not in (None, "none"):
                    tag = f"{enc} {'✓' if ok else '✗' if ok is not None else ''}".strip()
                    labels[k] = ", ".join(filter(None, [labels.get(k), tag]))
        for k in obstacles_of[i]:
            o = sc.obstacles[k]
            d = np.linalg.norm(pi - np.asarray(o.position), axis=1)
            d = np.where(mask[:, i], d, np.inf)
            kmin = int(np.argmin(d))
            pairs.append({"a": names[i], "b": f"obstacle{k}", "min_distance": float(d[kmin]),
                          "t_min": float(traj.t[kmin]), "encounter": "static" if d[kmin] <= g["r_safe"] else "none",
                          "compliant": None, "encounter_b": None, "compliant_b": None, "t_enter": None})
    collision = any(s["collided"] for s in ships)  # the closed loop's own judgement (ships and every hazard)
    warnings = check_routes(sc, [half + params["grounding_margin"] for _, half in sizes]) if sc.land else []
    metrics = {"method": sc.settings.method, "collision": bool(collision), "t_end": t_end,
               "params": dict(params), "ships": ships, "pairs": pairs, "route_warnings": warnings}
    return ScenarioResult(sc, traj, json_safe(metrics), labels)


def scenario_segments(sc) -> list:
    """Every wall segment and land edge of a scenario, as pairs of end points (L).

    Parameters
    ----------
    sc : Scenario
        The scenario.

    Returns
    -------
    list of ((ax, ay), (bx, by))
        Walls first, then land edges, in the order of the closed loop's wall segments.
    """
    return [seg for w in sc.walls for seg in w.segments] + [e for land in sc.land for e in land.edges]


def _rule9(traj: Trajectory, i: int, active, banks: list, profile: str):
    """Ship ``i``'s Rule 9(a) verdict (:func:`mmg_casadi.colregs.narrow_channel.rule9`, under ``profile``) as a
    dict, or None."""
    xy = np.column_stack([traj.state("x", i), traj.state("y", i)])
    r = rule9(traj.t, xy, traj.state("psi", i), active, banks, profile=profile)
    return None if r is None else r.to_dict()


def _encounters(traj: Trajectory, mask: np.ndarray, names: list, ship_pairs: list, profile: str) -> dict:
    """``{(own, other): [Encounter.to_dict()]}`` of the encounter scorer for both sides of every reported ship pair.

    Each ship is judged once against all the ships it is paired with (so that its duties towards several ships
    are judged together), on the trajectory's speeds over the ground and sailing mask.
    """
    met: dict = {}
    if len(traj.t) < 2:  # one sample has no velocity, hence no risk of collision
        return {}
    for i, j in ship_pairs:
        met.setdefault(i, set()).add(j)
        met.setdefault(j, set()).add(i)
    x, y, psi = traj.state("x"), traj.state("y"), traj.state("psi")
    out: dict = {}
    for i, others in met.items():
        ships = [i, *sorted(others)]
        for e in score_encounters(traj.t, np.stack([x[:, ships], y[:, ships]], axis=2), psi[:, ships],
                                  active=mask[:, ships], profile=profile, names=[names[k] for k in ships], own=0):
            out.setdefault((i, ships[e.other]), []).append(e.to_dict())
    return out


REDUCED_SPEED = 0.9
"""A ship sails at reduced speed while its speed through the water is below this fraction of its planned speed."""


def _position_at(traj, i: int, t) -> list | None:
    """Ship ``i``'s position ``[x, y]`` (L) at time ``t`` of the trajectory (``None`` for ``t`` None)."""
    if t is None:
        return None
    return [float(np.interp(t, traj.t, traj.state(name, i))) for name in ("x", "y")]


def _speed_metrics(ship, traj: Trajectory, i: int, sailing: np.ndarray, time_to_goal, r_tol: float) -> dict:
    """Ship ``i``'s ``min_speed`` (U, through the water, while sailing), ``reduced_speed_time`` (L/U below
    :data:`REDUCED_SPEED` of the planned speed of the leg sailed) and ``delay`` (time to goal minus the planned
    voyage time: the legs' lengths over their planned speeds, the last one ending at the goal's acceptance radius
    ``r_tol``; null if the goal was not reached)."""
    speed = np.hypot(traj.state("u", i), traj.state("v", i))
    legs = np.asarray([ship.speed] * len(ship.waypoints) if ship.speeds is None else ship.speeds, float)
    leg = np.clip(traj.state("idx", i).astype(int) - 1, 0, len(legs) - 1)
    planned = legs[leg]
    steps = np.diff(traj.t, append=traj.t[-1])
    path = np.vstack([ship.start, ship.waypoints])
    lengths = np.hypot(*np.diff(path, axis=0).T)
    lengths[-1] = max(lengths[-1] - r_tol, 0.0)
    voyage = float(np.sum(lengths / legs))
    return {"min_speed": float(np.min(speed[sailing])) if sailing.any() else None,
            "reduced_speed_time": float(np.sum(steps[sailing & (speed < REDUCED_SPEED * planned)])),
            "delay": None if time_to_goal is None else float(time_to_goal) - voyage}


def _replay_speed_metrics(traj: Trajectory, i: int, sailing: np.ndarray) -> dict:
    """A replayed ship's ``min_speed`` (U, over the ground, from its track while it sails); it has no planned
    speed or voyage, so ``reduced_speed_time`` is 0 and ``delay`` null."""
    speed = np.hypot(traj.state("u", i), traj.state("v", i))
    return {"min_speed": float(np.min(speed[sailing])) if sailing.any() else None, "reduced_speed_time": 0.0,
            "delay": None}


def _pairs(sc, traj: Trajectory, mask: np.ndarray, r_safe: float) -> tuple[list, list]:
    """The ship pairs ``(i, j)``, ``i < j``, and ship–obstacle pairs ``(i, k)`` a result reports: all of them, or in
    a fleet scenario (the fleet step) those that came within ``r_safe`` while sailing (a k-d tree per sample)."""
    N, S = traj.layout.n_ships, len(sc.obstacles)
    if not traj.layout.neighbours:
        return [(i, j) for i in range(N) for j in range(i + 1, N)], [(i, k) for i in range(N) for k in range(S)]
    ships, obstacles = set(), set()
    obs = np.array([o.position for o in sc.obstacles], float).reshape(S, 2)
    for k in range(len(traj.t)):
        sailing = np.flatnonzero(mask[k])
        if not len(sailing):
            continue
        pts = np.column_stack([traj.states[k, sailing, traj.layout.column("x")],
                               traj.states[k, sailing, traj.layout.column("y")]])
        from scipy.spatial import cKDTree  # about 0.2 s to import: only where it is used
        tree = cKDTree(pts)
        ships |= {(int(sailing[a]), int(sailing[b])) for a, b in tree.query_pairs(r_safe)}
        if S:
            for a, near in enumerate(tree.query_ball_point(obs, r_safe)):
                obstacles |= {(int(sailing[b]), a) for b in near}
    return sorted((min(p), max(p)) for p in ships), sorted(obstacles)


def write_outputs(res: ScenarioResult, out, *, figure_name: str = "scenario.png", tracking: bool = False,
                  units=None) -> None:
    """Write ``trajectory.npz``, ``trajectory.csv``, ``metrics.json`` and the figure into ``out``, all or none:
    they are written into a hidden sibling folder first and moved into ``out`` at the end
    (:func:`~mmg_casadi.io.staged_directory`), so an interruption (Ctrl-C, SIGTERM) leaves no partial file.

    Parameters
    ----------
    res : ScenarioResult
        The result to save.
    out : str or Path
        Output directory (created).
    figure_name : str
        File name of the figure.
    tracking : bool
        Draw the waypoint-tracking figure instead of the encounter figure.
    units : mmg_casadi.units.Units or str, optional
        Units of the figure: ``"nd"`` (default) or ``"si"``.
    """
    from mmg_casadi.plotting import plot_fleet, plot_scenario, plot_tracking  # matplotlib: only when writing
    with staged_directory(out) as tmp:
        res.trajectory.to_npz(tmp / "trajectory.npz")
        res.trajectory.to_csv(tmp / "trajectory.csv", names=res.names())
        figure = plot_tracking if tracking else plot_fleet if res.trajectory.layout.neighbours else plot_scenario
        figure(res, tmp / figure_name, **({} if units is None else {"units": units}))
        write_json(tmp / "metrics.json", res.metrics)
