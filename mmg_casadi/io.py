"""Small file helpers shared by the runners and the CLI: JSON with numpy values and NaN as null, atomically.

Examples
--------
>>> json_safe({"a": float("nan"), "b": [1.0, float("inf")]})
{'a': None, 'b': [1.0, None]}
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import secrets
import shutil
import tempfile
import tomllib
from pathlib import Path

import numpy as np

from mmg_casadi.errors import InputError


def json_safe(obj):
    """``obj`` with numpy scalars and arrays as Python values and non-finite floats as ``None``.

    Parameters
    ----------
    obj : object
        Nested dicts, lists, tuples, numbers, strings, numpy values.

    Returns
    -------
    object
        A copy with dicts, lists (for lists, tuples and arrays), Python numbers and None for non-finite floats.
    """
    if isinstance(obj, dict):
        return {k: json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return json_safe(obj.tolist())
    if isinstance(obj, np.bool_):
        return bool(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        return float(obj) if math.isfinite(obj) else None
    return obj


def write_json(path, obj) -> Path:
    """Write ``obj`` (made :func:`json_safe`) as indented JSON atomically (temporary file, then rename).

    Parameters
    ----------
    path : str or Path
        Destination; its directory is created.
    obj : object
        What to write.

    Returns
    -------
    pathlib.Path
        The path written.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(path.suffix + ".tmp")
    tmp.write_text(json.dumps(json_safe(obj), indent=2))
    tmp.replace(path)
    return path


def read_toml(path, what: str, cls=InputError) -> dict:
    """The TOML file ``path`` parsed, or one ``cls`` error: a missing or unreadable file (field: the path), text
    that is not UTF-8 or not valid TOML, arrays nested too deep included (field ``"toml"``).

    Parameters
    ----------
    path : str or Path
        The file.
    what : str
        What the file is, for the message (``"scenario"`` gives "an existing, readable scenario file").
    cls : type
        Error type raised (:class:`~mmg_casadi.errors.InputError` or a subclass).

    Returns
    -------
    dict
        The parsed TOML document.

    Examples
    --------
    >>> read_toml("missing.toml", "scenario")
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.InputError: missing.toml: expected an existing, readable scenario file, got 'No such file or directory'
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as err:
        raise cls(str(path), f"an existing, readable {what} file", err.strerror or str(err)) from None
    except UnicodeDecodeError as err:
        raise cls("toml", f"UTF-8 text in {path}", str(err)) from None
    try:
        return tomllib.loads(text)
    except (tomllib.TOMLDecodeError, RecursionError) as err:  # RecursionError: arrays nested too deep
        raise cls("toml", f"valid TOML in {path}", str(err)) from None


def write_text(path, text: str) -> Path:
    """Write ``text`` atomically (temporary file, then rename); the directory is created.

    Parameters
    ----------
    path : str or Path
        Destination.
    text : str
        UTF-8 text.

    Returns
    -------
    pathlib.Path
        The path written.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(path.suffix + ".tmp")
    tmp.write_text(text, encoding="utf-8")
    tmp.replace(path)
    return path


def check_output(path, *, kind: str = "dir", field: str = "--out") -> Path:
    """Refuse an output path that cannot be written, before any work: a probe file is created in its
    directory (and the missing directories on the way), then everything the probe made is removed.

    Parameters
    ----------
    path : str or Path
        The output directory (``kind="dir"``) or file (``kind="file"``; written atomically through
        ``path + ".tmp"``, as :func:`write_text` does).
    kind : {"dir", "file"}
        What ``path`` names.
    field : str, default '--out'
        Name of the input field, used in the error message.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    InputError
        ``path`` is a file where a directory is wanted (or the reverse), a parent is a file, or the
        directory cannot be created or written (read-only file system, no permission, name too long, ...).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> check_output(d / "new" / "run") == d / "new" / "run", sorted(d.iterdir())
    (True, [])
    >>> (d / "f").write_text("x")
    1
    >>> check_output(d / "f")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.InputError: --out: expected a directory (or a new path), not an existing file, got '...f'
    """
    if kind not in ("dir", "file"):
        raise ValueError(f"kind must be 'dir' or 'file', not {kind!r}")
    path = Path(path)
    if "\0" in str(path):  # pathlib's is_dir() and exists() answer False for it; open() raises ValueError
        raise InputError(field, "a valid path (no NUL character)", str(path))
    created: list[Path] = []
    try:
        if kind == "dir":
            if path.exists() and not path.is_dir():
                raise InputError(field, "a directory (or a new path), not an existing file", str(path))
            directory = path
        else:
            for p in (path, path.with_name(path.name + ".tmp")):
                if p.is_dir():
                    raise InputError(field, "a file name, not an existing directory" + (f" ({p})" if p != path else ""),
                                     str(path))
            directory = path.parent
        missing = []
        d = directory
        while not d.is_dir():
            if d.exists() or d.is_symlink():
                raise InputError(field, f"a path in directories only ({d} is a file or a broken link)", str(path))
            missing.append(d)
            d = d.parent
        for d in reversed(missing):
            d.mkdir()
            created.append(d)
        fd, probe = tempfile.mkstemp(dir=directory, prefix=".mmg-casadi-probe-")
        os.close(fd)
        os.unlink(probe)
    except InputError:
        raise
    except OSError as err:
        what = "directory" if kind == "dir" else "file"
        raise InputError(field, f"a writable {what} ({err.strerror or err})", str(path)) from None
    except ValueError as err:
        raise InputError(field, f"a valid path ({err})", str(path)) from None
    finally:
        for d in reversed(created):
            try:
                d.rmdir()
            except OSError:
                pass
    return path


@contextlib.contextmanager
def staged_directory(out):
    """Write a directory's files all or none: yield a fresh hidden sibling folder of ``out`` to write into, then
    move its files into ``out`` when the block ends normally; on any exception (Ctrl-C, SIGTERM raised as
    :class:`KeyboardInterrupt`, a full disk) remove the folder and re-raise, leaving ``out`` as it was.

    A new or empty ``out`` is replaced by the folder in one rename; into an ``out`` that holds files already, each
    file is moved by an atomic :func:`os.replace`, so no file of ``out`` is ever partly written.

    Parameters
    ----------
    out : str or Path
        The output directory (its parent is created).

    Yields
    ------
    Path
        The folder to write the files into (``<parent>/.<name>.tmp-<pid>-<random>``).

    Examples
    --------
    >>> import pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> with staged_directory(d / "run") as tmp:
    ...     _ = (tmp / "a.txt").write_text("a")
    >>> sorted(p.name for p in d.iterdir()), (d / "run" / "a.txt").read_text()
    (['run'], 'a')
    >>> try:
    ...     with staged_directory(d / "run") as tmp:
    ...         _ = (tmp / "a.txt").write_text("b")
    ...         raise KeyboardInterrupt
    ... except KeyboardInterrupt:
    ...     pass
    >>> sorted(p.name for p in d.iterdir()), (d / "run" / "a.txt").read_text()
    (['run'], 'a')
    """
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.parent / f".{out.name}.tmp-{os.getpid()}-{secrets.token_hex(4)}"
    tmp.mkdir()  # mkdir, not mkdtemp: the folder gets the usual permissions (umask), as out would
    try:
        yield tmp
        try:
            os.rename(tmp, out)  # out is new or an empty directory: all files appear at once
        except OSError:
            out.mkdir(exist_ok=True)
            for f in sorted(tmp.iterdir()):
                os.replace(f, out / f.name)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
