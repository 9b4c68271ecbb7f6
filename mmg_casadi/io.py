"""Small file helpers shared by the runners and the CLI: every output file is written atomically.

A file is written under a temporary name in its own directory (:func:`atomic_path`: ``.<name>.tmp-<pid>-<random>``
with the same suffix) and renamed into place when it is complete (``os.replace``), so an interruption (Ctrl-C,
SIGTERM, a full disk) leaves either the old file or the complete new one, never a part; the temporary file is
removed when the writing fails. :func:`write_text`, :func:`write_json`, :func:`atomic_open` and
:func:`save_figure` do this for text, JSON, a file handle and a matplotlib figure; :class:`StagedFiles` writes a
set of files (a study's final outputs) and renames them together at the end, with the termination signals held
back for the renames. CSV cells that hold text go through :func:`csv_cell`, which keeps a spreadsheet from reading
a name as a formula.

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
import signal
import tempfile
import threading
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
    return write_text(path, json.dumps(json_safe(obj), indent=2))


def _temporary_name(path: Path) -> Path:
    """A fresh hidden name beside ``path`` with its suffix (``np.savez`` and ``savefig`` read the suffix)."""
    return path.with_name(f".{path.stem}.tmp-{os.getpid()}-{secrets.token_hex(4)}{path.suffix}")


@contextlib.contextmanager
def atomic_path(path):
    """Yield a temporary path beside ``path`` to write the file to; rename it to ``path`` when the block ends
    normally, remove it when the block raises (an interruption included), so ``path`` is never partly written.

    Parameters
    ----------
    path : str or Path
        Destination; its directory is created.

    Yields
    ------
    Path
        The temporary path (same directory, hidden name, same suffix).

    Examples
    --------
    >>> d = Path(tempfile.mkdtemp())
    >>> with atomic_path(d / "a.txt") as tmp:
    ...     _ = tmp.write_text("new")
    >>> try:
    ...     with atomic_path(d / "a.txt") as tmp:
    ...         _ = tmp.write_text("half")
    ...         raise KeyboardInterrupt
    ... except KeyboardInterrupt:
    ...     pass
    >>> [p.name for p in d.iterdir()], (d / "a.txt").read_text()
    (['a.txt'], 'new')
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = _temporary_name(path)
    try:
        yield tmp
        os.replace(tmp, path)
    finally:
        with contextlib.suppress(OSError):
            tmp.unlink()


@contextlib.contextmanager
def atomic_open(path, mode: str = "w", **kwargs):
    """``open`` a temporary file beside ``path`` (:func:`atomic_path`) and rename it to ``path`` when the block
    ends normally.

    Parameters
    ----------
    path : str or Path
        Destination.
    mode : str, default 'w'
        A writing mode (``"w"``, ``"wb"``).
    **kwargs
        Passed to :func:`open` (e.g. ``encoding="utf-8", newline=""`` for a CSV file).

    Yields
    ------
    file object
        The open temporary file.
    """
    with atomic_path(path) as tmp:
        with open(tmp, mode, **kwargs) as fh:
            yield fh


def save_figure(fig, path, **kwargs) -> Path:
    """``fig.savefig(path, **kwargs)`` through a temporary file (:func:`atomic_path`).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : str or Path
        Destination; the format is its suffix.
    **kwargs
        Passed to ``savefig`` (e.g. ``dpi``).

    Returns
    -------
    pathlib.Path
        The path written.
    """
    path = Path(path)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, **kwargs)
    return path


FORMULA_START = ("=", "+", "-", "@", "\t", "\r")
"""First characters with which a spreadsheet reads a cell as a formula (OWASP "CSV injection")."""


def csv_cell(text) -> str:
    """A text cell for a CSV file that a spreadsheet shows as text: one starting like a formula
    (:data:`FORMULA_START`) gets a leading apostrophe. Quoting (commas, quotes, newlines) is the ``csv`` module's.

    Parameters
    ----------
    text : object
        The cell's text (``str()`` is taken).

    Returns
    -------
    str
        The cell.

    Examples
    --------
    >>> csv_cell("own ship"), csv_cell("=HYPERLINK(1)"), csv_cell("-x")
    ('own ship', "'=HYPERLINK(1)", "'-x")
    """
    text = str(text)
    return "'" + text if text.startswith(FORMULA_START) else text


class StagedFiles:
    """Write a set of files under temporary names and rename them all into place at the end (:meth:`commit`),
    the last one given last; SIGINT, SIGTERM and SIGHUP are held back during the renames (recorded by a
    handler of their own, then raised again with :func:`signal.raise_signal` for the handler they had), so an
    interruption leaves every file of the set old or every file new, and one that arrives during the renames is
    acted on after them. Before :meth:`commit` (or if the block raises) the temporary files are
    removed and the old files left as they were.

    Use as a context manager: ``with StagedFiles() as st: write to st.path(final)``; the block's normal end
    commits.

    Examples
    --------
    >>> d = Path(tempfile.mkdtemp())
    >>> with StagedFiles() as st:
    ...     _ = st.path(d / "a.txt").write_text("a")
    ...     _ = st.path(d / "b.txt").write_text("b")
    >>> sorted(p.name for p in d.iterdir())
    ['a.txt', 'b.txt']
    """

    def __init__(self):
        self._pending: list[tuple[Path, Path]] = []
        self._remove: list[Path] = []

    def path(self, final) -> Path:
        """A temporary path to write ``final`` to (renamed to ``final`` by :meth:`commit`).

        Parameters
        ----------
        final : str or Path
            The file's final path (its directory is created).

        Returns
        -------
        Path
            The temporary path.
        """
        final = Path(final)
        final.parent.mkdir(parents=True, exist_ok=True)
        tmp = _temporary_name(final)
        self._pending.append((tmp, final))
        return tmp

    def remove(self, path) -> None:
        """Remove ``path`` at :meth:`commit` (after the renames), e.g. a file of an older set.

        Parameters
        ----------
        path : str or Path
            The file to remove.
        """
        self._remove.append(Path(path))

    def commit(self) -> None:
        """Rename every temporary file to its final name, in the order given, then remove the files
        :meth:`remove` named; termination signals are held back meanwhile (in the main thread)."""
        held = _hold_signals()
        try:
            for tmp, final in self._pending:
                os.replace(tmp, final)
            for p in self._remove:
                with contextlib.suppress(FileNotFoundError):
                    p.unlink()
        finally:
            self._pending, self._remove = [], []
            _release_signals(held)

    def discard(self) -> None:
        """Remove the temporary files not committed."""
        for tmp, _final in self._pending:
            with contextlib.suppress(OSError):
                tmp.unlink()
        self._pending, self._remove = [], []

    def __enter__(self):
        return self

    def __exit__(self, exc_type, *_exc):
        if exc_type is None:
            self.commit()
        else:
            self.discard()
        return False


_HELD = tuple(getattr(signal, n) for n in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, n))


def _hold_signals():
    """Record :data:`_HELD` signals instead of acting on them; returns what :func:`_release_signals` needs.

    A Python handler always runs in the main thread (whichever thread the signal was delivered to), so this
    holds them back whatever the other threads of the process (a pool's, a progress bar's) block."""
    if threading.current_thread() is not threading.main_thread():
        return None
    received: list[int] = []
    previous = {}
    for s in _HELD:
        h = signal.getsignal(s)
        if h is signal.SIG_IGN or h is None:  # ignored, or a handler not set from Python: left alone
            continue
        previous[s] = signal.signal(s, lambda signum, _frame: received.append(signum))
    return previous, received


def _release_signals(held) -> None:
    if held is None:
        return
    previous, received = held
    for s, h in previous.items():
        signal.signal(s, h)
    if received:
        signal.raise_signal(received[0])  # acted on now, by the handler it had (it may raise)


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
    from mmg_casadi.readers import MAX_BYTES, decode, loads_toml, read_bytes  # the one file reader
    path = Path(path)
    kind = what if what in MAX_BYTES else "scenario"
    try:
        with open(path, "rb"):
            pass
    except (OSError, ValueError) as err:
        raise cls(str(path), f"an existing, readable {what} file", getattr(err, "strerror", None) or str(err)) from None
    text = decode(read_bytes(path, kind, str(path), cls), path, what, "toml", cls)
    return loads_toml(text, path, what, "toml", cls)


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
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return path


def check_output(path, *, kind: str = "dir", field: str = "--out") -> Path:
    """Refuse an output path that cannot be written, before any work: a probe file is created in its
    directory (and the missing directories on the way), then everything the probe made is removed.

    Parameters
    ----------
    path : str or Path
        The output directory (``kind="dir"``) or file (``kind="file"``; written atomically through a
        temporary name beside it, as :func:`write_text` does: the probe has a name of that length).
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
            if path.is_dir():
                raise InputError(field, "a file name, not an existing directory", str(path))
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
        if kind == "file":
            probe = _temporary_name(path)
            os.close(os.open(probe, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600))
        else:
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
