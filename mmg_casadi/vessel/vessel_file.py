"""Checks of a vessel data file (the format of the packaged ``kcs_mmg.toml`` and ``kvlcc2_mmg.toml``) before any
model is built from it: only the known tables and keys, and physically sane particulars.

* **Tables and keys** – the tables :data:`TABLES`; in ``[model]`` only ``hull_form``, in ``[steering]`` only the
  steering gear's three numbers, in ``[ship]``, ``[mass]``, ``[hull]``, ``[propeller]`` and ``[rudder]`` only
  coefficients of :class:`~mmg_casadi.vessel.ship.ShipParams` (a misspelt coefficient used to be ignored and the
  base value kept); ``[reference]`` holds free-form validation data.
* **Physical sanity** – the particulars of :data:`SANE` lie in their ranges: positive length, beam, draft,
  displacement, mass, moment of inertia, design speed, propeller diameter and speed, rudder area; block
  coefficient in (0, 1]; wake and thrust deduction fractions in [0, 1) (a negative mass gave a turning circle of
  advance -0.85 L; a zero length or a negative design speed a CasADi error after compiling).

Every failure is one :class:`~mmg_casadi.errors.ParameterError` naming the file, the table and the key.

Examples
--------
>>> check_vessel_data({"ship": {"L": 0.0}}, "my.toml", ["L"])  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
mmg_casadi.errors.ParameterError: my.toml: ship.L: expected a number in (0, 1000] m (length between perpendiculars), got 0.0
"""

from __future__ import annotations

import math

from mmg_casadi.errors import ParameterError

TABLES = ("model", "ship", "mass", "hull", "propeller", "rudder", "steering", "reference")
"""Tables of a vessel data file."""
STEERING_KEYS = ("delta_max_deg", "T_delta", "rate_max_deg_per_s")
"""Keys of the ``[steering]`` table."""
SANE = {
    "L": (0.0, 1000.0, "m (length between perpendiculars)"),
    "B": (0.0, 200.0, "m (beam)"),
    "d": (0.0, 50.0, "m (draft)"),
    "displacement": (0.0, 1e7, "m^3"),
    "Cb": (0.0, 1.0, "(block coefficient)"),
    "kzz": (0.0, 1.0, "(yaw radius of gyration / L)"),
    "rho": (0.0, 2000.0, "kg/m^3 (water density)"),
    "g": (0.0, 100.0, "m/s^2"),
    "U_design": (0.0, 50.0, "m/s (design speed)"),
    "Fn_design": (0.0, 2.0, "(design Froude number)"),
    "m": (0.0, 100.0, "(non-dimensional mass)"),
    "Izz": (0.0, 100.0, "(non-dimensional moment of inertia)"),
    "DP": (0.0, 50.0, "m (propeller diameter)"),
    "n_design_rpm": (0.0, 10000.0, "rev/min (design propeller speed)"),
    "AR_over_Ld": (0.0, 1.0, "(rudder area / (L d))"),
    "aspect_ratio": (0.0, 20.0, "(rudder aspect ratio)"),
}
"""Particulars checked, ``name: (low, high, unit)``, each in ``(low, high]``."""
FRACTIONS = ("wP", "tP", "tR")
"""Wake and thrust deduction fractions, each in [0, 1)."""
STEERING_SANE = {"T_delta": (0.0, 10.0, "(steering time constant, L/U_design; the KCS's is 1)"),
                 "rate_max_deg_per_s": (0.0, 30.0, "deg/s (largest rudder rate)")}
"""Steering-gear numbers checked, like :data:`SANE` (``delta_max_deg`` is checked by the gear itself)."""


def check_vessel_data(raw: dict, where: str, coefficients) -> dict:
    """Refuse a parsed vessel data file with an unknown table or key or an insane particular (module notes).

    Parameters
    ----------
    raw : dict
        The parsed TOML file.
    where : str
        The file (or vessel) named in errors.
    coefficients : iterable of str
        The coefficients of :class:`~mmg_casadi.vessel.ship.ShipParams`
        (:data:`mmg_casadi.vessel.ship.COEFFICIENTS`), the keys the five coefficient tables may hold.

    Returns
    -------
    dict
        ``raw``.
    """
    known = tuple(coefficients)
    for table, value in raw.items():
        if table not in TABLES:
            raise ParameterError(f"{where}: [{table}]", f"a table of a vessel data file (one of: {', '.join(TABLES)})")
        if not isinstance(value, dict):
            raise ParameterError(f"{where}: {table}", "a table", value)
        allowed = {"model": ("hull_form",), "steering": STEERING_KEYS, "reference": None}.get(table, known)
        if allowed is None:
            continue
        for key in value:
            if key not in allowed:
                raise ParameterError(f"{where}: {table}.{key}", f"a known key of [{table}]" + (
                    "" if table not in ("model", "steering") else f" (one of: {', '.join(allowed)})"))
    flat = {}
    for table in ("ship", "mass", "hull", "propeller", "rudder"):
        flat.update({k: (table, v) for k, v in raw.get(table, {}).items()})
    for key, entry in flat.items():  # every coefficient a finite number (an int beyond a float included)
        _check(entry, key, where, -math.inf, math.inf, "a finite number")
    for key, entry in raw.get("steering", {}).items():
        _check(("steering", entry), key, where, -math.inf, math.inf, "a finite number")
    for key, (low, high, unit) in SANE.items():
        if key in flat:
            _check(flat[key], key, where, low, high, f"a number in ({low:g}, {high:g}] {unit}", open_low=True)
    for key in FRACTIONS:
        if key in flat:
            _check(flat[key], key, where, 0.0, 1.0, "a fraction in [0, 1)", open_high=True)
    steering = raw.get("steering", {})
    for key, (low, high, unit) in STEERING_SANE.items():
        if key in steering:
            _check(("steering", steering[key]), key, where, low, high, f"a number in ({low:g}, {high:g}] {unit}",
                   open_low=True)
    return raw


def _check(entry, key: str, where: str, low: float, high: float, allowed: str, *, open_low: bool = False,
           open_high: bool = False) -> None:
    table, v = entry
    ok = not isinstance(v, bool) and isinstance(v, (int, float))
    if ok:
        try:
            x = float(v)
        except OverflowError:
            ok = False
        else:
            ok = math.isfinite(x) and (x > low if open_low else x >= low) and (x < high if open_high else x <= high)
    if not ok:
        raise ParameterError(f"{where}: {table}.{key}", allowed, v)
