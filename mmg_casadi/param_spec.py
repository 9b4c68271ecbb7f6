"""One parameter of the table (:class:`Param`): its default, allowed range or choices, unit, meaning and source,
and the check of a value against them. The table itself is :data:`mmg_casadi.params.PARAMETERS`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from mmg_casadi.errors import ParameterError, check_range


@dataclass(frozen=True)
class Param:
    """One parameter.

    Parameters
    ----------
    name : str
        Key in scenario files, ``--params`` files and the Python API.
    default : float, int or str
        The value used when nothing overrides it.
    low, high : float or None
        Bounds of the allowed interval (``None``: unbounded).
    unit : str
        Unit of the value (``""`` for dimensionless).
    meaning : str
        One line saying what it is.
    source : str
        Where the default comes from: a paper equation or table, or "our choice, because ...".
    group : str, optional
        One of :func:`groups`; a parameter declared with a method (``Method.params``) may leave it empty, the
        registry sets it to the method's name.
    low_open, high_open : bool
        Whether the bounds are excluded.
    kind : {"float", "int", "choice", "bool", "text"}
        Numbers are floats unless ``"int"``; ``"choice"`` takes one of ``choices``; ``"bool"`` true or false;
        ``"text"`` a string that ``parse`` checks.
    choices : tuple of str
        Allowed values of a ``"choice"``.
    structural : bool
        Changes the shape of the compiled closed loop (a :class:`~mmg_casadi.closed_loop.layout.Layout` field) rather
        than a numeric input of it.
    parse : callable, optional
        For ``"text"``: ``parse(value, field, cls)`` returns the checked value or raises ``cls``; ``choices`` then
        holds one string, the allowed values in words.
    """

    name: str
    default: object
    low: float | None
    high: float | None
    unit: str
    meaning: str
    source: str
    group: str = ""
    low_open: bool = False
    high_open: bool = False
    kind: str = "float"
    choices: tuple = ()
    structural: bool = False
    parse: object = None

    def allowed(self) -> str:
        """Human-readable allowed values, as error messages print them.

        Returns
        -------
        str
            E.g. ``"one of: ..."``, ``"true or false"``, ``"an integer >= 1"`` or the range text of
            :func:`~mmg_casadi.errors.check_range`.

        Examples
        --------
        >>> from mmg_casadi.params import PARAMETERS
        >>> PARAMETERS["vo_cone"].allowed()
        'one of: huang, wide'
        >>> PARAMETERS["dt"].allowed()
        'a number in (0, 2] L/U'
        """
        if self.kind == "choice":
            return f"one of: {', '.join(self.choices)}"
        if self.kind == "text":
            return self.choices[0]
        if self.kind == "bool":
            return "true or false"
        if self.kind == "int":
            return f"an integer >= {self.low:g}" if self.high is None else f"an integer in [{self.low:g}, {self.high:g}]"
        try:
            check_range(self.name, math.nan, self.low, self.high, low_open=self.low_open,
                        high_open=self.high_open, unit=self.unit)
        except ParameterError as err:
            return err.allowed
        raise AssertionError("check_range accepted nan")

    def check(self, value, field: str | None = None, cls=ParameterError):
        """``value`` converted to this parameter's type if allowed, else ``cls`` naming ``field`` (default: name).

        Parameters
        ----------
        value : object
            The value to check.
        field : str or None, optional
            Name used in the error message (default: the parameter's name).
        cls : type, default ParameterError
            Exception class raised for an invalid value.

        Returns
        -------
        str or bool or int or float
            The value: the choice, the bool, ``int(value)`` or the float within the range.

        Examples
        --------
        >>> from mmg_casadi.params import PARAMETERS
        >>> PARAMETERS["vo_candidates"].check(40)
        40
        >>> PARAMETERS["ilos_delta"].check(0, field="settings.ilos_delta")
        Traceback (most recent call last):
        ...
        mmg_casadi.errors.ParameterError: settings.ilos_delta: expected a number in (0, inf) L, got 0
        """
        field = field or self.name
        if self.kind == "text":
            return self.parse(value, field, cls)
        if self.kind == "choice":
            if not isinstance(value, str) or value not in self.choices:
                raise cls(field, self.allowed(), value)
            return value
        if self.kind == "bool":
            if not isinstance(value, bool):
                raise cls(field, self.allowed(), value)
            return value
        if self.kind == "int":
            if (isinstance(value, bool) or not isinstance(value, int) or value < self.low
                    or (self.high is not None and value > self.high)):
                raise cls(field, self.allowed(), value)
            return int(value)
        if not _is_real(value) or isinstance(value, int) and abs(value) > 2 ** 1023 or not math.isfinite(value):
            raise cls(field, self.allowed(), value)  # an int beyond any float: refused, not an OverflowError
        return check_range(field, value, self.low, self.high, low_open=self.low_open, high_open=self.high_open,
                           cls=cls, unit=self.unit)


def _is_real(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)
