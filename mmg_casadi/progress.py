"""Progress of long work on stderr: bars (tqdm), redrawn in place on a terminal, a line every 30 s in logs, and
status lines (:func:`say`).

Examples
--------
>>> import io
>>> with progress_bar(10, desc="runs", file=io.StringIO()) as bar:
...     _ = bar.update(10)
>>> bar.n
10
"""

from __future__ import annotations

import sys

from tqdm import tqdm


def progress_bar(total: int, *, desc: str = "", initial: int = 0, unit: str = "run", file=None) -> tqdm:
    """A tqdm bar of ``total`` units, ``initial`` of them already done (a resumed study): rate and ETA count
    only the work done since.

    Parameters
    ----------
    total : int
        Units of work.
    desc : str
        Text in front of the counter.
    initial : int
        Units already done.
    unit : str
        Name of a unit.
    file : file-like, optional
        Where to write (default ``sys.stderr``).

    Returns
    -------
    tqdm.tqdm
        The bar, updated at most every 0.5 s on a terminal and every 30 s otherwise.
    """
    file = file or sys.stderr
    tty = hasattr(file, "isatty") and file.isatty()
    return tqdm(total=total, desc=desc, initial=initial, unit=unit, file=file, dynamic_ncols=tty,
                mininterval=0.5 if tty else 30.0, smoothing=0.1)


def say(msg: str) -> None:
    """Print a status line of long work on stderr, flushed at once (a log shows it before the work that follows).

    Parameters
    ----------
    msg : str
        The line.

    Examples
    --------
    >>> import contextlib, io
    >>> err = io.StringIO()
    >>> with contextlib.redirect_stderr(err):
    ...     say("[1/2] design")
    >>> err.getvalue()
    '[1/2] design\\n'
    """
    print(msg, file=sys.stderr, flush=True)
