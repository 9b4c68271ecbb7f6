"""WGS-84 geodesy of the maritime-schema interchange: latitude/longitude on a local tangent plane and back.

Positions are mapped to a local tangent plane (x north, y east, metres) at a reference point on the WGS-84
ellipsoid (a = 6378137 m, f = 1/298.257223563): geodetic → Earth-centred Earth-fixed → rotation into the
reference's north/east/up frame, dropping "up". The map preserves distances from the reference to within
d³/(6R²) (0.5 m at d = 50 km) and is inverted exactly (to < 1 mm) by a short fixed-point iteration. Courses and
headings are given against the local north of each ship; they are turned into the plane by projecting the ship's
local direction (this accounts for the convergence of the meridians, 0.7° at 50 km east of the reference at
58° N). Used by :mod:`mmg_casadi.scenarios.maritime_schema` (reading) and
:mod:`mmg_casadi.scenarios.maritime_export` (writing).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

WGS84_A = 6378137.0
"""WGS-84 semi-major axis [m]."""
WGS84_F = 1.0 / 298.257223563
"""WGS-84 flattening."""
WGS84_E2 = WGS84_F * (2.0 - WGS84_F)


def _ecef(lat: float, lon: float, h: float = 0.0) -> np.ndarray:
    phi, lam = math.radians(lat), math.radians(lon)
    n = WGS84_A / math.sqrt(1.0 - WGS84_E2 * math.sin(phi) ** 2)
    return np.array([(n + h) * math.cos(phi) * math.cos(lam), (n + h) * math.cos(phi) * math.sin(lam),
                     (n * (1.0 - WGS84_E2) + h) * math.sin(phi)])


def _geodetic(p) -> tuple[float, float, float]:
    """(lat, lon, h) of an ECEF point (iterated to 1e-14 rad)."""
    x, y, z = p
    lon = math.atan2(y, x)
    r = math.hypot(x, y)
    lat = math.atan2(z, r * (1.0 - WGS84_E2))
    for _ in range(10):
        n = WGS84_A / math.sqrt(1.0 - WGS84_E2 * math.sin(lat) ** 2)
        h = r / math.cos(lat) - n if abs(lat) < math.pi / 4 else z / math.sin(lat) - n * (1.0 - WGS84_E2)
        new = math.atan2(z, r * (1.0 - WGS84_E2 * n / (n + h)))
        if abs(new - lat) < 1e-14:
            lat = new
            break
        lat = new
    n = WGS84_A / math.sqrt(1.0 - WGS84_E2 * math.sin(lat) ** 2)
    h = r / math.cos(lat) - n if abs(lat) < math.pi / 4 else z / math.sin(lat) - n * (1.0 - WGS84_E2)
    return math.degrees(lat), math.degrees(lon), h


def _neu(lat: float, lon: float) -> np.ndarray:
    """Rows: unit north, east, up vectors (ECEF) at a point."""
    phi, lam = math.radians(lat), math.radians(lon)
    sp, cp, sl, cl = math.sin(phi), math.cos(phi), math.sin(lam), math.cos(lam)
    return np.array([[-sp * cl, -sp * sl, cp], [-sl, cl, 0.0], [cp * cl, cp * sl, sp]])


def wrap_360(angle_deg: float) -> float:
    """``angle_deg`` wrapped into [0, 360) (``-1e-17 % 360`` is 360.0 in floating point; that gives 0.0 here).

    Parameters
    ----------
    angle_deg : float
        An angle [deg].

    Returns
    -------
    float
        The same direction in [0, 360) [deg].

    Examples
    --------
    >>> wrap_360(-90.0), wrap_360(720.5), wrap_360(-1e-17)
    (270.0, 0.5, 0.0)
    """
    a = angle_deg % 360.0
    return 0.0 if a >= 360.0 else a


@dataclass(frozen=True)
class LocalPlane:
    """Local tangent plane (x north, y east, metres) at the reference ``lat``, ``lon`` [deg] on WGS-84.

    Parameters
    ----------
    lat : float
        Latitude of the reference point (the plane's origin) [deg, WGS-84, north positive], in [-90, 90].
    lon : float
        Longitude of the reference point [deg, WGS-84, east positive], in [-180, 180].

    Examples
    --------
    >>> plane = LocalPlane(58.61, 10.59)
    >>> plane.to_plane(58.61, 10.59)
    (0.0, 0.0)
    >>> x, y = plane.to_plane(58.70, 10.80)
    >>> lat, lon = plane.to_geodetic(x, y)
    >>> abs(lat - 58.70) < 1e-9 and abs(lon - 10.80) < 1e-9
    True
    """

    lat: float
    lon: float

    def _frame(self):
        return _ecef(self.lat, self.lon), _neu(self.lat, self.lon)

    def to_plane(self, lat: float, lon: float) -> tuple[float, float]:
        """(x north, y east) [m] of a point on the ellipsoid.

        Parameters
        ----------
        lat : float
            Latitude of the point [deg, WGS-84].
        lon : float
            Longitude of the point [deg, WGS-84].

        Returns
        -------
        (float, float)
            The point's projection on the plane: metres north and east of the reference.
        """
        origin, neu = self._frame()
        d = neu @ (_ecef(lat, lon) - origin)
        return float(d[0]), float(d[1])

    def to_geodetic(self, x: float, y: float) -> tuple[float, float]:
        """(lat, lon) [deg] of the point on the ellipsoid whose projection on the plane is (x, y).

        The inverse of :meth:`to_plane` (to < 1 mm; a fixed-point iteration over the height above the plane).

        Parameters
        ----------
        x : float
            Metres north of the reference, in the plane.
        y : float
            Metres east of the reference, in the plane.

        Returns
        -------
        (float, float)
            Latitude and longitude [deg, WGS-84].
        """
        origin, neu = self._frame()
        up = 0.0
        for _ in range(20):
            lat, lon, _h = _geodetic(origin + neu.T @ np.array([x, y, up]))
            d = neu @ (_ecef(lat, lon) - origin)
            if abs(d[2] - up) < 1e-7:
                break
            up = float(d[2])
        return lat, lon

    def course_to_plane(self, course_deg: float, lat: float, lon: float) -> float:
        """A course [deg from local north, clockwise] at (lat, lon) as an angle in the plane [deg from x to y].

        Parameters
        ----------
        course_deg : float
            Course or heading [deg from the local north at (lat, lon), clockwise].
        lat : float
            Latitude of the ship [deg, WGS-84].
        lon : float
            Longitude of the ship [deg, WGS-84].

        Returns
        -------
        float
            The direction in the plane [deg from x (north of the reference) towards y (east)], in [0, 360).
        """
        c = math.radians(course_deg)
        local = _neu(lat, lon)
        v = _neu(self.lat, self.lon) @ (math.cos(c) * local[0] + math.sin(c) * local[1])
        return wrap_360(math.degrees(math.atan2(v[1], v[0])))

    def course_from_plane(self, angle_deg: float, lat: float, lon: float) -> float:
        """The inverse of :meth:`course_to_plane` (to ~(d/R)² rad): a plane angle as a course at (lat, lon).

        Parameters
        ----------
        angle_deg : float
            Direction in the plane [deg from x (north of the reference) towards y (east)].
        lat : float
            Latitude of the ship [deg, WGS-84].
        lon : float
            Longitude of the ship [deg, WGS-84].

        Returns
        -------
        float
            The course [deg from the local north at (lat, lon), clockwise], in [0, 360).
        """
        a = math.radians(angle_deg)
        ref = _neu(self.lat, self.lon)
        v = _neu(lat, lon) @ (math.cos(a) * ref[0] + math.sin(a) * ref[1])
        return wrap_360(math.degrees(math.atan2(v[1], v[0])))
