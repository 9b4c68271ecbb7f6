"""WGS-84 geodesy of the maritime-schema interchange: latitude/longitude on a local plane and back.

The plane (x north, y east, metres) is the ellipsoidal azimuthal equidistant projection about a reference point:
a point at geodesic distance ``s`` and azimuth ``a`` from the reference goes to ``(s cos a, s sin a)``. Distances
and azimuths are those of the geodesic on the WGS-84 ellipsoid (a = 6378137 m, f = 1/298.257223563), computed
with Karney's algorithms (C. F. F. Karney, "Algorithms for geodesics", J. Geodesy 87, 43-55, 2013,
doi:10.1007/s00190-012-0578-z) as implemented in his ``geographiclib`` package: the map and its inverse agree to
a few nanometres, and distances and bearings from the reference are exact.

A projection cannot keep every distance. About the reference the azimuthal equidistant one stretches distances
across the radial direction by ``s/m`` (``m`` the reduced length of the geodesic, Karney 2013; ``s/m - 1`` is
about ``s²/(6 R²)``), so the error of a distance between two points grows as the cube of their distance from the
reference. Positions are therefore accepted only within :data:`MAX_RANGE` of the reference: there every distance
between two accepted points is within 0.7 m of the geodesic one (largest over pairs of points on circles about
the reference at 0°, ±58° and 80° of latitude: 0.4 m within 50 km, 0.7 m within 60 km, 1.1 m within 70 km,
3.1 m within 100 km). A position beyond it raises a :class:`~mmg_casadi.errors.ScenarioError` naming the field
and the range.

Courses and headings are given against the local north of each ship. The plane's Jacobian at a point maps them
exactly: along the geodesic from the reference (azimuth ``a2`` at the point) the scale is 1, across it ``s/m``
(GeographicLib's ``AzimuthalEquidistant`` returns ``m/s`` as its reciprocal azimuthal scale), so a course ``c``
becomes the plane angle ``a1 + atan2(sin(c - a2) s/m, cos(c - a2))``;
:meth:`LocalPlane.course_from_plane` inverts it. Used by
:mod:`mmg_casadi.scenarios.maritime_schema` (reading) and :mod:`mmg_casadi.scenarios.maritime_export` (writing).
A converted scenario records its plane's reference in a comment (:func:`scenario_header`, read back by
:func:`read_header`).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from geographiclib.geodesic import Geodesic

from mmg_casadi.errors import ScenarioError

WGS84 = Geodesic.WGS84
"""The WGS-84 ellipsoid's geodesic (Karney 2013; ``geographiclib``)."""
MAX_RANGE = 60_000.0
"""Largest accepted geodesic distance from the plane's reference [m] (there distances are kept to < 1 m)."""

_INVERSE = Geodesic.STANDARD | Geodesic.REDUCEDLENGTH
_UNIT_SCALE_BELOW = 1.0
"""Closer to the reference than this [m] the across-track scale ``s/m`` is taken as 1."""
_SLACK = 1e-6
"""A point this far [m] beyond ``max_range`` still counts (so a point written at the range, rounded, reads back)."""


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


def initial_azimuth(lat1: float, lon1: float, lat2: float, lon2: float) -> float:
    """Azimuth [deg from north, clockwise, in [0, 360)] at the first point of the geodesic to the second.

    Parameters
    ----------
    lat1, lon1 : float
        The first point [deg, WGS-84].
    lat2, lon2 : float
        The second point [deg, WGS-84].

    Returns
    -------
    float
        The geodesic's azimuth at the first point (Karney 2013).

    Examples
    --------
    >>> round(initial_azimuth(0.0, 0.0, 0.0, 1.0), 9), round(initial_azimuth(58.0, 10.0, 57.0, 10.0), 9)
    (90.0, 180.0)
    """
    return wrap_360(WGS84.Inverse(lat1, lon1, lat2, lon2, Geodesic.AZIMUTH)["azi1"])


@dataclass(frozen=True)
class LocalPlane:
    """Local plane (x north, y east, metres): the azimuthal equidistant projection about ``lat``, ``lon``.

    Points farther than ``max_range`` from the reference (geodesic distance) are refused, in either direction.

    Parameters
    ----------
    lat : float
        Latitude of the reference point (the plane's origin) [deg, WGS-84, north positive], in [-90, 90].
    lon : float
        Longitude of the reference point [deg, WGS-84, east positive], in [-180, 180].
    max_range : float, optional
        Largest accepted distance from the reference [m]; default :data:`MAX_RANGE`.

    Examples
    --------
    >>> plane = LocalPlane(58.61, 10.59)
    >>> plane.to_plane(58.61, 10.59)
    (0.0, 0.0)
    >>> x, y = plane.to_plane(58.70, 10.80)
    >>> lat, lon = plane.to_geodetic(x, y)
    >>> abs(lat - 58.70) < 1e-12 and abs(lon - 10.80) < 1e-12
    True
    >>> plane.to_plane(-58.0, 20.0, field="targetShips[0].initial.position")
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.ScenarioError: targetShips[0].initial.position: expected a position within 60 km (geodesic distance) of the reference 58.61, 10.59, got '-58.0, 20.0 (12957.2 km away)'
    """

    lat: float
    lon: float
    max_range: float = MAX_RANGE

    def _refuse(self, field: str, what: str, distance: float):
        raise ScenarioError(field, f"a position within {self.max_range / 1000:g} km (geodesic distance) of the "
                            f"reference {self.lat!r}, {self.lon!r}", f"{what} ({distance / 1000:.1f} km away)")

    def _inverse(self, lat: float, lon: float, field: str) -> dict:
        g = WGS84.Inverse(self.lat, self.lon, lat, lon, _INVERSE)
        if not g["s12"] <= self.max_range + _SLACK:
            self._refuse(field, f"{lat!r}, {lon!r}", g["s12"])
        return g

    def distance(self, lat: float, lon: float) -> float:
        """Geodesic distance [m] of (lat, lon) from the reference.

        Parameters
        ----------
        lat, lon : float
            The point [deg, WGS-84].

        Returns
        -------
        float
            The distance along the geodesic (Karney 2013).
        """
        return WGS84.Inverse(self.lat, self.lon, lat, lon, Geodesic.DISTANCE)["s12"]

    def to_plane(self, lat: float, lon: float, *, field: str = "position") -> tuple[float, float]:
        """(x north, y east) [m] of a point on the ellipsoid.

        Parameters
        ----------
        lat : float
            Latitude of the point [deg, WGS-84].
        lon : float
            Longitude of the point [deg, WGS-84].
        field : str, optional
            The point's name in the error raised beyond ``max_range``.

        Returns
        -------
        (float, float)
            The point on the plane: its geodesic distance from the reference times the cosine and the sine of
            the geodesic's azimuth at the reference.

        Raises
        ------
        ScenarioError
            If the point lies farther than ``max_range`` from the reference.
        """
        g = self._inverse(lat, lon, field)
        if g["s12"] == 0.0:
            return 0.0, 0.0
        a = math.radians(g["azi1"])
        return g["s12"] * math.cos(a), g["s12"] * math.sin(a)

    def to_geodetic(self, x: float, y: float, *, field: str = "point") -> tuple[float, float]:
        """(lat, lon) [deg] of the point whose image on the plane is (x, y): the inverse of :meth:`to_plane`.

        Parameters
        ----------
        x : float
            Metres north of the reference, in the plane.
        y : float
            Metres east of the reference, in the plane.
        field : str, optional
            The point's name in the error raised beyond ``max_range``.

        Returns
        -------
        (float, float)
            Latitude and longitude [deg, WGS-84], longitude in [-180, 180].

        Raises
        ------
        ScenarioError
            If ``hypot(x, y)`` exceeds ``max_range``.
        """
        s = math.hypot(x, y)
        if not s <= self.max_range + _SLACK:
            self._refuse(field, f"x = {x:.1f} m, y = {y:.1f} m", s)
        g = WGS84.Direct(self.lat, self.lon, math.degrees(math.atan2(y, x)), s, Geodesic.LATITUDE | Geodesic.LONGITUDE)
        return g["lat2"], g["lon2"]

    def _frame(self, lat: float, lon: float, field: str) -> tuple[float, float, float]:
        """(a1, a2, s/m) at a point: azimuths at the reference and at the point [deg], the across-track scale."""
        g = self._inverse(lat, lon, field)
        # s/m - 1 is about K s^2 / 6 (K the Gaussian curvature): 4e-15 at 1 m, below which the ratio of the two
        # rounded lengths would be noise (a point 1e-9 m away gives 1.0024)
        scale = g["s12"] / g["m12"] if g["s12"] > _UNIT_SCALE_BELOW else 1.0
        return g["azi1"], g["azi2"], scale

    def course_to_plane(self, course_deg: float, lat: float, lon: float, *, field: str = "position") -> float:
        """A course [deg from local north, clockwise] at (lat, lon) as an angle in the plane [deg from x to y].

        Parameters
        ----------
        course_deg : float
            Course or heading [deg from the local north at (lat, lon), clockwise].
        lat : float
            Latitude of the ship [deg, WGS-84].
        lon : float
            Longitude of the ship [deg, WGS-84].
        field : str, optional
            The position's name in the error raised beyond ``max_range``.

        Returns
        -------
        float
            The direction in the plane [deg from x (north of the reference) towards y (east)], in [0, 360).
        """
        a1, a2, scale = self._frame(lat, lon, field)
        c = math.radians(course_deg - a2)
        return wrap_360(a1 + math.degrees(math.atan2(math.sin(c) * scale, math.cos(c))))

    def course_from_plane(self, angle_deg: float, lat: float, lon: float, *, field: str = "position") -> float:
        """The inverse of :meth:`course_to_plane`: a plane angle as a course at (lat, lon).

        Parameters
        ----------
        angle_deg : float
            Direction in the plane [deg from x (north of the reference) towards y (east)].
        lat : float
            Latitude of the ship [deg, WGS-84].
        lon : float
            Longitude of the ship [deg, WGS-84].
        field : str, optional
            The position's name in the error raised beyond ``max_range``.

        Returns
        -------
        float
            The course [deg from the local north at (lat, lon), clockwise], in [0, 360).
        """
        a1, a2, scale = self._frame(lat, lon, field)
        t = math.radians(angle_deg - a1)
        return wrap_360(a2 + math.degrees(math.atan2(math.sin(t) / scale, math.cos(t))))


_HEADER = re.compile(r"^# maritime-schema reference: lat = (\S+), lon = (\S+), length = (\S+) m$", re.M)


def scenario_header(plane: LocalPlane, unit_m: float) -> str:
    """A TOML comment recording the reference of a converted scenario (read back by :func:`read_header`).

    Parameters
    ----------
    plane : LocalPlane
        The plane the scenario is drawn in; its reference ``lat``, ``lon`` [deg] are recorded.
    unit_m : float
        The length unit [m per ship length] of the scenario.

    Returns
    -------
    str
        Two comment lines, each ending with a newline, to be put before the scenario's TOML text.

    Examples
    --------
    >>> read_header(scenario_header(LocalPlane(58.5, 10.25), 230.0))
    (58.5, 10.25, 230.0)
    """
    return (f"# maritime-schema reference: lat = {plane.lat!r}, lon = {plane.lon!r}, length = {unit_m!r} m\n"
            "# (x north, y east in the azimuthal equidistant plane about this point; lengths in ship lengths)\n")


def read_header(text: str):
    """(lat, lon, length_m) from a :func:`scenario_header` comment in ``text``, or None.

    Parameters
    ----------
    text : str
        Text of a scenario TOML file; the first header line anywhere in it counts.

    Returns
    -------
    (float, float, float) or None
        Reference latitude and longitude [deg] and the length unit [m]; None if there is no header line or
        one of its numbers is not a finite float in its range (latitude [-90, 90], longitude [-180, 180], length
        (0, 1000] m).

    Examples
    --------
    >>> read_header("[settings]") is None
    True
    """
    m = _HEADER.search(text)
    if m is None:
        return None
    try:
        values = tuple(float(v) for v in m.groups())
    except ValueError:
        return None
    lat, lon, length = values
    ok = all(math.isfinite(v) for v in values) and abs(lat) <= 90.0 and abs(lon) <= 180.0 and 0.0 < length <= 1000.0
    return values if ok else None
