"""The vessel library: every hull the closed loop can sail, by name, with its coefficients and steering gear.

A ship of a scenario names its vessel (``vessel = "kcs"``, the default); the closed loop builds one MMG model per
vessel its layout uses (``Layout.vessels``).

Examples
--------
>>> VESSELS
('kcs',)
>>> v = load_vessel("kcs")
>>> v.name, round(v.ship.U_design, 3)
('kcs', 12.347)
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

from mmg_casadi.errors import InputError
from mmg_casadi.vessel.ship import ShipParams, SteeringParams, load_kcs, load_steering

DEFAULT = "kcs"
"""The vessel of a ship that names none: the paper's KRISO Container Ship."""

_LOADERS = {"kcs": (load_kcs, load_steering)}

VESSELS: tuple[str, ...] = tuple(_LOADERS)
"""Names of the vessels in the library."""


@dataclass(frozen=True)
class Vessel:
    """One hull: its MMG coefficients and its steering gear.

    Parameters
    ----------
    name : str
        Name in scenario files and the parameter table.
    ship : ShipParams
        Particulars and MMG coefficients.
    steering : SteeringParams
        Steering-gear parameters.
    """

    name: str
    ship: ShipParams
    steering: SteeringParams


@lru_cache(maxsize=None)
def load_vessel(name: str = DEFAULT, field: str = "vessel") -> Vessel:
    """The vessel ``name`` of the library, or an :class:`~mmg_casadi.errors.InputError` naming ``field``.

    Parameters
    ----------
    name : str, default 'kcs'
        A name of :data:`VESSELS`.
    field : str, default 'vessel'
        Name of the input field, used in the error message.

    Examples
    --------
    >>> load_vessel("kvlcc9")
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.InputError: vessel: expected one of: kcs, got 'kvlcc9'
    """
    if not isinstance(name, str) or name not in _LOADERS:
        raise InputError(field, f"one of: {', '.join(VESSELS)}", name)
    ship, steering = _LOADERS[name]
    return Vessel(name, ship(), steering())
