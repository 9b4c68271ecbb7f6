"""A small dependency-free progress bar for long studies, written to stderr.

On a terminal the line ``desc  123/1000 (12.3%)  45.6 runs/s  ETA 0:01:23`` is redrawn in place (``\\r``)
at most every ``min_interval`` seconds; on anything else (CI logs, files) a full line is printed each time
another 10 % of the work is done, so logs stay short.
"""

from __future__ import annotations

import datetime
import math
import sys
import time

from .errors import InputError


def _format_eta(seconds: float) -> str:
    if not math.isfinite(seconds) or seconds < 0:
        return "?"
    return str(datetime.timedelta(seconds=int(round(seconds))))


class Progress:
    """Progress of ``total`` units of work (runs by default).

    Parameters
    ----------
    total : int
        Number of units of work (>= 0).
    desc : str
        Text in front of the counter.
    stream : file-like, optional
        Where to write; ``None`` (default) means ``sys.stderr`` at construction time.
    min_interval : float
        Minimum seconds between redraws on a terminal.
    initial : int
        Units already done, e.g. runs found in a resumed results table. The rate and the ETA count only
        the work done since construction.
    unit : str
        Name of a unit in the rate (``"runs"``).
    clock : callable
        Returns the time in seconds (``time.monotonic``); replaceable in tests.

    Examples
    --------
    >>> import io
    >>> now = [0.0]
    >>> out = io.StringIO()
    >>> with Progress(1000, desc="env 3", stream=out, initial=100, clock=lambda: now[0]) as bar:
    ...     now[0] = 10.0
    ...     bar.update(123)
    ...     now[0] = 70.0
    ...     bar.update(777)
    >>> print(out.getvalue(), end="")
    env 3  223/1000 (22.3%)  12.3 runs/s  ETA 0:01:03
    env 3  1000/1000 (100.0%)  12.9 runs/s  ETA 0:00:00
    """

    def __init__(self, total: int, desc: str = "", stream=None, min_interval: float = 0.5, *, initial: int = 0,
                 unit: str = "runs", clock=time.monotonic):
        if isinstance(total, bool) or not isinstance(total, int) or total < 0:
            raise InputError("total", "an integer >= 0", total)
        if isinstance(initial, bool) or not isinstance(initial, int) or not 0 <= initial <= total:
            raise InputError("initial", f"an integer in [0, {total}]", initial)
        if isinstance(min_interval, bool) or not isinstance(min_interval, (int, float)) or not min_interval >= 0:
            raise InputError("min_interval", "a number >= 0 seconds", min_interval)
        self.total = total
        self.desc = str(desc)
        self.stream = sys.stderr if stream is None else stream
        self.min_interval = float(min_interval)
        self.initial = initial
        self.n = initial
        self.unit = unit
        self._clock = clock
        self._start = clock()
        self._last_draw = -math.inf
        self._last_len = 0
        self._last_drawn_n: int | None = None
        self._decile = self._decile_of(initial)
        self._closed = False
        isatty = getattr(self.stream, "isatty", None)
        try:
            self._tty = bool(isatty()) if callable(isatty) else False
        except (OSError, ValueError):
            self._tty = False

    def _decile_of(self, n: int) -> int:
        return 10 if self.total == 0 else min(10, (10 * n) // self.total)

    def line(self, now: float | None = None) -> str:
        """The current status line, e.g. ``"desc  123/1000 (12.3%)  45.6 runs/s  ETA 0:01:23"``."""
        now = self._clock() if now is None else now
        elapsed = now - self._start
        done = self.n - self.initial
        rate = done / elapsed if elapsed > 0 else math.nan
        remaining = max(self.total - self.n, 0)
        if remaining == 0:
            eta = 0.0
        else:
            eta = remaining / rate if rate > 0 else math.nan
        pct = 100.0 if self.total == 0 else 100.0 * self.n / self.total
        rate_text = f"{rate:.1f}" if math.isfinite(rate) else "?"
        body = f"{self.n}/{self.total} ({pct:.1f}%)  {rate_text} {self.unit}/s  ETA {_format_eta(eta)}"
        return f"{self.desc}  {body}" if self.desc else body

    def _write(self, text: str) -> None:
        try:
            self.stream.write(text)
            self.stream.flush()
        except (OSError, ValueError):
            pass

    def _draw_tty(self, now: float) -> None:
        text = self.line(now)
        pad = " " * max(self._last_len - len(text), 0)
        self._write("\r" + text + pad)
        self._last_len = len(text)
        self._last_draw = now
        self._last_drawn_n = self.n

    def update(self, n: int = 1) -> None:
        """Record ``n`` more units of work done and redraw if due."""
        if isinstance(n, bool) or not isinstance(n, int) or n < 0:
            raise InputError("n", "an integer >= 0", n)
        if self._closed:
            return
        self.n += n
        if self._tty:
            now = self._clock()
            if now - self._last_draw >= self.min_interval or self.n >= self.total:
                self._draw_tty(now)
            return
        decile = self._decile_of(self.n)
        if decile > self._decile:
            self._decile = decile
            self._write(self.line() + "\n")

    def close(self) -> None:
        """Draw the final state and end the line; further calls do nothing."""
        if self._closed:
            return
        self._closed = True
        if self._tty:
            if self._last_drawn_n != self.n:
                self._draw_tty(self._clock())
            self._write("\n")
        elif self._decile < 10 or self.n == self.initial:
            self._write(self.line() + "\n")

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        self.close()
