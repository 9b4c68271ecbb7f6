"""Environmental disturbances of the MMG model: a uniform ocean current and a steady wind, as CasADi expressions.

Disturbance vector ``env = [V_c, beta_c, U_w, psi_w]`` (:data:`ENV_NAMES`), all in the prime-II system:

* ``V_c``: current speed over the design speed U_des; ``beta_c``: direction the current flows TOWARDS (rad,
  from x towards y, earth-fixed).
* ``U_w``: true wind speed over U_des (e.g. 15 m/s is 15/12.347 = 1.215); ``psi_w``: direction the wind comes
  FROM (rad, from x towards y, earth-fixed), the meteorological convention. A wind from port of a ship heading
  along x has ``psi_w = -pi/2``.

**Current.** The state carries the velocities relative to the water, ``nu_r = [u_r, v_r, r]``, and the
kinematics add the current (Fossen 2021, §10.3; Fossen 2012):

    x_dot = u_r cos(psi) - v_r sin(psi) + V_c cos(beta_c)
    y_dot = u_r sin(psi) + v_r cos(psi) + V_c sin(beta_c)

For a current that is constant and irrotational in the earth-fixed frame, its body-frame components
``u_c = V_c cos(beta_c - psi)``, ``v_c = V_c sin(beta_c - psi)`` obey ``u_c_dot = r v_c``, ``v_c_dot = -r u_c``,
and the rigid-body terms of the MMG equations are the same function of ``nu_r`` as of the ground velocity
``nu = nu_r + nu_c`` (Fossen 2021, §10.3, the property of an irrotational constant current). Hull, propeller
and rudder forces already depend on ``nu_r`` only, so the calm-water equations for ``[u, v, r]`` hold unchanged
with ``u, v`` read as velocities through the water; only the position kinematics change. Ground velocities, for
guidance and metrics, are :func:`ground_velocity`.

**Crab angle.** Over the ground the ship moves along its course ``chi = psi + beta_c`` with the crab angle
``beta_c = atan2(v_g, u_g)`` (:func:`crab_angle`); a course-keeping guidance law (LOS gives a desired course)
steers the heading ``psi_d = chi_d - beta_c`` (Fossen, Pettersen & Galeazzi 2015; Fossen 2021, ch. 12).

**Gusts** (optional, off unless asked for): :func:`gust_speeds` draws a seeded first-order Gauss-Markov
(Ornstein-Uhlenbeck) wind-speed sequence around the mean, to be fed step by step as ``U_w``.

**Wind.** The force on the above-water body follows Blendermann's parametric model (Blendermann 1994,
J. Wind Eng. Ind. Aerodyn. 51:339-351), in the form of Fossen (2021), §10.1.2, with the relative wind angle
``gamma = -atan2(v_rw, u_rw)`` (0 = wind on the bow, +pi/2 = wind from port) and relative wind speed ``V_rw``::

    C_X = -CD_lAF(gamma) cos(gamma) / D,   C_Y = CD_t sin(gamma) / D,
    C_N = (s_L/L_oa - 0.18 (|gamma| - pi/2)) C_Y,   D = 1 - (delta/2) (1 - CD_l/CD_t) sin^2(2 gamma),
    X = q A_F C_X,  Y = q A_L C_Y,  N = q A_L L_oa C_N,   q = rho_a V_rw^2 / 2,   CD_l = CD_lAF A_F / A_L,

``CD_lAF`` switching from its head-wind to its tail-wind value at ``|gamma| = pi/2``. The ``|gamma|`` in C_N makes
the published formula (given for 0 <= gamma <= pi) odd in gamma, as the port/starboard mirror image demands.
The apparent wind is the true wind relative to the ship's GROUND velocity (Fossen 2021, §10.1):
``u_rw = u_g - u_w``, ``v_rw = v_g - v_w`` with ``(u_w, v_w)`` the wind velocity in body axes.

The calm-water model has no air-load term (nor has the source's model with its wind switched off), and its
self-propulsion point u' = 1 at 115.5 rpm is calibrated without one. To keep that model exactly, the wind enters
as the INCREMENT over the still-air load, ``F(apparent wind) - F(still air, apparent = -ground velocity)``, the
way ITTC 7.5-04-01-01.1 (speed/power trials) and ISO 15016 correct trial data for wind. With ``env = 0`` the
disturbance is therefore exactly zero; the ship's own still-air drag (1.3 % of the hull resistance at U_des for
the default windage) stays unmodelled, as in calm water.

Forces are non-dimensionalised like the others: ``X' = X/(rho U_des^2 L d/2)``, ``N' = N/(rho U_des^2 L^2 d/2)``,
so ``X' = (rho_a/rho) (A_F/(L d)) C_X V_rw'^2`` with ``V_rw' = V_rw/U_des``.

References
----------
Blendermann, W. (1994). Parameter identification of wind loads on ships. J. Wind Eng. Ind. Aerodyn. 51, 339-351.
Fossen, T. I. (2021). Handbook of Marine Craft Hydrodynamics and Motion Control, 2nd ed., Wiley, ch. 10
(1st ed. 2011, ch. 8). The Blendermann parameters of :data:`CONTAINER_SHIP_LOADED` are the "container ship,
loaded" row of the table reproduced there, read from the author's MSS toolbox (``blendermann94.m``).
Fossen, T. I., Pettersen, K. Y. & Galeazzi, R. (2015). Line-of-sight path following for Dubins paths with
adaptive sideslip compensation of drift forces. IEEE Trans. Control Syst. Technol. 23(2), 820-827.
Fossen, T. I. (2012). How to incorporate wind, waves and ocean currents in the marine craft equations of motion.
Proc. IFAC MCMC 2012, Genova.
ITTC (2017). Recommended Procedure 7.5-04-01-01.1, Preparation, conduct and analysis of speed/power trials.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from mmg_casadi.errors import ParameterError, check_range

ENV_NAMES = ("V_c", "beta_c", "U_w", "psi_w")
NENV = len(ENV_NAMES)
RHO_AIR = 1.225  # kg/m^3, ISA sea level

_V2_MIN = 1e-20  # below this squared relative air speed (in U_des^2) the wind load is set to exactly zero


@dataclass(frozen=True)
class Environment:
    """Steady disturbance: current ``current_speed`` (fraction of U_des, [0, 1]) flowing towards
    ``current_direction`` (rad), true wind ``wind_speed`` (fraction of U_des, [0, 5]) coming from
    ``wind_direction`` (rad). The defaults are calm water.

    Parameters
    ----------
    current_speed : float, optional
        Current speed (fraction of U_des, [0, 1]).
    current_direction : float, optional
        Direction the current flows towards (rad).
    wind_speed : float, optional
        True wind speed (fraction of U_des, [0, 5]).
    wind_direction : float, optional
        Direction the true wind comes from (rad).

    Examples
    --------
    >>> Environment().vector().tolist()
    [0.0, 0.0, 0.0, 0.0]
    >>> env = Environment.from_si(current_speed=0.5, wind_speed=15.0, wind_direction=-math.pi / 2)
    >>> round(env.current_speed, 4), round(env.wind_speed, 4)
    (0.0405, 1.2149)
    """

    current_speed: float = 0.0
    current_direction: float = 0.0
    wind_speed: float = 0.0
    wind_direction: float = 0.0

    def __post_init__(self):
        check_range("current_speed", self.current_speed, 0.0, 1.0, unit="x U_design")
        check_range("current_direction", self.current_direction, unit="rad")
        check_range("wind_speed", self.wind_speed, 0.0, 5.0, unit="x U_design")
        check_range("wind_direction", self.wind_direction, unit="rad")

    @classmethod
    def from_si(cls, current_speed: float = 0.0, current_direction: float = 0.0, wind_speed: float = 0.0,
                wind_direction: float = 0.0, U_design: float = 12.347) -> "Environment":
        """Environment from speeds in m/s (directions in rad), scaled by the design speed ``U_design`` (m/s).

        Parameters
        ----------
        current_speed : float, optional
            Current speed (m/s).
        current_direction : float, optional
            Direction the current flows towards (rad).
        wind_speed : float, optional
            True wind speed (m/s).
        wind_direction : float, optional
            Direction the true wind comes from (rad).
        U_design : float, optional
            Design speed used for the scaling (m/s).

        Returns
        -------
        Environment
            Speeds in U_des units, directions (rad) unchanged.
        """
        return cls(current_speed / U_design, current_direction, wind_speed / U_design, wind_direction)

    @property
    def calm(self) -> bool:
        """True when there is neither current nor wind."""
        return self.current_speed == 0.0 and self.wind_speed == 0.0

    def vector(self) -> np.ndarray:
        """The Function input ``env = [V_c, beta_c, U_w, psi_w]``.

        Returns
        -------
        numpy.ndarray (4,)
            ``[V_c, beta_c, U_w, psi_w]``: current speed (U_des units), direction it flows towards (rad), true
            wind speed (U_des units), direction the wind comes from (rad).
        """
        return np.array([self.current_speed, self.current_direction, self.wind_speed, self.wind_direction])


@dataclass(frozen=True)
class BlendermannParams:
    """Blendermann (1994) wind-load parameters of a ship type: lateral drag coefficient ``CDt`` (on A_L),
    longitudinal drag coefficients ``CDl_AF_bow`` / ``CDl_AF_stern`` (on A_F, head / tail wind), cross-force
    parameter ``delta`` (all dimensionless).

    Parameters
    ----------
    CDt : float
        Lateral drag coefficient on A_L (> 0).
    CDl_AF_bow : float
        Longitudinal drag coefficient on A_F for head wind (> 0).
    CDl_AF_stern : float
        Longitudinal drag coefficient on A_F for tail wind (> 0).
    delta : float
        Cross-force parameter δ (dimensionless, [0, 1]).
    """

    CDt: float
    CDl_AF_bow: float
    CDl_AF_stern: float
    delta: float

    def __post_init__(self):
        for name in ("CDt", "CDl_AF_bow", "CDl_AF_stern"):
            check_range(name, getattr(self, name), 0.0, None, low_open=True)
        check_range("delta", self.delta, 0.0, 1.0)


#: "Container ship, loaded" (Blendermann 1994, as tabulated in Fossen 2021 §10.1.2).
CONTAINER_SHIP_LOADED = BlendermannParams(CDt=0.90, CDl_AF_bow=0.55, CDl_AF_stern=0.55, delta=0.40)


@dataclass(frozen=True)
class Windage:
    """Above-water geometry: frontal projected area ``A_F`` (m²), lateral projected area ``A_L`` (m²),
    longitudinal position ``s_L`` of the centroid of A_L (m, from midships, positive forward) and length over
    all ``L_oa`` (m); with the wind-load parameters ``coefficients`` and air density ``rho_air`` (kg/m³).

    The default is OUR ESTIMATE for the KCS carrying containers on deck (the published KCS is a bare hull
    without superstructure or cargo), derived as follows:

    * freeboard D - d = 19.0 - 10.8 = 8.2 m: the depth of the source's KCS model, 0.2517 m at
      L_pp = 3.0464 m, scaled to L_pp = 230 m (Source A of ``data/kcs_mmg.toml``);
    * deck cargo: four tiers of 8 ft 6 in containers (4 x 2.59 = 10.4 m) over 0.75 L = 172.5 m, centred
      0.025 L aft of midships, full breadth 32.2 m;
    * deckhouse: 16 m long, 24 m wide, 8 m above the container tiers, centred 0.32 L aft of midships;
    * L_oa is taken as L_pp (the overall length is not among the published particulars we use).

    A_L = 230 x 8.2 + 172.5 x 10.4 + 16 x 8 = 3808 m²; A_F = 32.2 x 8.2 + 32.2 x 10.4 + 24 x 8 = 791 m²;
    s_L = (172.5 x 10.4 x (-5.75) + 16 x 8 x (-73.6)) / 3808 = -5.2 m (the hull freeboard is centred at
    midships): the lateral centroid lies slightly aft of midships.
    :meth:`bare_hull` is the freeboard-only windage of the source's laboratory model.

    Parameters
    ----------
    A_F : float, optional
        Frontal projected area (m²).
    A_L : float, optional
        Lateral projected area (m²).
    s_L : float, optional
        Longitudinal position of the centroid of A_L from midships, positive forward (m).
    L_oa : float, optional
        Length over all (m).
    coefficients : BlendermannParams, optional
        Blendermann wind-load parameters of the ship type.
    rho_air : float, optional
        Air density (kg/m³).

    Examples
    --------
    >>> w = Windage()
    >>> round(w.A_L), round(w.A_F), round(w.s_L, 1)
    (3808, 791, -5.2)
    >>> w.bare_hull().A_F == 32.2 * 8.2
    True
    """

    A_F: float = 32.2 * 8.2 + 32.2 * 10.4 + 24.0 * 8.0
    A_L: float = 230.0 * 8.2 + 172.5 * 10.4 + 16.0 * 8.0
    s_L: float = (172.5 * 10.4 * (-0.025 * 230.0) + 16.0 * 8.0 * (-0.32 * 230.0)) / (
        230.0 * 8.2 + 172.5 * 10.4 + 16.0 * 8.0)
    L_oa: float = 230.0
    coefficients: BlendermannParams = CONTAINER_SHIP_LOADED
    rho_air: float = RHO_AIR

    def __post_init__(self):
        check_range("A_F", self.A_F, 0.0, None, low_open=True, unit="m^2")
        check_range("A_L", self.A_L, 0.0, None, low_open=True, unit="m^2")
        check_range("L_oa", self.L_oa, 0.0, None, low_open=True, unit="m")
        check_range("s_L", self.s_L, -0.5 * self.L_oa, 0.5 * self.L_oa, unit="m")
        check_range("rho_air", self.rho_air, 0.0, None, low_open=True, unit="kg/m^3")

    @classmethod
    def bare_hull(cls, L: float = 230.0, B: float = 32.2, freeboard: float = 8.2) -> "Windage":
        """Freeboard-only windage (no deck cargo, no deckhouse): A_F = B x freeboard, A_L = L x freeboard,
        centroid at midships.

        Parameters
        ----------
        L : float, optional
            Length, used for A_L and L_oa (m).
        B : float, optional
            Breadth (m).
        freeboard : float, optional
            Freeboard height above the waterline (m).

        Returns
        -------
        Windage
            ``A_F = B freeboard``, ``A_L = L freeboard`` (m²), ``s_L = 0`` and ``L_oa = L`` (m).
        """
        return cls(A_F=B * freeboard, A_L=L * freeboard, s_L=0.0, L_oa=L)


def current_body(V_c, beta_c, psi):
    """Body-frame components ``(u_c, v_c)`` of a current of speed ``V_c`` flowing towards ``beta_c``.

    Parameters
    ----------
    V_c : float or casadi.SX or casadi.MX
        Current speed (U_des units).
    beta_c : float or casadi.SX or casadi.MX
        Direction the current flows towards (rad).
    psi : float or casadi.SX or casadi.MX
        Heading ψ (rad).

    Returns
    -------
    u_c : float or casadi.SX or casadi.MX
        Current velocity along the ship's x axis (U_des units).
    v_c : float or casadi.SX or casadi.MX
        Current velocity along the ship's y axis (U_des units).

    Examples
    --------
    >>> [round(float(c), 12) for c in current_body(0.1, math.pi / 2, 0.0)]   # current towards starboard
    [0.0, 0.1]
    """
    return V_c * ca.cos(beta_c - psi), V_c * ca.sin(beta_c - psi)


def ground_velocity(u_r, v_r, psi, V_c, beta_c):
    """Ground (over-the-ground) body velocities ``(u_g, v_g) = (u_r + u_c, v_r + v_c)`` from the velocities
    through the water of the state.

    Parameters
    ----------
    u_r : float or casadi.SX or casadi.MX
        Surge velocity through the water (U_des units).
    v_r : float or casadi.SX or casadi.MX
        Sway velocity through the water (U_des units).
    psi : float or casadi.SX or casadi.MX
        Heading ψ (rad).
    V_c : float or casadi.SX or casadi.MX
        Current speed (U_des units).
    beta_c : float or casadi.SX or casadi.MX
        Direction the current flows towards (rad).

    Returns
    -------
    u_g : float or casadi.SX or casadi.MX
        Surge velocity over the ground (U_des units).
    v_g : float or casadi.SX or casadi.MX
        Sway velocity over the ground (U_des units).

    Examples
    --------
    >>> [round(float(c), 12) for c in ground_velocity(1.0, 0.0, 0.0, 0.1, math.pi)]   # head current
    [0.9, 0.0]
    """
    u_c, v_c = current_body(V_c, beta_c, psi)
    return u_r + u_c, v_r + v_c


def velocity_over_ground(u_r, v_r, psi, V_c, beta_c):
    """Earth-fixed velocity over the ground ``(x_dot, y_dot) = R(psi) (u_r, v_r) + V_c (cos beta_c, sin beta_c)``,
    the velocity that obstacle-avoidance guidance (fields, velocity obstacle) must use.

    Parameters
    ----------
    u_r : float or casadi.SX or casadi.MX
        Surge velocity through the water (U_des units).
    v_r : float or casadi.SX or casadi.MX
        Sway velocity through the water (U_des units).
    psi : float or casadi.SX or casadi.MX
        Heading ψ (rad).
    V_c : float or casadi.SX or casadi.MX
        Current speed (U_des units).
    beta_c : float or casadi.SX or casadi.MX
        Direction the current flows towards (rad).

    Returns
    -------
    x_dot : float or casadi.SX or casadi.MX
        Earth-fixed x velocity over the ground (L per L/U, i.e. U_des units).
    y_dot : float or casadi.SX or casadi.MX
        Earth-fixed y velocity over the ground (U_des units).

    Examples
    --------
    >>> [round(float(c), 12) for c in velocity_over_ground(1.0, 0.0, math.pi / 2, 0.1, math.pi / 2)]
    [0.0, 1.1]
    """
    x_c, y_c = current_kinematics(V_c, beta_c)
    return u_r * ca.cos(psi) - v_r * ca.sin(psi) + x_c, u_r * ca.sin(psi) + v_r * ca.cos(psi) + y_c


def current_kinematics(V_c, beta_c):
    """Earth-fixed drift ``(x_dot, y_dot)`` added by the current to the position kinematics.

    Parameters
    ----------
    V_c : float or casadi.SX or casadi.MX
        Current speed (U_des units).
    beta_c : float or casadi.SX or casadi.MX
        Direction the current flows towards (rad).

    Returns
    -------
    x_dot : float or casadi.SX or casadi.MX
        Earth-fixed x component of the current, ``V_c cos(beta_c)`` (U_des units).
    y_dot : float or casadi.SX or casadi.MX
        Earth-fixed y component of the current, ``V_c sin(beta_c)`` (U_des units).

    Examples
    --------
    >>> [round(float(c), 12) for c in current_kinematics(0.1, 0.0)]
    [0.1, 0.0]
    """
    return V_c * ca.cos(beta_c), V_c * ca.sin(beta_c)


def apparent_wind(u_g, v_g, psi, U_w, psi_w):
    """Apparent (relative) wind ``(u_rw, v_rw)`` in body axes: ship ground velocity minus wind velocity, for a
    true wind of speed ``U_w`` coming FROM ``psi_w``.

    Parameters
    ----------
    u_g : float or casadi.SX or casadi.MX
        Surge velocity over the ground (U_des units).
    v_g : float or casadi.SX or casadi.MX
        Sway velocity over the ground (U_des units).
    psi : float or casadi.SX or casadi.MX
        Heading ψ (rad).
    U_w : float or casadi.SX or casadi.MX
        True wind speed (U_des units).
    psi_w : float or casadi.SX or casadi.MX
        Direction the true wind comes from (rad).

    Returns
    -------
    u_rw : float or casadi.SX or casadi.MX
        Surge component of the apparent wind in body axes (U_des units).
    v_rw : float or casadi.SX or casadi.MX
        Sway component of the apparent wind in body axes (U_des units).

    Examples
    --------
    >>> [round(float(c), 12) + 0.0 for c in apparent_wind(0.0, 0.0, 0.0, 1.0, -math.pi / 2)]  # from port
    [0.0, -1.0]
    """
    u_w = -U_w * ca.cos(psi_w - psi)  # the wind blows towards psi_w + pi
    v_w = -U_w * ca.sin(psi_w - psi)
    return u_g - u_w, v_g - v_w


def blendermann_coefficients(gamma, params: BlendermannParams = CONTAINER_SHIP_LOADED, *, A_F: float,
                             A_L: float, s_L_over_Loa: float):
    """Wind-load coefficients ``(C_X, C_Y, C_N)`` of Blendermann (1994) at relative wind angle ``gamma`` (rad).

    ``C_X`` is on the frontal area A_F, ``C_Y`` on the lateral area A_L and ``C_N`` on A_L L_oa (moment about
    midships); see the module docstring for the formulae.

    Parameters
    ----------
    gamma : float or casadi.SX or casadi.MX
        Relative wind angle γ (rad, 0 for head wind).
    params : BlendermannParams, optional
        Wind-load parameters of the ship type.
    A_F : float
        Frontal projected area (m²).
    A_L : float
        Lateral projected area (m²).
    s_L_over_Loa : float
        Centroid position of A_L over L_oa (positive forward).

    Returns
    -------
    C_X : float or casadi.SX or casadi.MX
        Longitudinal wind-force coefficient (on A_F, dimensionless).
    C_Y : float or casadi.SX or casadi.MX
        Lateral wind-force coefficient (on A_L, dimensionless).
    C_N : float or casadi.SX or casadi.MX
        Yaw wind-moment coefficient (on A_L L_oa, about midships, dimensionless).

    Examples
    --------
    >>> cx, cy, cn = blendermann_coefficients(0.0, A_F=791.0, A_L=3808.0, s_L_over_Loa=-0.02)
    >>> float(cx), float(cy), float(cn)       # head wind: C_X = -CD_lAF(0), no side force
    (-0.55, 0.0, 0.0)
    >>> [round(float(c), 4) for c in blendermann_coefficients(math.pi / 2, A_F=791.0, A_L=3808.0,
    ...                                                       s_L_over_Loa=-0.02)]
    [-0.0, 0.9, -0.018]
    """
    p = params
    cos_g, sin_g = ca.cos(gamma), ca.sin(gamma)
    cdl_af = ca.if_else(cos_g >= 0, p.CDl_AF_bow, p.CDl_AF_stern)
    cdl = cdl_af * A_F / A_L
    den = 1.0 - 0.5 * p.delta * (1.0 - cdl / p.CDt) * ca.sin(2.0 * gamma) ** 2
    C_X = -cdl_af * cos_g / den
    C_Y = p.CDt * sin_g / den
    C_N = (s_L_over_Loa - 0.18 * (ca.fabs(gamma) - 0.5 * math.pi)) * C_Y
    return C_X, C_Y, C_N


def _wind_load_nd(ship, windage: Windage, u_rw, v_rw):
    """Non-dimensional (X', Y', N') of an apparent wind (u_rw, v_rw) in U_des units; zero at zero air speed."""
    V2 = u_rw**2 + v_rw**2
    moving = V2 > _V2_MIN
    # safe arguments keep the derivative of atan2 finite where the load is masked to zero
    gamma = -ca.atan2(ca.if_else(moving, v_rw, 0.0), ca.if_else(moving, u_rw, 1.0))
    C_X, C_Y, C_N = blendermann_coefficients(gamma, windage.coefficients, A_F=windage.A_F, A_L=windage.A_L,
                                             s_L_over_Loa=windage.s_L / windage.L_oa)
    q = (windage.rho_air / ship.rho) * V2 / (ship.L * ship.d)
    X = ca.if_else(moving, q * windage.A_F * C_X, 0.0)
    Y = ca.if_else(moving, q * windage.A_L * C_Y, 0.0)
    N = ca.if_else(moving, q * windage.A_L * windage.L_oa / ship.L * C_N, 0.0)
    return X, Y, N


def wind_forces(ship, windage: Windage, u_g, v_g, psi, U_w, psi_w):
    """Non-dimensional wind load increment ``(X_W', Y_W', N_W')`` over the still-air load, on a ship with
    ground velocity ``(u_g, v_g)`` (body axes, U_des units) and heading ``psi`` in a true wind ``U_w`` (U_des
    units) coming from ``psi_w``.

    Parameters
    ----------
    ship : ShipParams
        Ship particulars (L, d, rho).
    windage : Windage
        Above-water geometry and wind-load parameters.
    u_g : float or casadi.SX or casadi.MX
        Surge velocity over the ground (U_des units).
    v_g : float or casadi.SX or casadi.MX
        Sway velocity over the ground (U_des units).
    psi : float or casadi.SX or casadi.MX
        Heading ψ (rad).
    U_w : float or casadi.SX or casadi.MX
        True wind speed (U_des units).
    psi_w : float or casadi.SX or casadi.MX
        Direction the true wind comes from (rad).

    Returns
    -------
    X_W : float or casadi.SX or casadi.MX
        Non-dimensional wind surge force increment X_W' (prime-II).
    Y_W : float or casadi.SX or casadi.MX
        Non-dimensional wind sway force increment Y_W' (prime-II).
    N_W : float or casadi.SX or casadi.MX
        Non-dimensional wind yaw moment increment N_W' (prime-II).

    Examples
    --------
    >>> from mmg_casadi.vessel.ship import load_kcs
    >>> X, Y, N = wind_forces(load_kcs(), Windage(), 0.0, 0.0, 0.0, 1.0, -math.pi / 2)  # at rest, from port
    >>> float(Y) > 0 > float(N)          # pushed to starboard, bow turned to port (centroid aft)
    True
    >>> [float(f) for f in wind_forces(load_kcs(), Windage(), 1.0, 0.0, 0.3, 0.0, 1.0)]  # no wind: zero
    [0.0, 0.0, 0.0]
    """
    u_rw, v_rw = apparent_wind(u_g, v_g, psi, U_w, psi_w)
    X, Y, N = _wind_load_nd(ship, windage, u_rw, v_rw)
    X0, Y0, N0 = _wind_load_nd(ship, windage, u_g, v_g)  # still air
    return X - X0, Y - Y0, N - N0


def crab_angle(u_g, v_g):
    """Crab angle β_c = atan2(v_g, u_g) between heading and course over the ground (rad, positive when the ship
    is set to starboard); the course is ψ + β_c.

    Parameters
    ----------
    u_g : float or casadi.SX or casadi.MX
        Surge velocity over the ground (U_des units).
    v_g : float or casadi.SX or casadi.MX
        Sway velocity over the ground (U_des units).

    Returns
    -------
    float or casadi.SX or casadi.MX
        Crab angle β_c (rad, in (-π, π]).

    Examples
    --------
    >>> round(math.degrees(float(crab_angle(1.0, 0.1))), 4)   # set to starboard by 0.1 U
    5.7106
    """
    return ca.atan2(v_g, u_g)


def gust_speeds(n_steps: int, dt: float, mean_speed: float, *, intensity: float = 0.1,
                time_constant: float = 5.0, seed: int = 0) -> np.ndarray:
    """Seeded gusty wind-speed sequence ``U_w[k]`` (U_des units) at steps of ``dt`` (L/U_des), for ``env[2]``.

    A first-order Gauss-Markov (Ornstein-Uhlenbeck) process around ``mean_speed`` with standard deviation
    ``intensity * mean_speed`` (turbulence intensity, [0, 0.5]) and correlation time ``time_constant``
    (L/U_des; 5 is about 93 s for the KCS), so its spectrum is ``S(ω) = 2σ²T/(1 + ω²T²)``. It is sampled
    exactly: ``U[k+1] = m + a (U[k] - m) + σ sqrt(1 - a²) w[k]``, ``a = exp(-dt/T)``, ``w[k]`` standard normal,
    ``U[0]`` drawn from the stationary distribution; speeds are clipped at 0. A simple filtered noise in the
    sense of the issue; the spectral wind-gust models (Harris, NORSOK) of Fossen (2021) §10.1 are not used.

    Parameters
    ----------
    n_steps : int
        Number of samples (≥ 1).
    dt : float
        Sample interval (L/U_des, > 0).
    mean_speed : float
        Mean wind speed (U_des units, [0, 5]).
    intensity : float, optional
        Turbulence intensity σ/mean (in [0, 0.5]).
    time_constant : float, optional
        Correlation time T (L/U_des, > 0).
    seed : int, optional
        Seed of the random generator.

    Returns
    -------
    numpy.ndarray (n_steps,)
        Wind speed ``U_w[k]`` at each step (U_des units, ≥ 0).

    Examples
    --------
    >>> g = gust_speeds(1000, 0.1, 1.2, seed=3)
    >>> g.shape, bool(np.all(g == gust_speeds(1000, 0.1, 1.2, seed=3)))
    ((1000,), True)
    >>> bool(np.all(gust_speeds(5, 0.1, 1.2, intensity=0.0) == 1.2))
    True
    """
    if not isinstance(n_steps, (int, np.integer)) or isinstance(n_steps, bool) or n_steps < 1:
        raise ParameterError("n_steps", "an integer >= 1", n_steps)
    check_range("dt", dt, 0.0, None, low_open=True, unit="L/U_design")
    check_range("mean_speed", mean_speed, 0.0, 5.0, unit="x U_design")
    check_range("intensity", intensity, 0.0, 0.5)
    check_range("time_constant", time_constant, 0.0, None, low_open=True, unit="L/U_design")
    rng = np.random.default_rng(seed)
    sigma = intensity * mean_speed
    a = math.exp(-dt / time_constant)
    w = rng.standard_normal(n_steps)
    dev = np.empty(n_steps)
    dev[0] = sigma * w[0]
    b = sigma * math.sqrt(1.0 - a * a)
    for k in range(1, n_steps):
        dev[k] = a * dev[k - 1] + b * w[k]
    return np.maximum(mean_speed + dev, 0.0)
