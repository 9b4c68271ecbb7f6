"""Validated entries of a scenario file: numbers, ranges, strings, points and tables, each error naming its dotted key.

:mod:`mmg_casadi.scenarios.scenario` reads a file with these; every malformed entry raises one
:class:`~mmg_casadi.errors.ScenarioError` whose ``field`` is the dotted key and whose message lists the allowed
values.
"""

from __future__ import annotations

import json
import math

from mmg_casadi.errors import ScenarioError, check_range

_POINT = "a point [x, y] of two finite numbers (ship lengths)"


def _as_point(p) -> tuple[float, float]:
    """``p`` as a tuple of two floats."""
    return (float(p[0]), float(p[1]))


def _as_points(ps) -> tuple[tuple[float, float], ...]:
    """``ps`` as a tuple of points."""
    return tuple(_as_point(p) for p in ps)


def toml_key(k: str) -> str:
    r"""``k`` as written in a dotted TOML key: bare if it may be, else a quoted string (so it fits on one line).

    Parameters
    ----------
    k : str
        One key (one part of a dotted key). It stays bare if it is non-empty and only ASCII letters, digits,
        ``_`` and ``-``; otherwise it becomes a JSON-escaped (hence valid TOML basic) string in double quotes.

    Returns
    -------
    str
        The key as TOML text.

    Examples
    --------
    >>> toml_key("speed"), toml_key(""), toml_key("a\nb")
    ('speed', '""', '"a\\nb"')
    """
    if k and all(c.isascii() and (c.isalnum() or c in "_-") for c in k):
        return k
    return json.dumps(k)


def _table(value, key: str, allowed_keys) -> dict:
    """``value`` as a table whose keys all lie in ``allowed_keys`` (``key`` is its dotted name, "" for the root)."""
    if not isinstance(value, dict):
        raise ScenarioError(key or "scenario", "a table", value)
    for k in value:
        if k not in allowed_keys:
            name = toml_key(k)
            raise ScenarioError(f"{key}.{name}" if key else name, f"a known key (one of: {', '.join(allowed_keys)})")
    return value


def _tables(d: dict, key: str, allowed_keys, *, required: bool) -> list[dict]:
    """The array of tables ``d[key]`` (empty if absent and not ``required``)."""
    if key not in d:
        if required:
            raise ScenarioError(key, f"at least one [[{key}]] table (required)")
        return []
    value = d[key]
    if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
        raise ScenarioError(key, f"an array of tables [[{key}]]", value)
    if required and not value:
        raise ScenarioError(key, f"at least one [[{key}]] table (required)", value)
    return [_table(v, f"{key}[{i}]", allowed_keys) for i, v in enumerate(value)]


def _required(d: dict, key: str, prefix: str, allowed: str):
    """``d[key]``, or a ScenarioError naming ``prefix.key`` if it is missing."""
    if key not in d:
        raise ScenarioError(f"{prefix}.{key}", f"{allowed} (a required key, missing here)")
    return d[key]


def _is_number(value) -> bool:
    """True for a finite int or float (not a bool; an int too large for a float is not finite)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return False
    try:
        return math.isfinite(value)
    except OverflowError:
        return False


def _number(value, key: str, allowed: str = "a finite number") -> float:
    """``value`` as a float if it is a finite number."""
    if not _is_number(value):
        raise ScenarioError(key, allowed, value)
    return float(value)


def _range_text(key: str, low, high, **kw) -> str:
    """The ``allowed`` text :func:`check_range` gives for this interval."""
    try:
        check_range(key, math.nan, low, high, cls=ScenarioError, **kw)
    except ScenarioError as err:
        return err.allowed
    raise AssertionError("check_range accepted nan")


def _ranged(value, key: str, low=None, high=None, **kw) -> float:
    """``value`` as a float if it is a finite number (not a bool or a string) in the given interval."""
    if not _is_number(value):
        raise ScenarioError(key, _range_text(key, low, high, **kw), value)
    return check_range(key, value, low, high, cls=ScenarioError, **kw)


def _string(value, key: str, allowed=None) -> str:
    """``value`` if it is a (non-empty) string, optionally one of ``allowed``."""
    if allowed is not None:
        if not isinstance(value, str) or value not in allowed:
            raise ScenarioError(key, f"one of: {', '.join(allowed)}", value)
        return value
    if not isinstance(value, str) or not value:
        raise ScenarioError(key, "a non-empty string", value)
    return value


def _point(value, key: str) -> tuple[float, float]:
    """``value`` as a point: a list of two finite numbers."""
    if not isinstance(value, (list, tuple)) or len(value) != 2 or not all(_is_number(v) for v in value):
        raise ScenarioError(key, _POINT, value)
    return _as_point(value)


def _points(value, key: str, min_count: int) -> tuple[tuple[float, float], ...]:
    """``value`` as a tuple of at least ``min_count`` points."""
    if not isinstance(value, (list, tuple)) or len(value) < min_count:
        noun = "point" if min_count == 1 else "points"
        raise ScenarioError(key, f"a list of at least {min_count} {noun} [[x, y], ...] (ship lengths)", value)
    return tuple(_point(p, f"{key}[{j}]") for j, p in enumerate(value))
