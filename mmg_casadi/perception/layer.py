"""The perception layer inside the compiled step: what the own ship's method knows of the other ships.

With ``perception`` other than ``"off"`` (``Layout.perception``) the own ship
(ship 0) no longer sees the true states of the other ships: at every guidance step, before her method runs, the
layer takes the true states, draws the sensors' noise, updates what she knows and hands her method the perceived
positions, velocities and presence instead of the truth (static obstacles stay known, from the chart). Everything
else, the other ships' methods, the collision bookkeeping and the COLREG scorer, uses the true states.

Where it runs. All of it is CasADi expressions compiled into the closed-loop step (one extra Function per step in
the sparse step), so a Monte Carlo study keeps its one ``mapaccum`` per batch: the noise comes from a random
generator per target whose state is six state rows (:mod:`mmg_casadi.perception.rng`, seeded per run from the
study's seed, :func:`initial_rows`), the AIS schedule and the last report are state rows, and the tracker's mean and
covariance are state rows (:mod:`mmg_casadi.perception.tracker`). The rows of ship ``j`` (:func:`rows`) are the own
ship's knowledge *of ship j*; ship 0's own rows are unused. What it cannot do inside the step: nothing of the model
needed to leave it; the one approximation forced by a fixed step is that an AIS report is taken at the step after
it arrives, its position brought to its transmission time along the ship's velocity (exact on a straight course)
and then dead-reckoned to the step with its own reported velocity (:func:`mmg_casadi.closed_loop.sensing.perceive`).

Modes:

``ais``
    the last received report of each target (:mod:`mmg_casadi.perception.sensors`), dead-reckoned to the present
    with its reported speed and course, as an AIS target on a chart display; a target is unknown until its first
    report.
``radar``
    a constant-velocity Kalman filter per target fed with radar plots, associated by nearest neighbour
    (:mod:`mmg_casadi.perception.tracker`); a track starts from its target's first detection.
``ais-radar``
    the same filter fed with the radar plots and the AIS reports (position, then speed and course); a track starts
    from whichever comes first.

Each step draws, per target and in this order, five uniforms for AIS (position x and y, speed, course, loss) and
three for radar (range, bearing, detection), so the AIS noise of a run is the same in the modes ``ais`` and
``ais-radar``.

The rows ``seen_x``, ``seen_y``, ``seen_vx``, ``seen_vy``, ``seen_known`` after a step hold what the own ship's method
was given during it, and ``seen_err_int`` / ``seen_err_time`` accumulate the position error of a known target while
the true target is within R_safe of the own ship (:func:`perception_error`).
"""

from __future__ import annotations

import math

import numpy as np

from mmg_casadi.perception import rng, sensors, tracker

MODES = ("off", "ais", "radar", "ais-radar")
"""Values of the parameter ``perception``."""
RNG_ROWS = tuple(f"rng{k}" for k in range(6))
AIS_ROWS = ("ais_next", "ais_t", "ais_x", "ais_y", "ais_vx", "ais_vy")
TRACK_ROWS = ("trk_x", "trk_y", "trk_vx", "trk_vy", "trk_known") + tuple(f"trk_p{i}{j}" for i, j in tracker.UPPER)
SEEN_ROWS = ("seen_x", "seen_y", "seen_vx", "seen_vy", "seen_known", "seen_err_int", "seen_err_time")
INPUTS = ("ais_class_b", "ais_scale", "ais_latency", "ais_dropout", "ais_sigma_p", "ais_sigma_sog", "ais_sigma_cog",
          "radar_sigma_r", "radar_sigma_b", "radar_range", "radar_p_detect", "tracker_q", "tracker_gate",
          "kn_per_u", "s_per_t", "turn_rate")
"""Numeric inputs of a step with perception (scene units: L, L/U, U, rad; :func:`input_values`)."""
NEVER = -1.0e9
"""``ais_t`` of a target whose first report has not arrived."""
STREAM = 0x706572
"""Last word of the per-run noise seed's sequence (``"per"`` in ASCII), apart from the other generators'."""
KNOT = 1852.0 / 3600.0
"""One knot in m/s."""
SIGMA_V0 = 1.0
"""Standard deviation (U) of the velocity of a track started from a radar plot (unknown: a ship's speed is below about
1 U)."""


def rows(mode: str) -> tuple[str, ...]:
    """State rows of each ship in a layout with perception ``mode`` (after all its other rows).

    Parameters
    ----------
    mode : str
        One of :data:`MODES`.

    Returns
    -------
    tuple of str
        Empty for ``"off"``.

    Examples
    --------
    >>> len(rows("off")), len(rows("ais")), len(rows("ais-radar"))
    (0, 19, 34)
    """
    if mode == "off":
        return ()
    if mode not in MODES:
        raise ValueError(f"perception: expected one of {', '.join(MODES)}, got {mode!r}")
    return (RNG_ROWS + (AIS_ROWS if "ais" in mode else ()) + (TRACK_ROWS if "radar" in mode else ()) + SEEN_ROWS)


def input_values(values: dict, ship) -> list[float]:
    """The step's :data:`INPUTS` from the table's values, in the scene's units (the own ship's ``ship``).

    Parameters
    ----------
    values : dict
        The table parameters of :mod:`mmg_casadi.params` group ``perception`` (their units: m, s, kn, deg, NM).
    ship : ShipParams
        The own ship's hull: its length ``L`` (m) and design speed ``U_design`` (m/s) are the scene's units.

    Returns
    -------
    list of float
        One value per name of :data:`INPUTS`.
    """
    L, U = float(ship.L), float(ship.U_design)
    T = L / U
    v = {"ais_class_b": 1.0 if values["ais_class"] == "B" else 0.0, "ais_scale": values["ais_interval_scale"],
         "ais_latency": values["ais_latency_s"] / T, "ais_dropout": values["ais_dropout"],
         "ais_sigma_p": values["ais_position_sigma_m"] / L, "ais_sigma_sog": values["ais_sog_sigma_kn"] * KNOT / U,
         "ais_sigma_cog": math.radians(values["ais_cog_sigma_deg"]), "radar_sigma_r": values["radar_range_sigma_m"] / L,
         "radar_sigma_b": math.radians(values["radar_bearing_sigma_deg"]),
         "radar_range": values["radar_range_nm"] * 1852.0 / L, "radar_p_detect": values["radar_p_detect"],
         "tracker_q": values["tracker_q"] * T ** 3 / L ** 2, "tracker_gate": values["tracker_gate"],
         "kn_per_u": U / KNOT, "s_per_t": T, "turn_rate": math.radians(sensors.TURNING_DEG_PER_S) * T}
    return [float(v[k]) for k in INPUTS]


def run_seed(base_seed: int, environment: int, run: int) -> int:
    """The ``perception_seed`` of run ``run`` of a study: drawn from the study's seed, the same for every method.

    Parameters
    ----------
    base_seed, environment, run : int
        The study's seed and the run.

    Returns
    -------
    int
        A seed in [0, 2^32).

    Examples
    --------
    >>> run_seed(0, 5, 3) == run_seed(0, 5, 3) != run_seed(0, 5, 4)
    True
    """
    return int(np.random.SeedSequence([int(base_seed), int(environment), int(run), STREAM]).generate_state(1)[0])


def initial_rows(mode: str, seed: int, ship: int, interval: float) -> dict:
    """A ship's perception rows at t = 0: its noise generator seeded from ``(seed, ship)``, no report, no track.

    Parameters
    ----------
    mode : str
        The layout's perception mode.
    seed : int
        The run's ``perception_seed``.
    ship : int
        Ship index.
    interval : float
        The ship's AIS reporting interval at t = 0 (L/U): its first report is sent at a time uniform in
        ``[0, interval)`` (drawn from the generator's first uniform, which the step does not use again).

    Returns
    -------
    dict
        Row name to value.
    """
    state = rng.seed_state([int(seed), int(ship), STREAM])
    state, u = rng.mrg_next(state)
    out = dict(zip(RNG_ROWS, (float(s) for s in state)))
    if "ais" in mode:
        out.update({"ais_next": float(u) * float(interval), "ais_t": NEVER})
    return out


def initial_interval(values: dict, ship, speed: float) -> float:
    """AIS reporting interval (L/U) of a ship sailing at ``speed`` (U) on a straight course, scaled as the study asks.

    Parameters
    ----------
    values : dict
        The table's perception parameters.
    ship : ShipParams
        The own ship's hull (the scene's units).
    speed : float
        The ship's speed (fraction of the own ship's design speed).

    Returns
    -------
    float
        The interval in L/U.
    """
    kn = abs(float(speed)) * float(ship.U_design) / KNOT
    s = sensors.ais_interval_s(kn, 0.0, 1.0 if values["ais_class"] == "B" else 0.0)
    return float(values["ais_interval_scale"]) * s / (float(ship.L) / float(ship.U_design))


SENSOR_PARAMS = {"ais": ("ais_class", "ais_interval_scale", "ais_latency_s", "ais_dropout", "ais_position_sigma_m",
                         "ais_sog_sigma_kn", "ais_cog_sigma_deg"),
                 "radar": ("radar_range_sigma_m", "radar_bearing_sigma_deg", "radar_range_nm", "radar_p_detect",
                           "tracker_q", "tracker_gate")}
"""The table parameters of each sensor (the tracker's with the radar: the mode ``ais`` has no filter)."""


def unused_parameter(resolved: dict) -> str | None:
    """A sensor parameter set away from its default that the run's ``perception`` does not use, or None.

    Parameters
    ----------
    resolved : dict
        A resolved parameter set.

    Returns
    -------
    str or None
        The first such name (``perception_seed`` too with perception ``"off"``).

    Examples
    --------
    >>> from mmg_casadi.params import resolve
    >>> unused_parameter(resolve({"ais_dropout": 0.2})), unused_parameter(resolve({"perception": "radar",
    ...                                                                             "radar_p_detect": 0.5}))
    ('ais_dropout', None)
    """
    from mmg_casadi.params import PARAMETERS

    mode = resolved["perception"]
    names = [k for sensor, ks in SENSOR_PARAMS.items() if sensor not in mode for k in ks]
    if mode == "off":
        names.append("perception_seed")
    return next((k for k in names if resolved[k] != PARAMETERS[k].default), None)


def perception_error(layout, x_final) -> float:
    """Mean distance (L) between where the own ship's method saw a target and where it was, over the time a known
    target was within R_safe of the sailing own ship (``nan`` without perception or without such time).

    Parameters
    ----------
    layout : Layout
        The closed loop's shape.
    x_final : array (nx,)
        Final scenario state.

    Returns
    -------
    float
        The time-weighted mean position error over all targets.
    """
    if layout.perception == "off":
        return math.nan
    x = np.asarray(x_final, float)
    err = sum(x[layout.row("seen_err_int", j)] for j in range(1, layout.n_ships))
    time = sum(x[layout.row("seen_err_time", j)] for j in range(1, layout.n_ships))
    return float(err / time) if time > 0 else math.nan
