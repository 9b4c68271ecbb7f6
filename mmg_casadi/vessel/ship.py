"""KCS particulars and MMG coefficients, read from the packaged data file ``data/kcs_mmg.toml``.

All coefficients are non-dimensional in the prime-II system built on the DESIGN speed (lengths in L, time in
L/U_des, forces over ½ρU_des²Ld, moments over ½ρU_des²L²d); the data file records the source of every number.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, fields
from functools import lru_cache
from importlib import resources
from pathlib import Path

from mmg_casadi.errors import ParameterError
from mmg_casadi.vessel.vessel_file import check_vessel_data


@dataclass(frozen=True, kw_only=True)
class ShipParams:
    """Ship particulars and MMG coefficients of one hull (see ``kcs_mmg.toml``, ``kvlcc2_mmg.toml``).

    The coefficients with a default belong to one hull form only (``hull_form``): the drift-angle ones
    (``X0`` ... ``Nbrr``) to ``'beta'``, the v-r ones (``R0`` ... ``C2_neg``) to ``'yy2015'``; the loader requires
    every coefficient of the file's form.

    Dimensional particulars: ``L``, ``B``, ``d``, ``DP`` in m; ``U_design`` in m/s; ``rho`` in kg/m³;
    ``n_design_rpm`` in rev/min; ``xG`` in m. Everything else is non-dimensional (prime-II, design speed).

    Parameters
    ----------
    L : float
        Length between perpendiculars (m).
    B : float
        Breadth (m).
    d : float
        Draft (m).
    Cb : float
        Block coefficient.
    displacement : float
        Displacement volume ∇ (m³).
    xG : float
        Longitudinal centre of gravity from midship (m).
    kzz : float
        Yaw radius of gyration over L.
    rho : float
        Water density (kg/m³).
    g : float
        Gravitational acceleration (m/s²).
    Fn_design : float
        Design Froude number.
    U_design : float
        Design speed (m/s).
    m : float
        Non-dimensional mass m'.
    mx : float
        Surge added mass m_x'.
    my : float
        Sway added mass m_y'.
    Jzz : float
        Yaw added moment of inertia J_zz'.
    Izz : float
        Yaw moment of inertia I_zz'.
    X0 : float, default 0
        Surge resistance coefficient X_0' (of u'²).
    Xbb : float, default 0
        Hull surge derivative X_ββ'.
    Xbr_minus_my : float, default 0
        Hull surge derivative X_βr' − m_y'.
    Xrr : float
        Hull surge derivative X_rr'.
    Xbbbb : float, default 0
        Hull surge derivative X_ββββ'.
    Yb : float, default 0
        Hull sway derivative Y_β'.
    Yr_minus_mx : float, default 0
        Hull sway derivative Y_r' − m_x'.
    Ybbb : float, default 0
        Hull sway derivative Y_βββ'.
    Ybbr : float, default 0
        Hull sway derivative Y_ββr'.
    Ybrr : float, default 0
        Hull sway derivative Y_βrr'.
    Yrrr : float
        Hull sway derivative Y_rrr'.
    Nb : float, default 0
        Hull yaw-moment derivative N_β'.
    Nr : float
        Hull yaw-moment derivative N_r'.
    Nbbb : float, default 0
        Hull yaw-moment derivative N_βββ'.
    Nbbr : float, default 0
        Hull yaw-moment derivative N_ββr'.
    Nbrr : float, default 0
        Hull yaw-moment derivative N_βrr'.
    Nrrr : float
        Hull yaw-moment derivative N_rrr'.
    DP : float
        Propeller diameter (m).
    wP : float
        Effective wake fraction at the propeller w_P.
    tP : float
        Thrust deduction factor t_P.
    k0 : float
        Thrust-coefficient polynomial K_T(J) constant term.
    k1 : float
        Thrust-coefficient polynomial K_T(J) linear term.
    k2 : float
        Thrust-coefficient polynomial K_T(J) quadratic term.
    n_design_rpm : float
        Propeller speed at the design self-propulsion point (rev/min).
    xP : float
        Longitudinal propeller position x_P' (over L).
    AR_over_Ld : float
        Rudder area over L·d.
    aspect_ratio : float
        Rudder aspect ratio Λ.
    f_alpha : float
        Rudder lift-gradient coefficient f_α.
    eta : float
        Propeller diameter over rudder span, η = D_P/H_R.
    epsilon : float
        Wake ratio ε between rudder and propeller.
    kappa : float
        Propeller-slipstream factor κ.
    xR : float
        Longitudinal rudder position x_R' (over L).
    lR : float
        Effective longitudinal rudder inflow coordinate l_R' (over L).
    gammaR_pos : float
        Flow-straightening coefficient γ_R for β_P > 0.
    gammaR_neg : float
        Flow-straightening coefficient γ_R for β_P ≤ 0.
    tR : float
        Rudder steering-resistance deduction factor t_R.
    aH : float
        Rudder-hull interaction factor a_H.
    xH : float
        Longitudinal position of the hull-induced rudder force x_H' (over L).
    hull_form : str, default 'beta'
        Force model of the hull: ``'beta'``, the laboratory's drift-angle polynomial with design-speed scaling
        and constant wake (the KCS, ``kcs_mmg.toml``), or ``'yy2015'``, the standard form of Yasukawa &
        Yoshimura (2015) in v' = v/U and r' = rL/U with U² scaling, a wake that depends on β_P and
        flow straightening switched on β_R (the KVLCC2, ``kvlcc2_mmg.toml``).
    R0 : float, default 0
        ``'yy2015'``: straight-running resistance coefficient R_0' (X_H' = -R_0' + ...).
    Xvv, Xvr, Xvvvv : float, default 0
        ``'yy2015'``: hull surge derivatives X_vv', X_vr', X_vvvv' (X_rr' is ``Xrr``).
    Yv, Yr, Yvvv, Yvvr, Yvrr : float, default 0
        ``'yy2015'``: hull sway derivatives Y_v', Y_r', Y_vvv', Y_vvr', Y_vrr' (Y_rrr' is ``Yrrr``).
    Nv, Nvvv, Nvvr, Nvrr : float, default 0
        ``'yy2015'``: hull yaw-moment derivatives N_v', N_vvv', N_vvr', N_vrr' (N_r', N_rrr' are ``Nr``,
        ``Nrrr``).
    C1, C2_pos, C2_neg : float, default 0
        ``'yy2015'``: wake-change coefficients, (1 - w_P)/(1 - w_P0) = 1 + (1 - exp(-C1|β_P|))(C2 - 1), C2 for
        β_P > 0 and β_P < 0; ``wP`` is then w_P0, the wake in straight running.
    """

    L: float
    B: float
    d: float
    Cb: float
    displacement: float
    xG: float
    kzz: float
    rho: float
    g: float
    Fn_design: float
    U_design: float
    m: float
    mx: float
    my: float
    Jzz: float
    Izz: float
    X0: float = 0.0
    Xbb: float = 0.0
    Xbr_minus_my: float = 0.0
    Xrr: float
    Xbbbb: float = 0.0
    Yb: float = 0.0
    Yr_minus_mx: float = 0.0
    Ybbb: float = 0.0
    Ybbr: float = 0.0
    Ybrr: float = 0.0
    Yrrr: float
    Nb: float = 0.0
    Nr: float
    Nbbb: float = 0.0
    Nbbr: float = 0.0
    Nbrr: float = 0.0
    Nrrr: float
    DP: float
    wP: float
    tP: float
    k0: float
    k1: float
    k2: float
    n_design_rpm: float
    xP: float
    AR_over_Ld: float
    aspect_ratio: float
    f_alpha: float
    eta: float
    epsilon: float
    kappa: float
    xR: float
    lR: float
    gammaR_pos: float
    gammaR_neg: float
    tR: float
    aH: float
    xH: float
    hull_form: str = "beta"
    R0: float = 0.0
    Xvv: float = 0.0
    Xvr: float = 0.0
    Xvvvv: float = 0.0
    Yv: float = 0.0
    Yr: float = 0.0
    Yvvv: float = 0.0
    Yvvr: float = 0.0
    Yvrr: float = 0.0
    Nv: float = 0.0
    Nvvv: float = 0.0
    Nvvr: float = 0.0
    Nvrr: float = 0.0
    C1: float = 0.0
    C2_pos: float = 0.0
    C2_neg: float = 0.0

    @property
    def xG_nd(self) -> float:
        """Longitudinal centre of gravity x_G' = x_G/L."""
        return self.xG / self.L

    @property
    def time_scale_s(self) -> float:
        """Seconds per unit of non-dimensional time, L/U_des."""
        return self.L / self.U_design


@dataclass(frozen=True)
class SteeringParams:
    """Steering gear: saturation ``delta_max_deg`` (deg), time constant ``T_delta`` (non-dimensional, L/U_des),
    rate limit ``rate_max_deg_per_s`` (deg/s, full scale).

    Parameters
    ----------
    delta_max_deg : float, optional
        Rudder saturation (deg, in (0, 45]).
    T_delta : float, optional
        Time constant of the steering lag (L/U_des, > 0).
    rate_max_deg_per_s : float, optional
        Rudder rate limit (deg/s full scale, > 0).
    """

    delta_max_deg: float = 35.0
    T_delta: float = 1.0
    rate_max_deg_per_s: float = 5.0

    def __post_init__(self):
        if not 0.0 < self.delta_max_deg <= 45.0:
            raise ParameterError("delta_max_deg", "a number in (0, 45] degrees", self.delta_max_deg)
        if not self.T_delta > 0.0:
            raise ParameterError("T_delta", "a number > 0 (non-dimensional time)", self.T_delta)
        if not self.rate_max_deg_per_s > 0.0:
            raise ParameterError("rate_max_deg_per_s", "a number > 0 deg/s", self.rate_max_deg_per_s)

    @property
    def delta_max(self) -> float:
        """Rudder saturation in rad."""
        return math.radians(self.delta_max_deg)

    def rate_max_nd(self, ship: ShipParams) -> float:
        """Rate limit in rad per unit non-dimensional time: 5°/s × L/U_des.

        Parameters
        ----------
        ship : ShipParams
            Ship whose L/U_des sets the time scale.

        Returns
        -------
        float
            Largest rudder rate (rad per unit time L/U_des).
        """
        return math.radians(self.rate_max_deg_per_s) * ship.time_scale_s


DATA_FILE = "kcs_mmg.toml"


@lru_cache(maxsize=1)
def _packaged_text() -> str:
    """The packaged data file, read once per process (a study builds thousands of scenarios)."""
    return resources.files("mmg_casadi").joinpath("data", DATA_FILE).read_text()


def _read_toml(path: str | Path | None) -> dict:
    if path is None:
        return check_vessel_data(tomllib.loads(_packaged_text()), DATA_FILE, COEFFICIENTS)
    from mmg_casadi.readers import load_toml  # size, UTF-8 and nesting checked while reading
    return check_vessel_data(load_toml(path, "vessel", "vessel file", ParameterError), str(path), COEFFICIENTS)


@lru_cache(maxsize=1)
def _packaged_kcs() -> ShipParams:
    return ship_from_table(_read_toml(None))


COEFFICIENTS: tuple[str, ...] = tuple(f.name for f in fields(ShipParams) if f.name != "hull_form")
"""Every coefficient and particular of :class:`ShipParams` (the keys a vessel data file's tables may hold)."""
HULL_FORMS = ("beta", "yy2015")
"""Hull force models of :class:`ShipParams` (``hull_form``)."""

_FORM_ONLY = {
    "beta": ("X0", "Xbb", "Xbr_minus_my", "Xbbbb", "Yb", "Yr_minus_mx", "Ybbb", "Ybbr", "Ybrr", "Nb", "Nbbb",
             "Nbbr", "Nbrr"),
    "yy2015": ("R0", "Xvv", "Xvr", "Xvvvv", "Yv", "Yr", "Yvvv", "Yvvr", "Yvrr", "Nv", "Nvvv", "Nvvr", "Nvrr",
               "C1", "C2_pos", "C2_neg"),
}


def required_coefficients(hull_form: str) -> tuple[str, ...]:
    """Names of :class:`ShipParams` a data file of ``hull_form`` must give.

    Parameters
    ----------
    hull_form : str
        One of :data:`HULL_FORMS`.

    Returns
    -------
    tuple of str
        Field names of :class:`ShipParams` (``hull_form`` excluded) that the file must give, in field order.

    Examples
    --------
    >>> "R0" in required_coefficients("yy2015"), "R0" in required_coefficients("beta")
    (True, False)
    """
    other = {n for form, names in _FORM_ONLY.items() if form != hull_form for n in names}
    return tuple(f.name for f in fields(ShipParams) if f.name != "hull_form" and f.name not in other)


def ship_from_table(raw: dict) -> ShipParams:
    """:class:`ShipParams` from a parsed vessel data file (blocks ``model``, ``ship``, ``mass``, ``hull``,
    ``propeller``, ``rudder``); every coefficient of the file's hull form is required.

    Parameters
    ----------
    raw : dict
        The parsed TOML file.

    Returns
    -------
    ShipParams
        The ship, every coefficient as a float.
    """
    model = raw.get("model", {})
    form = model.get("hull_form", "beta") if isinstance(model, dict) else None
    if not isinstance(form, str) or form not in HULL_FORMS:
        raise ParameterError("model.hull_form", f"one of: {', '.join(HULL_FORMS)}", form)
    flat: dict = {}
    for block in ("ship", "mass", "hull", "propeller", "rudder"):
        flat.update(raw[block])
    names = {f.name for f in fields(ShipParams)} - {"hull_form"}
    missing = [k for k in required_coefficients(form) if k not in flat]
    if missing:
        raise ParameterError(missing[0], f"a number (every coefficient of the '{form}' form: "
                             f"{', '.join(missing)} missing)", None)
    wrong = sorted(k for k in _FORM_ONLY[[f for f in HULL_FORMS if f != form][0]] if k in flat)
    if wrong:
        raise ParameterError(wrong[0], f"no coefficient of another hull form in a '{form}' file", flat[wrong[0]])
    bad = [k for k in sorted(names & flat.keys())
           if isinstance(flat[k], bool) or not isinstance(flat[k], (int, float)) or not math.isfinite(flat[k])]
    if bad:
        raise ParameterError(bad[0], "a finite number", flat[bad[0]])
    return ShipParams(hull_form=form, **{k: float(v) for k, v in flat.items() if k in names})


def load_ship(path: str | Path) -> ShipParams:
    """Ship particulars and coefficients of a vessel data file (any :data:`HULL_FORMS`).

    Parameters
    ----------
    path : str or pathlib.Path
        TOML data file in the format of the packaged ``kcs_mmg.toml`` / ``kvlcc2_mmg.toml``.

    Returns
    -------
    ShipParams
        The ship of the file.
    """
    return ship_from_table(_read_toml(path))


def load_kcs(path: str | Path | None = None) -> ShipParams:
    """Load the KCS coefficients from the packaged data file (or ``path``).

    Parameters
    ----------
    path : str or pathlib.Path, optional
        TOML data file to read instead of the packaged one.

    Returns
    -------
    ShipParams
        The KCS (packaged file read once and shared; the object is frozen), or the ship of ``path``.

    Examples
    --------
    >>> kcs = load_kcs()
    >>> round(kcs.m, 6), round(kcs.Izz, 6)
    (0.18228, 0.011432)
    """
    return _packaged_kcs() if path is None else ship_from_table(_read_toml(path))  # frozen: sharing is safe


def load_steering(path: str | Path | None = None) -> SteeringParams:
    """Steering-gear parameters from the data file's ``[steering]`` block.

    Parameters
    ----------
    path : str or pathlib.Path, optional
        TOML data file to read instead of the packaged one.

    Returns
    -------
    SteeringParams
        Rudder limit (deg), steering time constant (L/U) and rate limit (deg/s) of the file.
    """
    return steering_from_table(_read_toml(path))


def steering_from_table(raw: dict) -> SteeringParams:
    """:class:`SteeringParams` from the ``[steering]`` block of a parsed vessel data file.

    Parameters
    ----------
    raw : dict
        The parsed TOML file.

    Returns
    -------
    SteeringParams
        Rudder limit (deg), steering time constant (L/U) and rate limit (deg/s) of the block.
    """
    s = raw["steering"]
    for k in ("delta_max_deg", "T_delta", "rate_max_deg_per_s"):
        if not isinstance(s.get(k), (int, float)) or isinstance(s.get(k), bool):
            raise ParameterError(f"steering.{k}", "a number", s.get(k))
    return SteeringParams(float(s["delta_max_deg"]), float(s["T_delta"]), float(s["rate_max_deg_per_s"]))


def load_reference(name: str = "turning_15deg_starboard", path: str | Path | None = None) -> dict:
    """Published validation reference stored in the data file's ``[reference.*]`` tables.

    Parameters
    ----------
    name : str, optional
        Name of the ``[reference.NAME]`` table.
    path : str or pathlib.Path, optional
        TOML data file to read instead of the packaged one.

    Returns
    -------
    dict
        A copy of the ``[reference.NAME]`` table, its keys and units as in the data file.
    """
    return dict(_read_toml(path)["reference"][name])


def derived_masses(ship: ShipParams) -> dict:
    """Mass and added masses recomputed from the particulars and the dimensional added masses of the data source.

    ``m' = ∇/(½L²d)``, ``I_zz' = m'(k_zz² + x_G'²)``; the added masses m_x = 1790.85 t, m_y = 44324.18 t and
    J_zz = 140067300 t·m² (MDLHydroD, Source A) over ½L²d and ½L⁴d.

    Parameters
    ----------
    ship : ShipParams
        Ship whose particulars are used.

    Returns
    -------
    dict
        ``"m"``, ``"mx"``, ``"my"`` (over ½L²d), ``"Jzz"`` (over ½L⁴d) and ``"Izz"`` (``m'(k_zz² + x_G'²)``),
        non-dimensional (prime-II).
    """
    q = 0.5 * ship.L**2 * ship.d
    m = ship.displacement / q
    xg = ship.xG / ship.L
    return {
        "m": m,
        "mx": 1790.85 / q,
        "my": 44324.18 / q,
        "Jzz": 140067300.0 / (0.5 * ship.L**4 * ship.d),
        "Izz": m * (ship.kzz**2 + xg**2),
    }
