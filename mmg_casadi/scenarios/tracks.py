"""Recorded tracks of replayed ships in scenario files: ``track = "file.csv"`` or an inline ``[ships.track]`` table.

A ship with a ``track`` is *replayed* (:mod:`mmg_casadi.closed_loop.replay`): it follows its track, interpolated
in time, instead of being simulated. The track gives its samples in the scenario's units::

    [[ships]]
    name = "999000002"
    track = "target.csv"   # CSV with the columns t, x, y (L/U, L, L); other columns are ignored;
                           # a relative path is relative to the scenario file's folder
    # or inline:
    # [ships.track]
    # t = [-2.0, 10.0, 25.5]
    # x = [30.0, 30.0, 18.0]
    # y = [40.0, 28.0, 12.0]

The times are strictly increasing, the first at or before the scenario's start (t = 0) and the last after it; a
replayed ship starts where its track is at t = 0 and is done at its last sample. Speeds between samples are at
most :data:`MAX_TRACK_SPEED` (a larger one is a bad record).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mmg_casadi.closed_loop.replay import sample_track, track_heading
from mmg_casadi.errors import ScenarioError
from mmg_casadi.limits import MAX_COORDINATE
from mmg_casadi.readers import csv_rows

TRACK_COLUMNS = ("t", "x", "y")
"""Columns (keys) of a track: time (L/U), position x and y (L)."""
MAX_TRACK_POINTS = 20_000
"""Largest number of samples of one track."""
MIN_TRACK_STEP = 1e-6
"""Smallest time between two samples of a track [L/U] (a closer pair makes no speed: 0/0)."""
MAX_TRACK_SPEED = 3.0
"""Largest speed between two samples (U, the model envelope's speed): a faster jump is a bad record."""
_ALLOWED = ('a CSV file name (columns t, x, y) or a table {t = [...], x = [...], y = [...]} of 2 to '
            f'{MAX_TRACK_POINTS} samples')


@dataclass(frozen=True)
class Track:
    """A recorded track: sample times ``t`` (L/U, strictly increasing) and positions ``x``, ``y`` (L).

    Parameters
    ----------
    t, x, y : sequence of float
        The samples.

    Examples
    --------
    >>> tr = Track([0.0, 10.0], [0.0, 5.0], [0.0, 0.0])
    >>> tr.position(4.0).tolist(), tr.speed(4.0), tr.heading(4.0)
    ([2.0, 0.0], 0.5, 0.0)
    """

    t: tuple
    x: tuple
    y: tuple

    def __post_init__(self):
        for name in TRACK_COLUMNS:
            object.__setattr__(self, name, tuple(float(v) for v in getattr(self, name)))

    def __len__(self) -> int:
        return len(self.t)

    def position(self, tq: float) -> np.ndarray:
        """Position (L) at time ``tq`` (L/U), as the compiled step interpolates it.

        Parameters
        ----------
        tq : float
            Time (L/U).

        Returns
        -------
        numpy.ndarray (2,)
            ``[x, y]``.
        """
        return sample_track(self.t, self.x, self.y, tq)[0]

    def velocity(self, tq: float) -> np.ndarray:
        """Velocity over the ground (U) of the segment containing ``tq``.

        Parameters
        ----------
        tq : float
            Time (L/U).

        Returns
        -------
        numpy.ndarray (2,)
            ``[v_x, v_y]``.
        """
        return sample_track(self.t, self.x, self.y, tq)[1]

    def speed(self, tq: float) -> float:
        """Speed over the ground (U) at time ``tq``.

        Parameters
        ----------
        tq : float
            Time (L/U).

        Returns
        -------
        float
            The speed.
        """
        return float(math.hypot(*self.velocity(tq)))

    def heading(self, tq: float) -> float:
        """Heading (rad) at time ``tq``: the direction of the velocity (of the first movement while still).

        Parameters
        ----------
        tq : float
            Time (L/U).

        Returns
        -------
        float
            The heading, from x towards y.
        """
        return track_heading(self.t, self.x, self.y, tq)

    def to_dict(self) -> dict:
        """The inline ``[ships.track]`` table.

        Returns
        -------
        dict
            ``{"t": [...], "x": [...], "y": [...]}``.
        """
        return {name: list(getattr(self, name)) for name in TRACK_COLUMNS}


def _read_csv(path: Path, key: str) -> dict:
    """The columns t, x, y of a track CSV file as lists of strings (streamed: at most :data:`MAX_TRACK_POINTS` rows
    and :data:`~mmg_casadi.readers.MAX_BYTES` ``["track"]`` bytes are read, only these columns kept)."""
    cols: dict[str, list] = {c: [] for c in TRACK_COLUMNS}
    for _line, row in csv_rows(path, "track", max_rows=MAX_TRACK_POINTS, field=key, cls=ScenarioError):
        if any(c not in row for c in TRACK_COLUMNS):
            break
        for c in TRACK_COLUMNS:
            cols[c].append(row[c])
    if not cols["t"]:
        raise ScenarioError(key, "a CSV file with the columns t, x, y and at least two rows", str(path))
    return cols


def _number(value, key: str) -> float:
    """``value`` (a number or a numeric string of a CSV file) as a finite float of magnitude at most
    :data:`~mmg_casadi.limits.MAX_COORDINATE` (ship lengths for a position, L/U for a time)."""
    allowed = f"a finite number in [-{MAX_COORDINATE:g}, {MAX_COORDINATE:g}]"
    if isinstance(value, bool):
        raise ScenarioError(key, allowed, value)
    try:
        v = float(value)
    except (TypeError, ValueError, OverflowError):
        raise ScenarioError(key, allowed, value) from None
    if not math.isfinite(v) or abs(v) > MAX_COORDINATE:
        raise ScenarioError(key, allowed, value)
    return v


def parse_track(value, key: str, base_dir=None) -> Track:
    """A validated :class:`Track` from a scenario's ``track`` entry (module docstring).

    Parameters
    ----------
    value : str or dict
        A CSV file name or an inline table ``{t, x, y}``.
    key : str
        Dotted name of the entry (``ships[1].track``); errors name it.
    base_dir : str or Path, optional
        Folder a relative file name is relative to (the scenario file's; default the working directory).

    Returns
    -------
    Track
        The track.

    Raises
    ------
    ScenarioError
        One line naming the entry and the allowed values.

    Examples
    --------
    >>> parse_track({"t": [0, 10], "x": [0, 5], "y": [0, 0]}, "ships[1].track").t
    (0.0, 10.0)
    >>> parse_track({"t": [1, 10], "x": [0, 5], "y": [0, 0]}, "ships[1].track")
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.ScenarioError: ships[1].track.t[0]: expected a first time at or before the scenario's start, 0, got 1.0
    """
    where = key
    if isinstance(value, str) and value:
        path = Path(value)
        if not path.is_absolute() and base_dir is not None:
            path = Path(base_dir) / path
        cols = _read_csv(path, key)
        where = f"{key} ({path.name} row"
    elif isinstance(value, dict):
        extra = [k for k in value if k not in TRACK_COLUMNS]
        if extra or any(c not in value for c in TRACK_COLUMNS):
            raise ScenarioError(key, "a table with the keys t, x, y (arrays of equal length)",
                                extra[0] if extra else sorted(value))
        cols = value
        for c in TRACK_COLUMNS:
            if not isinstance(cols[c], list):
                raise ScenarioError(f"{key}.{c}", "an array of numbers", cols[c])
    else:
        raise ScenarioError(key, _ALLOWED, value)
    n = len(cols["t"])
    if not 2 <= n <= MAX_TRACK_POINTS or any(len(cols[c]) != n for c in TRACK_COLUMNS):
        raise ScenarioError(key, f"{_ALLOWED}, the same number of each", {c: len(cols[c]) for c in TRACK_COLUMNS})

    def field(c, k):
        return f"{where} {k + 2}.{c})" if where != key else f"{key}.{c}[{k}]"

    data = {c: [_number(v, field(c, k)) for k, v in enumerate(cols[c])] for c in TRACK_COLUMNS}
    t = np.asarray(data["t"])
    bad = np.flatnonzero(np.diff(t) < MIN_TRACK_STEP)
    if bad.size:
        k = int(bad[0]) + 1
        raise ScenarioError(field("t", k), f"a time at least {MIN_TRACK_STEP:g} after the previous one, {t[k - 1]:g} "
                            "(strictly increasing)", float(t[k]))
    if t[0] > 0:
        raise ScenarioError(field("t", 0), "a first time at or before the scenario's start, 0", float(t[0]))
    if t[-1] <= 0:
        raise ScenarioError(field("t", n - 1), "a last time after the scenario's start, 0", float(t[-1]))
    speed = np.hypot(np.diff(data["x"]), np.diff(data["y"])) / np.diff(t)
    fast = np.flatnonzero(speed > MAX_TRACK_SPEED)
    if fast.size:
        k = int(fast[0]) + 1
        raise ScenarioError(field("x", k), f"a position reached from the previous one at most at "
                            f"{MAX_TRACK_SPEED:g} U (a faster jump is a bad record)", f"{speed[k - 1]:.3g} U")
    return Track(data["t"], data["x"], data["y"])
