"""Limits on what a run or a study accepts, checked before any work; larger input is refused with one line.

They bound memory and time on the machines the toolkit is built for (2 cores, a few GB): a scenario's size
(the fleet step's cost grows with the fleet, its compile cost does not), a rollout's number of steps and of
ship-steps (a trajectory keeps every ship's every step), and a study's number of runs (results stream to disk, but a plan holds every run
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
import os

from mmg_casadi.errors import InputError, ParameterError

MAX_SHIPS = 2000
"""Largest fleet of one scenario (the fleet step runs it; ``benchmarks/fleet_scaling.py`` measures 1000)."""
MAX_UNROLLED_SHIPS = 40
"""Largest scenario of the unrolled step (a scenario of ``fleet_from_ships`` ships or more runs the fleet step):
its expression graph grows with the square of the fleet (``benchmarks/fleet_scaling.py``: 144 s to compile at
40 ships), so a larger ``fleet_from_ships`` than the scenario's size is refused above this."""
MAX_OBSTACLES = 2000
"""Largest number of static obstacles of one scenario."""
MAX_UNROLLED_OBSTACLE_PAIRS = 64
"""Largest ``ships × obstacles`` of a scenario of the unrolled step: the unrolled step writes every ship–obstacle
pair into its expression, so its compiler's time and memory grow with them (2 ships: 8 obstacles 5.7 s and
84 MB, 32 obstacles 17 s and 187 MB, 500 obstacles over 10 minutes and 6 GB), while the fleet step sees
obstacles through its neighbour slots and compiles in the same 6-13 s and 100-140 MB at 2000 obstacles. A
scenario with more pairs runs the fleet step; every paper scenario and Monte Carlo environment (at most 10 ships
× 4 obstacles) and every packaged one (2 × 16) stays unrolled."""
MAX_COORDINATE = 10_000.0
"""Largest absolute coordinate of a position of a scenario [ship lengths]: 2300 km at the KCS's 230 m. The largest
fleet the toolkit runs (``mmg-casadi traffic 2000``, environment 5's density) spans about 1400 L; the bound keeps
every distance, its square and the fields' terms far from overflow (a start at 1e300 L made the step's NaN)."""
MAX_WALL_SEGMENTS = 500
"""Largest number of wall segments of one scenario (every ship tests every segment at every step)."""
MAX_STEPS = 100_000
"""Largest number of guidance steps of one run, ``t_max / dt`` (a trajectory keeps every step)."""
MAX_SHIP_STEPS = 2_400_000
"""Largest ``ships × t_max / dt`` of one run (a trajectory keeps every ship's every step; ``simulate`` of 300
ships over 1200 steps peaks at 0.39 GB, about 0.6 kB a ship-step over the 0.17 GB of the interpreter): MAX_SHIPS
ships over the default horizon (t_max 300, dt 0.25), about 1.6 GB."""
MAX_WORKERS_PER_CORE = 4
"""Largest ``--workers`` per core of this machine (``os.cpu_count()``): every local worker is a process holding
the compiled libraries, and more workers than cores only share them."""
MAX_RUNS = 100_000
"""Largest ``--runs`` of a study (per environment and method; 20 × the paper's 5000): the plan holds every run key."""
MAX_STUDY_RUNS = 500_000
"""Largest number of runs of one study, ``runs × environments × methods`` (a sweep: × values; the paper's
analysis: 5000 × 5 × 3 = 75 000): the summary reads every row of ``runs.csv`` into memory, about 2.8 kB a row
at its peak, so about 1.4 GB."""


def check_steps(t_max: float, dt: float, cls=ParameterError, ships: int = 1) -> int:
    """The number of steps ``ceil(t_max / dt)``, or an error naming ``t_max / dt`` when it exceeds
    :data:`MAX_STEPS` (or ``ships × t_max / dt`` when that exceeds :data:`MAX_SHIP_STEPS`).

    Parameters
    ----------
    t_max : float
        Horizon (L/U).
    dt : float
        Guidance step (L/U).
    cls : type, default ParameterError
        Error class raised.
    ships : int, default 1
        Ships of the run.

    Returns
    -------
    int
        The number of guidance steps.

    Examples
    --------
    >>> check_steps(300.0, 0.25, ships=2000)
    1200
    >>> check_steps(300.0, 0.1, ships=2000)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.ParameterError: ships × t_max / dt: expected at most 2400000 ship-steps ... <= 1200), got 6000000
    """
    steps = math.ceil(t_max / dt - 1e-9)
    if steps > MAX_STEPS:
        raise cls("t_max / dt", f"at most {MAX_STEPS} steps (MAX_STEPS)", steps)
    if ships * steps > MAX_SHIP_STEPS:
        raise cls("ships × t_max / dt", f"at most {MAX_SHIP_STEPS} ship-steps (MAX_SHIP_STEPS; {ships} ships: "
                  f"t_max / dt <= {MAX_SHIP_STEPS // ships})", ships * steps)
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


def max_workers() -> int:
    """The largest ``--workers`` on this machine: :data:`MAX_WORKERS_PER_CORE` × ``os.cpu_count()``.

    Returns
    -------
    int
        The limit.
    """
    return MAX_WORKERS_PER_CORE * (os.cpu_count() or 1)


def check_study_size(runs: int, cells: int, field: str = "--runs") -> None:
    """Refuse a study of more than :data:`MAX_STUDY_RUNS` runs (``runs`` per cell × ``cells``).

    Parameters
    ----------
    runs : int
        Runs per cell (environment and method, and value of a sweep).
    cells : int
        Number of cells.
    field : str, default '--runs'
        Name of the input field, used in the error message.

    Examples
    --------
    >>> check_study_size(5000, 15)
    >>> check_study_size(100_000, 15)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.InputError: --runs: expected at most 33333 runs for 15 cells (... 500000 runs in all), got 100000
    """
    if runs * cells > MAX_STUDY_RUNS:
        raise InputError(field, f"at most {MAX_STUDY_RUNS // cells} runs for {cells} cells (environments × methods "
                         f"[× values]: MAX_STUDY_RUNS = {MAX_STUDY_RUNS} runs in all)", runs)


def check_unrolled(n_ships: int, fleet_from_ships: int, cls=ParameterError) -> None:
    """Refuse a scenario of more than :data:`MAX_UNROLLED_SHIPS` ships that ``fleet_from_ships`` would run with
    the unrolled step.

    Parameters
    ----------
    n_ships : int
        The scenario's ships.
    fleet_from_ships : int
        The parameter: scenarios of at least this many ships run the fleet step.
    cls : type, default ParameterError
        Error class raised.

    Examples
    --------
    >>> check_unrolled(100, 16)
    >>> check_unrolled(100, 1000)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.ParameterError: fleet_from_ships: expected at most 100 for a scenario of 100 ships (...), got 1000
    """
    if n_ships > MAX_UNROLLED_SHIPS and n_ships < fleet_from_ships:
        raise cls("fleet_from_ships", f"at most {n_ships} for a scenario of {n_ships} ships (more than "
                  f"MAX_UNROLLED_SHIPS = {MAX_UNROLLED_SHIPS} ships run the fleet step)", fleet_from_ships)


def check_runs(runs, field: str = "--runs") -> int:
    """``runs`` if it is an integer in [1, :data:`MAX_RUNS`], else an :class:`~mmg_casadi.errors.InputError`.

    Parameters
    ----------
    runs : int
        Runs per environment and method.
    field : str, default '--runs'
        Name of the input field, used in the error message.

    Returns
    -------
    int
        ``runs``.
    """
    if isinstance(runs, bool) or not isinstance(runs, int) or not 1 <= runs <= MAX_RUNS:
        raise InputError(field, f"an integer in [1, {MAX_RUNS}] (MAX_RUNS)", runs)
    return runs
