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

import tomllib
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources
from pathlib import Path

from mmg_casadi.errors import InputError
from mmg_casadi.vessel.ship import (ShipParams, SteeringParams, load_kcs, load_steering, ship_from_table,
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
    try:
        raw = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError, RecursionError) as e:  # RecursionError: nested too deep
        raise InputError(field, "a readable vessel TOML file", f"{path} ({e})") from None
    return _vessel_from(path.stem, raw, str(path))


def _vessel_from(name: str, raw: dict, where: str) -> Vessel:
    for block in ("ship", "mass", "hull", "propeller", "rudder", "steering"):
        if not isinstance(raw.get(block), dict):
            raise InputError(f"{where}: [{block}]", "a table of the vessel data format (see kcs_mmg.toml)")
    return Vessel(name, ship_from_table(raw), steering_from_table(raw))


def vessel_table() -> list[dict]:
    """One row per library vessel: particulars, design speed, self-propulsion propeller speed and source.

    ``rpm_design`` is the propeller speed of steady straight running at the design speed, solved from the surge
    balance of the vessel's own model (:func:`~mmg_casadi.vessel.mmg.propeller_rpm_for_speed`).

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
