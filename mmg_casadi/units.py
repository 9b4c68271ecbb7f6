"""Units of figures, tables and summaries: the package's non-dimensional prime-II system or SI units.

The library computes in ship lengths L, times L/U and speeds as fractions of the design speed U of the
reference hull (the parameter ``vessel``, the KCS by default: L = 230 m, U = 12.347 m/s, L/U = 18.6 s). A
:class:`Units` turns those numbers into what a reader wants to see: ``Units.of("nd")`` keeps them, and
``Units.of("si", vessel)`` gives metres, seconds and knots.

Examples
--------
>>> si = Units.of("si")
>>> si.length(2.0), round(si.time(1.0), 2), round(si.speed(1.0), 2)
(460.0, 18.63, 24.0)
>>> si.length_unit, si.time_unit, si.speed_unit
('m', 's', 'kn')
>>> nd = Units.of("nd")
>>> nd.length(2.0), nd.length_unit
(2.0, 'L')
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mmg_casadi.errors import InputError

UNIT_SYSTEMS = ("nd", "si")
"""``nd``: the library's non-dimensional units (L, L/U, U); ``si``: metres, seconds and knots."""
KNOT = 1852.0 / 3600.0
"""One knot in m/s."""


def _scale(x, k: float):
    """``x`` times ``k``; a list or tuple becomes an array first."""
    return np.asarray(x, float) * k if isinstance(x, (list, tuple)) else x * k


@dataclass(frozen=True)
class Units:
    """Scales from the library's units to the units shown.

    Parameters
    ----------
    system : str
        ``"nd"`` or ``"si"`` (:data:`UNIT_SYSTEMS`).
    length_m : float
        Metres per ship length L of the reference hull.
    speed_m_s : float
        Design speed U of the reference hull (m/s).
    """

    system: str
    length_m: float
    speed_m_s: float

    @classmethod
    def of(cls, system: str = "nd", vessel: str = "kcs") -> Units:
        """The units ``system`` for the reference hull ``vessel``.

        Parameters
        ----------
        system : str
            ``"nd"`` (L, L/U, U) or ``"si"`` (m, s, kn).
        vessel : str
            Name of the reference hull (:func:`mmg_casadi.vessel.library.load_vessel`), whose L and U scale
            the non-dimensional numbers.

        Returns
        -------
        Units
            The scales.
        """
        if system not in UNIT_SYSTEMS:
            raise InputError("units", f"one of: {', '.join(UNIT_SYSTEMS)}", system)
        from mmg_casadi.vessel.library import load_vessel
        ship = load_vessel(vessel).ship
        return cls(system, float(ship.L), float(ship.U_design))

    @property
    def si(self) -> bool:
        """Whether the units are SI (m, s, kn)."""
        return self.system == "si"

    @property
    def length_unit(self) -> str:
        """Name of the length unit (``L`` or ``m``)."""
        return "m" if self.si else "L"

    @property
    def time_unit(self) -> str:
        """Name of the time unit (``L/U`` or ``s``)."""
        return "s" if self.si else "L/U"

    @property
    def speed_unit(self) -> str:
        """Name of the speed unit (``U`` or ``kn``)."""
        return "kn" if self.si else "U"

    def length(self, x):
        """A length in L shown in :attr:`length_unit`.

        Parameters
        ----------
        x : float or numpy.ndarray
            Length(s) in ship lengths L.

        Returns
        -------
        float or numpy.ndarray
            The same in the units shown.
        """
        return _scale(x, self.length_m) if self.si else x

    def time(self, t):
        """A time in L/U shown in :attr:`time_unit`.

        Parameters
        ----------
        t : float or numpy.ndarray
            Time(s) in L/U.

        Returns
        -------
        float or numpy.ndarray
            The same in the units shown.
        """
        return _scale(t, self.length_m / self.speed_m_s) if self.si else t

    def speed(self, v):
        """A speed as a fraction of U shown in :attr:`speed_unit`.

        Parameters
        ----------
        v : float or numpy.ndarray
            Speed(s) as fractions of the design speed U.

        Returns
        -------
        float or numpy.ndarray
            The same in the units shown.
        """
        return _scale(v, self.speed_m_s / KNOT) if self.si else v

    def fmt_length(self, x: float) -> str:
        """``x`` (L) as text with its unit: ``"5.77 L"`` or ``"1327 m"``.

        Parameters
        ----------
        x : float
            Length in L.

        Returns
        -------
        str
            The length and its unit.
        """
        return f"{self.length(x):.0f} m" if self.si else f"{x:.2f} L"

    def fmt_time(self, t: float) -> str:
        """``t`` (L/U) as text with its unit: ``"51.8 L/U"`` or ``"964 s"``.

        Parameters
        ----------
        t : float
            Time in L/U.

        Returns
        -------
        str
            The time and its unit.
        """
        return f"{self.time(t):.0f} s" if self.si else f"{t:.1f} L/U"
