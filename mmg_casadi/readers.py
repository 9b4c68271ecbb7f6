"""Reading the files a user gives, checked before any work: size, encoding, nesting, names.

Every reader of the toolkit (scenario and vessel TOML, parameter files, generation descriptions, GeoJSON land,
maritime-schema JSON, AIS and track CSV, identification data) reads through these functions, so a file is
refused with one :class:`~mmg_casadi.errors.InputError` (or the subclass the caller names) instead of a traceback
or a runaway allocation:

* **size** – at most :data:`MAX_BYTES` ``[kind]`` bytes, counted while reading (:func:`read_bytes` stops at the
  limit; :func:`csv_rows` streams the rows and stops at the byte or row limit), so a file far over the limit
  costs no more memory than the limit;
* **encoding** – UTF-8 (a leading byte-order mark is dropped), the offset of the first bad byte named;
* **nesting** – arrays and tables nested at most :data:`MAX_NESTING` deep (:func:`nesting_depth`);
* **numbers** – JSON's ``NaN`` and ``Infinity`` are refused (:func:`load_json`), a number is finite and within a
  stated range (:func:`finite`);
* **names** – a name (of a ship, a vessel, an MMSI) has 1 to :data:`MAX_NAME_LENGTH` characters and no control,
  format or unassigned code point (:func:`check_name`): every output format can hold it (a figure escapes its
  ``$``, :func:`mmg_casadi.plotting.escape_text`; a CSV quotes it and keeps it from reading as a formula,
  :func:`mmg_casadi.io.csv_cell`).

Examples
--------
>>> nesting_depth({"a": [1, [2, {"b": 3}]]})
4
>>> check_name("own ship", "ships[0].name")
'own ship'
>>> check_name("a\\x00b", "ships[0].name")
Traceback (most recent call last):
...
mmg_casadi.errors.InputError: ships[0].name: expected a name of 1 to 64 characters without control characters, got 'a\\x00b'
"""

from __future__ import annotations

import csv
import io
import json
import math
import tomllib
import unicodedata
from pathlib import Path

import numpy as np

from mmg_casadi.errors import InputError

MB = 1 << 20
MAX_BYTES = {
    "scenario": 32 * MB, "vessel": 1 * MB, "parameter": 1 * MB, "description": 1 * MB,
    "GeoJSON": 64 * MB, "traffic situation": 32 * MB, "AIS": 128 * MB, "track": 16 * MB,
    "identification data": 64 * MB, "generation record": 64 * MB,
}
"""Largest file of each kind [bytes]. A scenario of MAX_SHIPS ships with waypoints and MAX_OBSTACLES obstacles
takes about 1 MB of TOML; a track of MAX_TRACK_POINTS rows under 1 MB; a GeoJSON coast of a chart a few MB; an AIS
file of :data:`MAX_AIS_REPORTS` reports about 70 MB. The limits leave room above those and stop a wrong file
(a video, /dev/zero) before it costs memory."""
MAX_NESTING = 32
"""Deepest nesting of arrays and tables in a JSON or TOML file (the formats need 6: a MultiPolygon's coordinates
in a FeatureCollection)."""
MAX_NAME_LENGTH = 64
"""Longest name of a ship, vessel or MMSI [characters] (AIS names have 20; every figure legend holds 64)."""
MAX_AIS_REPORTS = 1_000_000
"""Most reports of an AIS file (rows of a CSV or objects of a JSON file)."""
_REFUSED_CATEGORIES = ("Cc", "Cf", "Cs", "Co", "Cn", "Zl", "Zp")
"""Unicode categories a name may not contain: control, format (e.g. right-to-left overrides), surrogate, private
use, unassigned, line and paragraph separators."""


def _limit(kind: str) -> int:
    return MAX_BYTES[kind]


def _a(kind: str) -> str:
    """``kind`` with its indefinite article ("a scenario", "an AIS")."""
    return ("an " if kind[:1] in "aeiouAEIOU" else "a ") + kind


def _size_text(n: int) -> str:
    return f"{n / MB:g} MB" if n >= MB else f"{n} bytes"


def read_bytes(path, kind: str, field: str | None = None, cls=InputError) -> bytes:
    """The bytes of the ``kind`` file ``path``, at most :data:`MAX_BYTES` ``[kind]`` of them (reading stops there).

    Parameters
    ----------
    path : str or Path
        The file.
    kind : str
        A key of :data:`MAX_BYTES` (also the file's description in the message).
    field : str, optional
        The field named in an error (default the path).
    cls : type, default InputError
        Error class raised.

    Returns
    -------
    bytes
        The file's content.
    """
    path = Path(path)
    field = str(path) if field is None else field
    limit = _limit(kind)
    try:
        if path.is_dir():
            raise IsADirectoryError(21, "Is a directory")
        with open(path, "rb") as fh:
            data = fh.read(limit + 1)
    except OSError as err:
        raise cls(field, f"an existing, readable {kind} file", f"{path} ({err.strerror or err})") from None
    except ValueError as err:  # e.g. a NUL in the path
        raise cls(field, f"an existing, readable {kind} file", f"{path} ({err})") from None
    if len(data) > limit:
        raise cls(field, f"{_a(kind)} file of at most {_size_text(limit)} (MAX_BYTES)", f"{path}: larger")
    return data


def decode(data: bytes, path, kind: str, field: str | None = None, cls=InputError) -> str:
    """``data`` decoded as UTF-8 (a leading byte-order mark dropped), or an error naming the first bad byte.

    Parameters
    ----------
    data : bytes
        The file's bytes.
    path : str or Path
        The file (for the message).
    kind : str
        What the file is.
    field : str, optional
        The field named in an error (default the path).
    cls : type, default InputError
        Error class raised.

    Returns
    -------
    str
        The text.

    Examples
    --------
    >>> decode("ö".encode(), "a.toml", "scenario")
    'ö'
    >>> decode(b"ab\\xff", "a.toml", "scenario")
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.InputError: a.toml: expected a scenario file in UTF-8, got 'byte 0xff at offset 2'
    """
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as err:
        raise cls(str(path) if field is None else field, f"{_a(kind)} file in UTF-8",
                  f"byte 0x{data[err.start]:02x} at offset {err.start}") from None
    return text[1:] if text.startswith("\ufeff") else text


def read_text(path, kind: str, field: str | None = None, cls=InputError) -> str:
    """The UTF-8 text of the ``kind`` file ``path`` (:func:`read_bytes`, :func:`decode`).

    Parameters
    ----------
    path : str or Path
        The file.
    kind : str
        A key of :data:`MAX_BYTES`.
    field : str, optional
        The field named in an error (default the path).
    cls : type, default InputError
        Error class raised.

    Returns
    -------
    str
        The text.
    """
    return decode(read_bytes(path, kind, field, cls), path, kind, field, cls)


def nesting_depth(value) -> int:
    """How deeply lists and dicts are nested in ``value`` (a scalar: 0), without recursion.

    Parameters
    ----------
    value : object
        A parsed JSON or TOML value.

    Returns
    -------
    int
        The depth.
    """
    deepest, todo = 0, [(value, 1)]
    while todo:
        v, d = todo.pop()
        if isinstance(v, dict):
            v = list(v.values())
        elif not isinstance(v, list):
            continue
        deepest = max(deepest, d)
        todo.extend((x, d + 1) for x in v if isinstance(x, (list, dict)))
    return deepest


def _check_depth(value, path, kind: str, field: str | None, cls) -> None:
    if nesting_depth(value) > MAX_NESTING:
        raise cls(str(path) if field is None else field, f"{_a(kind)} file nested at most {MAX_NESTING} levels deep "
                  "(MAX_NESTING)", "deeper")


def _no_constant(name: str):
    raise ValueError(f"{name} is not a number JSON allows")


def load_json(path, kind: str, field: str | None = None, cls=InputError):
    """The parsed JSON file ``path``: limited in size, UTF-8, nested at most :data:`MAX_NESTING` deep, without
    ``NaN``/``Infinity``.

    Parameters
    ----------
    path : str or Path
        The file.
    kind : str
        A key of :data:`MAX_BYTES`.
    field : str, optional
        The field named in an error (default the path).
    cls : type, default InputError
        Error class raised.

    Returns
    -------
    object
        The parsed value.
    """
    text = read_text(path, kind, field, cls)
    where = str(path) if field is None else field
    try:
        value = json.loads(text, parse_constant=_no_constant)
    except RecursionError:
        raise cls(where, f"{_a(kind)} file nested at most {MAX_NESTING} levels deep (MAX_NESTING)", "deeper") from None
    except json.JSONDecodeError as err:
        raise cls(where, f"{_a(kind)} file of valid JSON", f"{err.msg} at line {err.lineno}") from None
    except ValueError as err:  # NaN, Infinity; an integer of more than 4300 digits
        raise cls(where, f"{_a(kind)} file of valid JSON", str(err)) from None
    _check_depth(value, path, kind, field, cls)
    try:  # a "\\ud800" escape decodes to a lone surrogate, which no output file can hold
        json.dumps(value, ensure_ascii=False).encode("utf-8")
    except UnicodeEncodeError as err:
        raise cls(where, f"{_a(kind)} file of Unicode text (no unpaired surrogate escape)",
                  err.object[err.start:err.end].encode("unicode_escape").decode()) from None
    return value


def loads_toml(text: str, path, kind: str, field: str | None = None, cls=InputError) -> dict:
    """``text`` parsed as TOML, nested at most :data:`MAX_NESTING` deep.

    Parameters
    ----------
    text : str
        The TOML text.
    path : str or Path
        Its file (for the message).
    kind : str
        What the file is.
    field : str, optional
        The field named in an error (default ``"toml"``).
    cls : type, default InputError
        Error class raised.

    Returns
    -------
    dict
        The parsed document.
    """
    where = "toml" if field is None else field
    try:
        value = tomllib.loads(text)
    except RecursionError:
        raise cls(where, f"{_a(kind)} file nested at most {MAX_NESTING} levels deep (MAX_NESTING) in {path}",
                  "deeper") from None
    except (tomllib.TOMLDecodeError, ValueError) as err:
        raise cls(where, f"valid TOML in {path}", str(err)) from None
    _check_depth(value, path, kind, field, cls)
    return value


def load_toml(path, kind: str, field: str | None = None, cls=InputError) -> dict:
    """The parsed TOML file ``path``: limited in size, UTF-8, nested at most :data:`MAX_NESTING` deep.

    Parameters
    ----------
    path : str or Path
        The file.
    kind : str
        A key of :data:`MAX_BYTES`.
    field : str, optional
        The field named in a parse error (default ``"toml"``; a missing or unreadable file names the path).
    cls : type, default InputError
        Error class raised.

    Returns
    -------
    dict
        The parsed document.
    """
    return loads_toml(read_text(path, kind, None, cls), path, kind, field, cls)


class _Counted(io.RawIOBase):
    """A binary file that refuses to be read past ``limit`` bytes (``OverflowError``)."""

    def __init__(self, fh, limit: int):
        self.fh, self.limit, self.count = fh, limit, 0

    def readable(self) -> bool:
        return True

    def readinto(self, b) -> int:
        n = self.fh.readinto(b)
        self.count += n or 0
        if self.count > self.limit:
            raise OverflowError
        return n


def csv_rows(path, kind: str, *, max_rows: int, field: str | None = None, cls=InputError):
    """Stream the rows of the ``kind`` CSV file ``path`` as dicts keyed by its header, with their line numbers.

    Reading stops (with ``cls``) as soon as the file passes :data:`MAX_BYTES` ``[kind]`` bytes or ``max_rows``
    rows, a byte is not UTF-8 or a line is not CSV: memory stays bounded by what the caller keeps of the rows.

    Parameters
    ----------
    path : str or Path
        The file.
    kind : str
        A key of :data:`MAX_BYTES`.
    max_rows : int
        Most data rows.
    field : str, optional
        The field named in an error (default the path).
    cls : type, default InputError
        Error class raised.

    Yields
    ------
    (int, dict)
        The row's line number (the header is line 1) and its cells by column name (a missing cell is None).
    """
    path = Path(path)
    where = str(path) if field is None else field
    limit = _limit(kind)
    try:
        if path.is_dir():
            raise IsADirectoryError(21, "Is a directory")
        raw = open(path, "rb")
    except (OSError, ValueError) as err:
        raise cls(where, f"an existing, readable {kind} CSV file", f"{path} ({getattr(err, 'strerror', None) or err})") \
            from None
    counted = _Counted(raw, limit)
    text = io.TextIOWrapper(io.BufferedReader(counted, 1 << 16), encoding="utf-8-sig", errors="strict", newline="")
    try:
        reader = csv.DictReader(text)
        for k, row in enumerate(reader):
            if k >= max_rows:
                raise cls(where, f"{_a(kind)} file of at most {max_rows} rows", f"{path}: more")
            yield reader.line_num, row
    except OverflowError:
        raise cls(where, f"{_a(kind)} file of at most {_size_text(limit)} (MAX_BYTES)", f"{path}: larger") from None
    except UnicodeDecodeError as err:
        raise cls(where, f"{_a(kind)} file in UTF-8", f"{path}: byte 0x{err.object[err.start]:02x} near offset "
                  f"{counted.count - len(err.object) + err.start}") from None
    except csv.Error as err:
        raise cls(where, f"{_a(kind)} file of valid CSV", f"{path}: {err}") from None
    finally:
        text.close()


def check_name(value, field: str, cls=InputError) -> str:
    """``value`` if it is a name of 1 to :data:`MAX_NAME_LENGTH` characters without control, format, surrogate,
    private-use, unassigned or line-breaking code points; else ``cls``.

    Parameters
    ----------
    value : object
        The name.
    field : str
        The field named in an error.
    cls : type, default InputError
        Error class raised.

    Returns
    -------
    str
        ``value``.
    """
    allowed = f"a name of 1 to {MAX_NAME_LENGTH} characters without control characters"
    if not isinstance(value, str) or not 1 <= len(value) <= MAX_NAME_LENGTH:
        got = value if not isinstance(value, str) or len(value) <= 2 * MAX_NAME_LENGTH else \
            f"{value[:MAX_NAME_LENGTH]}... ({len(value)} characters)"
        raise cls(field, allowed, got)
    if any(unicodedata.category(c) in _REFUSED_CATEGORIES for c in value):
        raise cls(field, allowed, value)
    return value


def is_finite(value) -> bool:
    """Whether ``value`` is a finite real number (not a bool; an int too large for a float is not finite).

    Parameters
    ----------
    value : object
        The value.

    Returns
    -------
    bool
        True for a finite int or float (NumPy's included).

    Examples
    --------
    >>> is_finite(2.5), is_finite(10 ** 400), is_finite(float("nan")), is_finite(True), is_finite("1")
    (True, False, False, False, False)
    """
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        return False
    try:
        return math.isfinite(value)
    except OverflowError:
        return False


def finite(value, field: str, low: float, high: float, cls=InputError, unit: str = "") -> float:
    """``value`` as a float if it is a finite number (not a bool or a string) in ``[low, high]``; else ``cls``.

    Parameters
    ----------
    value : object
        The value.
    field : str
        The field named in an error.
    low, high : float
        The closed interval.
    cls : type, default InputError
        Error class raised.
    unit : str, optional
        Unit named in the message.

    Returns
    -------
    float
        The value.

    Examples
    --------
    >>> finite(3, "x", -10, 10)
    3.0
    >>> finite(1e300, "x", -10, 10, unit="L")
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.InputError: x: expected a finite number in [-10, 10] L, got 1e+300
    """
    ok = not isinstance(value, bool) and isinstance(value, (int, float))
    if ok:
        try:
            x = float(value)
        except OverflowError:  # an int too large for a float
            ok = False
        else:
            ok = math.isfinite(x) and low <= x <= high
    if not ok:
        raise cls(field, f"a finite number in [{low:g}, {high:g}]" + (f" {unit}" if unit else ""), value)
    return x

