"""Random current and wind of the statistical study: one steady disturbance per run, the same for every method.

A study given ranges (:class:`DisturbanceRanges`, e.g. ``--current 0-0.1 --wind 0-15``) draws for each run a
current speed uniform in its range (fraction of the design speed) flowing towards a direction uniform in
[-180°, 180°), and a true wind speed uniform in its range (m/s) coming from a direction uniform in [-180°, 180°).
The values are the table parameters :data:`ENV_COLUMNS` (:mod:`mmg_casadi.params`), recorded per run in
``runs.csv``.

The draw depends only on ``(environment, run, base_seed)``, not on the method, so every method meets the same
disturbance in the same run. It uses its own generator, ``default_rng(SeedSequence([base_seed, environment, run,
STREAM]))``, separate from the scenario sampler's ``SeedSequence([base_seed, environment, run])``
(:mod:`mmg_casadi.montecarlo.sampling`): the sampled encounters are unchanged, so a disturbed study pairs run by run with a
calm one. The four uniforms are always drawn in the order current speed, current direction, wind speed, wind
direction, so adding a wind range leaves the current of every run unchanged.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from mmg_casadi.errors import InputError
from mmg_casadi.readers import is_finite
from mmg_casadi.params import PARAMETERS

ENV_COLUMNS: tuple[str, ...] = ("current_speed", "current_direction_deg", "wind_speed", "wind_direction_deg")
"""The table parameters a disturbance sets (and the ``runs.csv`` columns that record them)."""

STREAM = 0x656E76
"""Last word of the disturbance generator's seed sequence (``"env"`` in ASCII), separating it from the scenario
sampler's."""

_RANGE_PARAM = {"current": "current_speed", "wind": "wind_speed"}


def _check_range(field: str, value) -> tuple[float, float] | None:
    """``value`` as ``(low, high)`` within the bounds of its table parameter, or None."""
    if value is None:
        return None
    p = PARAMETERS[_RANGE_PARAM[field]]
    allowed = f"(low, high) with {p.low:g} <= low <= high <= {p.high:g} {p.unit}"
    ok = isinstance(value, (tuple, list)) and len(value) == 2 and all(is_finite(v) for v in value)
    if not ok or not p.low <= value[0] <= value[1] <= p.high:
        raise InputError(field, allowed, value)
    return float(value[0]), float(value[1])


@dataclass(frozen=True)
class DisturbanceRanges:
    """Ranges of the per-run disturbance of a study.

    Parameters
    ----------
    current : (float, float), optional
        Current speed range, fractions of the design speed in [0, 1]; ``None``: no current.
    wind : (float, float), optional
        True wind speed range in m/s, in [0, 60]; ``None``: no wind.

    Examples
    --------
    >>> DisturbanceRanges(current=(0, 0.1)).to_dict()
    {'current': [0.0, 0.1], 'wind': None}
    >>> DisturbanceRanges().active
    False
    >>> DisturbanceRanges(wind=(20, 10))
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.InputError: wind: expected (low, high) with 0 <= low <= high <= 60 m/s, got (20, 10)
    """

    current: tuple[float, float] | None = None
    wind: tuple[float, float] | None = None

    def __post_init__(self):
        object.__setattr__(self, "current", _check_range("current", self.current))
        object.__setattr__(self, "wind", _check_range("wind", self.wind))

    @property
    def active(self) -> bool:
        """Whether any range is given."""
        return self.current is not None or self.wind is not None

    def to_dict(self) -> dict:
        """``{"current": [low, high] or None, "wind": ...}`` as ``study.json`` and ``metrics.json`` record it.

        Returns
        -------
        dict
            ``"current"`` and ``"wind"``: ``[low, high]`` (U_des units) or None.
        """
        return {k: None if v is None else list(v) for k, v in (("current", self.current), ("wind", self.wind))}


def sample_disturbance(environment: int, run: int, base_seed: int, ranges: DisturbanceRanges) -> dict:
    """The disturbance of run ``run`` of ``environment``: the table parameters :data:`ENV_COLUMNS`.

    Parameters
    ----------
    environment, run, base_seed : int
        As for :func:`mmg_casadi.montecarlo.sampling.sample_scenario`.
    ranges : DisturbanceRanges
        Speed ranges; a quantity without a range is zero (speed and direction).

    Returns
    -------
    dict
        ``current_speed``, ``wind_speed`` (U_des units), ``current_direction_deg``, ``wind_direction_deg``
        (degrees in [-180, 180)).

    Examples
    --------
    >>> r = DisturbanceRanges(current=(0.0, 0.1))
    >>> d = sample_disturbance(5, 3, 0, r)
    >>> 0 <= d["current_speed"] <= 0.1, -180 <= d["current_direction_deg"] < 180, d["wind_speed"]
    (True, True, 0.0)
    >>> d == sample_disturbance(5, 3, 0, r)
    True
    """
    rng = np.random.default_rng(np.random.SeedSequence([int(base_seed), int(environment), int(run), STREAM]))
    u = rng.uniform(size=4)
    out = dict.fromkeys(ENV_COLUMNS, 0.0)
    if ranges.current is not None:
        lo, hi = ranges.current
        out["current_speed"] = float(lo + (hi - lo) * u[0])
        out["current_direction_deg"] = float(-180.0 + 360.0 * u[1])
    if ranges.wind is not None:
        lo, hi = ranges.wind
        out["wind_speed"] = float(lo + (hi - lo) * u[2])
        out["wind_direction_deg"] = float(-180.0 + 360.0 * u[3])
    return out


_RANGE = re.compile(r"^\s*([0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*(?:-\s*([0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*)?$")


def parse_range(text: str, field: str) -> tuple[float, float]:
    """A range ``"LOW-HIGH"`` (or one number ``"X"`` for ``X-X``) of the command line, checked for ``field``.

    Parameters
    ----------
    text : str
        ``"LOW-HIGH"`` or ``"X"`` (meaning ``X-X``), non-negative decimal numbers (exponents allowed, no sign;
        spaces around the numbers are ignored). Current speeds are fractions of the design speed in [0, 1],
        wind speeds m/s in [0, 60].
    field : str
        ``"current"`` or ``"wind"``: the range's table parameter (its bounds) and the name in error messages.

    Returns
    -------
    (float, float)
        ``(low, high)``; an :class:`~mmg_casadi.errors.InputError` if ``text`` is not a range or
        ``low <= high`` within the parameter's bounds does not hold.

    Examples
    --------
    >>> parse_range("0-0.1", "current"), parse_range("15", "wind")
    ((0.0, 0.1), (15.0, 15.0))
    >>> parse_range("0-2", "current")
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.InputError: current: expected (low, high) with 0 <= low <= high <= 1 U, got (0.0, 2.0)
    """
    m = _RANGE.match(text) if isinstance(text, str) else None
    if m is None:
        raise InputError(field, "a range LOW-HIGH of non-negative numbers, e.g. 0-0.1", text)
    lo = float(m.group(1))
    hi = float(m.group(2)) if m.group(2) is not None else lo
    return _check_range(field, (lo, hi))
