"""The vessel library: every hull the closed loop can sail, by name, with its coefficients and steering gear.

A ship of a scenario names its vessel (``vessel = "kcs"``, the default); the closed loop builds one MMG model per
vessel its layout uses (``Layout.vessels``). Each hull is one packaged data file that names the source of every
coefficient; :func:`load_vessel` also reads such a file from a path (e.g. one written by
:mod:`mmg_casadi.identify`).

Examples
--------
>>> VESSELS
('kcs', 'kvlcc2')
>>> v = load_vessel("kcs")
>>> v.name, round(v.ship.U_design, 3)
('kcs', 12.347)
>>> k = load_vessel("kvlcc2")
>>> k.ship.hull_form, k.ship.L
('yy2015', 320.0)
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources
from pathlib import Path

from mmg_casadi.errors import InputError
from mmg_casadi.readers import load_toml
from mmg_casadi.vessel.vessel_file import check_vessel_data
from mmg_casadi.vessel.ship import (COEFFICIENTS, ShipParams, SteeringParams, load_kcs, load_steering, ship_from_table,
                                    steering_from_table)

DEFAULT = "kcs"
"""The vessel of a ship that names none: the paper's KRISO Container Ship."""

_FILES = {"kcs": "kcs_mmg.toml", "kvlcc2": "kvlcc2_mmg.toml"}

SOURCES = {
    "kcs": "KRISO Container Ship; Deraj et al. 2023 (Ocean Eng. 273:113937) via the seed paper, Tables 1-2",
    "kvlcc2": "KRISO VLCC 2; Yasukawa & Yoshimura 2015 (J. Mar. Sci. Technol. 20:37-52), MMG standard method",
}
"""One line per vessel: what the hull is and where its coefficients come from (the data file has the details)."""

VESSELS: tuple[str, ...] = tuple(_FILES)
"""Names of the vessels in the library."""

HULL_TYPES = {"kcs": "container", "kvlcc2": "tanker"}
"""The kind of ship each hull stands for, matched against an imported ship type (:func:`closest_vessel`)."""

_TYPE_WORDS = {"container": ("container", "cargo"), "tanker": ("tanker",)}
"""Words of a ship type (maritime-schema ``shipType``, AIS type names) that name each kind."""


def closest_vessel(length_m: float | None, ship_type: str | None = None) -> tuple[str, str]:
    """The library's hull closest to a ship of length ``length_m`` and type ``ship_type``, and why.

    The hulls of the ship's kind (``ship_type`` containing one of the words of :data:`_TYPE_WORDS`, any case) are
    the candidates, all hulls if none is of its kind; among them the one whose length is closest on a log scale
    (ratio, not difference: a 60 m ship is closer to 230 m than to 320 m, and a 400 m one to 320 m).

    Parameters
    ----------
    length_m : float or None
        The ship's length (m, > 0); None: :data:`DEFAULT`.
    ship_type : str or None, optional
        Its type as read (e.g. ``"Tanker"``, ``"Cargo"``, ``"Passenger"``).

    Returns
    -------
    tuple of str
        ``(vessel, reason)``: a name of :data:`VESSELS` and a short phrase saying how it was chosen.

    Examples
    --------
    >>> closest_vessel(300.0)
    ('kvlcc2', 'closest length (320 m)')
    >>> closest_vessel(300.0, "Cargo")
    ('kcs', 'container hull, closest length (230 m)')
    >>> closest_vessel(None)
    ('kcs', 'no length: the default hull')
    """
    if length_m is None:
        return DEFAULT, "no length: the default hull"
    kind = next((k for k, words in _TYPE_WORDS.items()
                 if isinstance(ship_type, str) and any(w in ship_type.lower() for w in words)), None)
    names = [v for v in VESSELS if HULL_TYPES[v] == kind] or list(VESSELS)
    best = min(names, key=lambda v: (abs(math.log(float(length_m) / load_vessel(v).ship.L)), v != DEFAULT))
    prefix = f"{kind} hull, " if kind is not None and HULL_TYPES[best] == kind else ""
    return best, f"{prefix}closest length ({load_vessel(best).ship.L:g} m)"


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


def data_path(name: str):
    """The packaged data file of the library vessel ``name`` (an importlib resource).

    Parameters
    ----------
    name : str
        A name of :data:`VESSELS`.

    Returns
    -------
    importlib.resources.abc.Traversable
        The TOML file of the vessel inside the installed package.
    """
    return resources.files("mmg_casadi").joinpath("data", _FILES[name])


@lru_cache(maxsize=None)
def _library_vessel(name: str) -> Vessel:
    if name == "kcs":
        return Vessel(name, load_kcs(), load_steering())
    with data_path(name).open("rb") as fh:
        raw = tomllib.load(fh)
    return _vessel_from(name, raw, name)


def load_vessel(name: str | Path = DEFAULT, field: str = "vessel") -> Vessel:
    """The vessel ``name`` of the library, or of a data file; an :class:`~mmg_casadi.errors.InputError` naming
    ``field`` otherwise.

    Parameters
    ----------
    name : str or pathlib.Path, default 'kcs'
        A name of :data:`VESSELS`, or the path of a TOML data file in the format of the packaged ones (its stem is
        the vessel's name).
    field : str, default 'vessel'
        Name of the input field, used in the error message.

    Returns
    -------
    Vessel
        The vessel: its name, MMG coefficients and steering gear.

    Examples
    --------
    >>> load_vessel("kvlcc9")
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.InputError: vessel: expected one of: kcs, kvlcc2 (or a vessel .toml file), got 'kvlcc9'
    """
    if isinstance(name, str) and name in _FILES:
        return _library_vessel(name)  # read once per process; a file given by path is read at every call
    path = Path(name) if isinstance(name, (str, Path)) else None
    if path is None or path.suffix.lower() != ".toml" or not path.is_file():
        raise InputError(field, f"one of: {', '.join(VESSELS)} (or a vessel .toml file)", name)
    raw = load_toml(path, "vessel", field)  # size, UTF-8 and nesting checked while reading
    return _vessel_from(path.stem, raw, str(path))


def _vessel_from(name: str, raw: dict, where: str) -> Vessel:
    check_vessel_data(raw, where, COEFFICIENTS)  # known tables and keys, sane particulars
    for block in ("ship", "mass", "hull", "propeller", "rudder", "steering"):
        if not isinstance(raw.get(block), dict):
            raise InputError(f"{where}: [{block}]", "a table of the vessel data format (see kcs_mmg.toml)")
    return Vessel(name, ship_from_table(raw), steering_from_table(raw))


def vessel_table() -> list[dict]:
    """One row per library vessel: particulars, design speed, self-propulsion propeller speed and source.

    ``rpm_design`` is the propeller speed of steady straight running at the design speed, solved from the surge
    balance of the vessel's own model (:func:`~mmg_casadi.vessel.mmg.propeller_rpm_for_speed`).

    Returns
    -------
    list of dict
        One dict per name of :data:`VESSELS`: ``name``, ``L_m``, ``B_m``, ``d_m`` (m), ``U_design_m_s`` (m/s),
        ``U_design_kn`` (kn), ``Fn``, ``rpm_design`` (rev/min), ``hull_form`` and ``source``.

    Examples
    --------
    >>> rows = vessel_table()
    >>> [(r["name"], r["L_m"], round(r["rpm_design"], 1)) for r in rows]
    [('kcs', 230.0, 115.5), ('kvlcc2', 320.0, 105.0)]
    """
    from mmg_casadi.vessel.mmg import propeller_rpm_for_speed  # CasADi rootfinder: only when listing
    rows = []
    for name in VESSELS:
        s = load_vessel(name).ship
        rows.append({"name": name, "L_m": s.L, "B_m": s.B, "d_m": s.d, "U_design_m_s": s.U_design,
                     "U_design_kn": s.U_design * 3600.0 / 1852.0, "Fn": s.Fn_design,
                     "rpm_design": propeller_rpm_for_speed(1.0, s), "hull_form": s.hull_form,
                     "source": SOURCES[name]})
    return rows


def ship_size(vessel: str | Path | None = None, length_m: float | None = None,
              beam_m: float | None = None, unit: str | Path | None = None) -> tuple[float, float]:
    """A ship's length and half beam in the scenario's length unit L, for its collision geometry.

    The unit L is the length of the own ship's hull, ``unit`` (:data:`DEFAULT`, the KCS's 230 m, unless the own
    ship sails another): positions, radii and distances of a scenario are in it. A ship's own ``length_m`` and ``beam_m`` (e.g. read from a traffic
    situation) win over its vessel's particulars.

    Parameters
    ----------
    vessel : str or Path, optional
        The ship's vessel (default :data:`DEFAULT`).
    length_m, beam_m : float, optional
        The ship's own length and beam [m] (> 0); ``None`` for the vessel's.
    unit : str or Path, optional
        The own ship's vessel, whose length is the unit (default :data:`DEFAULT`).

    Returns
    -------
    tuple of float
        ``(length, half_beam)`` in L: a KCS gives exactly ``(1.0, 0.07)``.

    Examples
    --------
    >>> ship_size()[0], ship_size(length_m=122.0)[0] == 122.0 / 230.0
    (1.0, True)
    >>> round(ship_size("kvlcc2")[0], 4)
    1.3913
    """
    unit = load_vessel(unit or DEFAULT).ship.L
    hull = load_vessel(vessel or DEFAULT).ship
    length = hull.L if length_m is None else float(length_m)
    beam = hull.B if beam_m is None else float(beam_m)
    return length / unit, 0.5 * beam / unit


def pair_collision_distance(collision_distance, length_a, length_b):
    """Centre distance below which two ships of lengths ``length_a`` and ``length_b`` (L) collide.

    ``collision_distance`` (the paper's 2 L) is the distance for two ships of the unit length; it scales with
    their mean length, ``collision_distance * (length_a + length_b) / 2``, which is exactly
    ``collision_distance`` for two ships of length 1 (the arithmetic has no rounding there). Works on floats,
    NumPy arrays and CasADi expressions alike.

    Parameters
    ----------
    collision_distance : float or array or SX/MX
        The collision distance of two ships of the unit length (L).
    length_a, length_b : float or array or SX/MX
        The two ships' lengths (L, :func:`ship_size`).

    Returns
    -------
    float or array or SX/MX
        The pair's collision distance (L).

    Examples
    --------
    >>> pair_collision_distance(2.0, 1.0, 1.0)
    2.0
    >>> round(pair_collision_distance(2.0, 1.0, 122.0 / 230.0), 4)
    1.5304
    """
    return collision_distance * (0.5 * (length_a + length_b))
