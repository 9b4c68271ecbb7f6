"""Errors raised for bad user input, and for a study that could not finish.

Every input error names the offending field and the allowed values, so the CLI can print one line and exit with
status 2 instead of a traceback. A :class:`RunError` (e.g. a batch whose worker died more often than it is
retried) is printed as one line too, with exit status 1.
"""

from __future__ import annotations


class InputError(ValueError):
    """Bad user input (a parameter, a CLI argument or a scenario entry).

    Parameters
    ----------
    field : str
        Dotted name of the offending field, e.g. ``"ships[1].speed"`` or ``"--rudder"``.
    allowed : str
        Human-readable description of the allowed values, e.g. ``"a number in (0, 35] degrees"``.
    got : object, optional
        The value that was given.

    Examples
    --------
    >>> str(InputError("rudder", "a number in (0, 35] degrees", 40))
    'rudder: expected a number in (0, 35] degrees, got 40'
    """

    def __init__(self, field: str, allowed: str, got: object = None):
        self.field = field
        self.allowed = allowed
        self.got = got
        msg = f"{field}: expected {allowed}"
        if got is not None:
            msg += f", got {got!r}" if isinstance(got, str) else f", got {got}"
        super().__init__(msg)


class ParameterError(InputError):
    """A model, guidance or field parameter outside its allowed range.

    Parameters
    ----------
    field, allowed, got
        As for :class:`InputError`.
    """


class ScenarioError(InputError):
    """A malformed or inconsistent scenario file.

    Parameters
    ----------
    field, allowed, got
        As for :class:`InputError`.
    """


class RunError(RuntimeError):
    """A study stopped because some of its work could not be done; what it finished is kept.

    The message says what failed and how to resume (the CLI prints it as one line and exits with status 1).

    Parameters
    ----------
    message : str
        One line: what failed, why, and what to do.

    Examples
    --------
    >>> str(RunError("batch (environment 1, inverse-square, runs 0-127): the Ray worker died 4 times"))
    'batch (environment 1, inverse-square, runs 0-127): the Ray worker died 4 times'
    """

    def __init__(self, message: str):
        super().__init__(message)


def check_range(field: str, value, low=None, high=None, *, low_open=False, high_open=False,
                cls=ParameterError, unit: str = "") -> float:
    """Return ``float(value)`` if it lies in the given interval, else raise ``cls``.

    Parameters
    ----------
    field : str
        Name of the checked field, used in the error message.
    value : float-like
        The value to check.
    low : float or None, optional
        Lower bound (``None``: unbounded).
    high : float or None, optional
        Upper bound (``None``: unbounded).
    low_open : bool, default False
        Whether ``low`` itself is excluded.
    high_open : bool, default False
        Whether ``high`` itself is excluded.
    cls : type, default ParameterError
        Exception class raised for a value out of range.
    unit : str, default ''
        Unit shown after the bounds in the error message.

    Returns
    -------
    float
        ``float(value)``.

    Examples
    --------
    >>> check_range("delta", 2.0, 0.0, None, low_open=True)
    2.0
    >>> check_range("delta", -1, 0.0, None, low_open=True)
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.ParameterError: delta: expected a number in (0, inf), got -1
    """
    lo = "-inf" if low is None else f"{low:g}"
    hi = "inf" if high is None else f"{high:g}"
    interval = f"{'(' if low_open or low is None else '['}{lo}, {hi}{')' if high_open or high is None else ']'}"
    allowed = f"a number in {interval}" + (f" {unit}" if unit else "")
    if isinstance(value, bool):
        raise cls(field, allowed, value)
    try:
        x = float(value)
    except (TypeError, ValueError, OverflowError):  # OverflowError: an int beyond any float
        raise cls(field, allowed, value) from None
    if x != x:
        raise cls(field, allowed, value)
    if low is not None and (x < low or (low_open and x == low)):
        raise cls(field, allowed, value)
    if high is not None and (x > high or (high_open and x == high)):
        raise cls(field, allowed, value)
    return x
