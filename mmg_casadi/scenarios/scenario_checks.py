"""Checks of the values of a scenario file (tables, numbers, ranges, points, names, polygons, static data), each
failure one :class:`~mmg_casadi.errors.ScenarioError` naming the field and the allowed values; used by
:func:`mmg_casadi.scenarios.scenario.scenario_from_dict`.

Every position (start, waypoint, obstacle, wall and land point) is a finite number within
:data:`~mmg_casadi.limits.MAX_COORDINATE` ship lengths of the origin; every name passes
:func:`mmg_casadi.readers.check_name`; a land polygon is a valid polygon (:func:`valid_polygon`: no edge crosses
another, by the geometry library's validity check).

Examples
--------
>>> _point([1e300, 0], "ships[0].start")
Traceback (most recent call last):
...
mmg_casadi.errors.ScenarioError: ships[0].start: expected a point [x, y] of two finite numbers within 10000 ship lengths of the origin (MAX_COORDINATE), got [1e+300, 0]
"""

from __future__ import annotations

import datetime
import json
import math

from mmg_casadi.errors import ScenarioError, check_range
from mmg_casadi.limits import MAX_COORDINATE
from mmg_casadi.readers import check_name

_POINT = f"a point [x, y] of two finite numbers within {MAX_COORDINATE:g} ship lengths of the origin (MAX_COORDINATE)"


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


def _name(value, key: str) -> str:
    """``value`` as a name (:func:`mmg_casadi.readers.check_name`: 1 to 64 characters, no control characters)."""
    return check_name(value, key, ScenarioError)


def valid_polygon(points, key: str) -> None:
    """Refuse a polygon whose edges cross or touch each other (not a simple polygon), by the geometry library's
    validity check (``shapely``, the OGC simple-features rules), with the library's reason and place.

    Parameters
    ----------
    points : sequence of (float, float)
        The polygon's points, not closed.
    key : str
        Dotted name of the points, named in the error.

    Examples
    --------
    >>> valid_polygon([(0, 0), (0, 4), (4, 4), (4, 0)], "land[0].points")
    >>> valid_polygon([(0, 0), (4, 4), (0, 4), (4, 0)], "land[0].points")
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.ScenarioError: land[0].points: expected a simple polygon (no edge crossing or touching another), got 'Self-intersection[2 2]'
    """
    import shapely  # about 0.3 s to import: only where land is read
    from shapely.validation import explain_validity
    poly = shapely.Polygon(points)
    if not poly.is_valid:
        raise ScenarioError(key, "a simple polygon (no edge crossing or touching another)", explain_validity(poly))


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
    """``value`` as a point: a list of two finite numbers within :data:`~mmg_casadi.limits.MAX_COORDINATE`."""
    if not isinstance(value, (list, tuple)) or len(value) != 2 or \
            not all(_is_number(v) and abs(v) <= MAX_COORDINATE for v in value):
        raise ScenarioError(key, _POINT, value)
    return _as_point(value)


def _points(value, key: str, min_count: int) -> tuple[tuple[float, float], ...]:
    """``value`` as a tuple of at least ``min_count`` points."""
    if not isinstance(value, (list, tuple)) or len(value) < min_count:
        noun = "point" if min_count == 1 else "points"
        raise ScenarioError(key, f"a list of at least {min_count} {noun} [[x, y], ...] (ship lengths)", value)
    return tuple(_point(p, f"{key}[{j}]") for j, p in enumerate(value))


_METADATA = "a string, a finite number, true or false, an array or a table of these (values with a JSON form)"
_INT64 = (-(2 ** 63), 2 ** 63 - 1)


def check_metadata(value, key: str, *, drop_nulls: bool = False) -> dict:
    """``value`` as a metadata table: nested tables and arrays of strings, finite numbers and booleans.

    The values that both a scenario file (TOML) and a traffic situation (JSON) can hold: no null, datetime or
    non-finite number, integers in the 64-bit range of TOML.

    Parameters
    ----------
    value : dict
        The table to check (a :attr:`ShipSpec.metadata`).
    key : str
        Dotted name of the table, e.g. ``"ships[1].metadata"``; an error names the offending entry under it.
    drop_nulls : bool, optional
        Leave out table entries whose value is None (JSON null) instead of refusing them.

    Returns
    -------
    dict
        A deep copy of ``value``.

    Examples
    --------
    >>> check_metadata({"mmsi": 257000123, "dimensions": {"height": 8.0}}, "ships[0].metadata")
    {'mmsi': 257000123, 'dimensions': {'height': 8.0}}
    >>> check_metadata({"sogMax": float("nan")}, "ships[0].metadata")
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.ScenarioError: ships[0].metadata.sogMax: expected a string, a finite number, true or false, an array or a table of these (values with a JSON form), got nan
    """
    def plain(v, k):
        if isinstance(v, dict):
            out = {}
            for name, item in v.items():
                if not isinstance(name, str):
                    raise ScenarioError(k, "a table with string keys", name)
                if item is not None or not drop_nulls:
                    out[name] = plain(item, f"{k}.{toml_key(name)}")
            return out
        if isinstance(v, list):
            return [plain(item, f"{k}[{j}]") for j, item in enumerate(v)]
        if isinstance(v, (str, bool)):
            return v
        if isinstance(v, int) and _INT64[0] <= v <= _INT64[1]:
            return v
        if isinstance(v, float) and math.isfinite(v):
            return v
        shown = v.isoformat() if isinstance(v, (datetime.date, datetime.time)) else v
        raise ScenarioError(k, _METADATA, shown)

    if not isinstance(value, dict):
        raise ScenarioError(key, "a table of static data", value)
    try:
        return plain(value, key)
    except RecursionError:
        raise ScenarioError(key, "tables and arrays nested less deeply (Python's recursion limit)") from None
