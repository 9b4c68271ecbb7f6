"""Limits on what a run or a study accepts, checked before any work; larger input is refused with one line.

They bound memory and time on the machines the toolkit is built for (2 cores, a few GB): a scenario's size
(the fleet step's cost grows with the fleet, its compile cost does not), a rollout's number of steps (a
trajectory keeps every step), and a study's number of runs (results stream to disk, but a plan holds every run
key).

Examples
--------
>>> check_steps(300.0, 0.25)
1200
>>> check_steps(300.0, 1e-6)
Traceback (most recent call last):
...
mmg_casadi.errors.ParameterError: t_max / dt: expected at most 100000 steps (MAX_STEPS), got 300000000
"""

from __future__ import annotations

import math

from mmg_casadi.errors import InputError, ParameterError

MAX_SHIPS = 2000
"""Largest fleet of one scenario (the fleet step runs it; ``benchmarks/fleet_scaling.py`` measures 1000)."""
MAX_OBSTACLES = 2000
"""Largest number of static obstacles of one scenario."""
MAX_WALL_SEGMENTS = 500
"""Largest number of wall segments of one scenario (every ship tests every segment at every step)."""
MAX_STEPS = 100_000
"""Largest number of guidance steps of one run, ``t_max / dt`` (a trajectory keeps every step)."""
MAX_RUNS = 100_000
"""Largest ``--runs`` of a study (per environment and method; 20 × the paper's 5000): the plan holds every run key."""


def check_steps(t_max: float, dt: float, cls=ParameterError) -> int:
    """The number of steps ``ceil(t_max / dt)``, or an error naming ``t_max / dt`` when it exceeds
    :data:`MAX_STEPS`.

    Parameters
    ----------
    t_max : float
        Horizon (L/U).
    dt : float
        Guidance step (L/U).
    cls : type, default ParameterError
        Error class raised.
    """
    steps = math.ceil(t_max / dt - 1e-9)
    if steps > MAX_STEPS:
        raise cls("t_max / dt", f"at most {MAX_STEPS} steps (MAX_STEPS)", steps)
    return steps


def check_size(n_ships: int, n_obstacles: int, n_wall_segments: int, cls=InputError) -> None:
    """Refuse a scenario with more ships, obstacles or wall segments than the limits.

    Parameters
    ----------
    n_ships, n_obstacles, n_wall_segments : int
        The scenario's counts.
    cls : type, default InputError
        Error class raised.

    Examples
    --------
    >>> check_size(3000, 0, 0)
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.InputError: ships: expected at most 2000 ships (MAX_SHIPS), got 3000
    """
    for field, n, limit, name in (("ships", n_ships, MAX_SHIPS, "MAX_SHIPS"),
                                  ("obstacles", n_obstacles, MAX_OBSTACLES, "MAX_OBSTACLES"),
                                  ("walls", n_wall_segments, MAX_WALL_SEGMENTS, "MAX_WALL_SEGMENTS")):
        if n > limit:
            raise cls(field, f"at most {limit} {field if field != 'walls' else 'wall segments'} ({name})", n)


def check_runs(runs, field: str = "--runs") -> int:
    """``runs`` if it is an integer in [1, :data:`MAX_RUNS`], else an :class:`~mmg_casadi.errors.InputError`.

    Parameters
    ----------
    runs : int
        Runs per environment and method.
    field : str, default '--runs'
        Name of the input field, used in the error message.
    """
    if isinstance(runs, bool) or not isinstance(runs, int) or not 1 <= runs <= MAX_RUNS:
        raise InputError(field, f"an integer in [1, {MAX_RUNS}] (MAX_RUNS)", runs)
    return runs
