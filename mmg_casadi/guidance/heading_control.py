"""PD heading control (paper §3.3).

Positive rudder turns the ship to starboard (ψ increasing), so δ_c = −K_p e − K_d r with e = ψ − ψ_d turns the
ship towards ψ_d. The heading error is wrapped to (-π, π], so headings on either side of ±π are close.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from mmg_casadi.vessel.actuators import saturate
from mmg_casadi.params import check_fields
from mmg_casadi.params import field as param_field
from mmg_casadi.guidance.ilos import wrap_angle


@dataclass(frozen=True)
class PdHeadingParams:
    """PD heading-controller parameters (paper Table 2).

    ``kp``: proportional gain K_p^c (rad of rudder per rad of heading error, > 0); ``kd``: derivative gain K_d^c
    (rad of rudder per unit non-dimensional yaw rate, ≥ 0); ``delta_max_deg``: command saturation (deg, (0, 45]).

    Parameters
    ----------
    kp : float
        Proportional gain K_p^c (rad of rudder per rad of heading error, > 0).
    kd : float
        Derivative gain K_d^c (rad of rudder per unit non-dimensional yaw rate, ≥ 0).
    delta_max_deg : float
        Rudder-command saturation (deg, in (0, 45]).
    """

    kp: float = param_field("kp")
    kd: float = param_field("kd")
    delta_max_deg: float = param_field("delta_max_deg")

    def __post_init__(self):
        check_fields(self)

    @property
    def delta_max(self) -> float:
        """Command saturation in rad."""
        return math.radians(self.delta_max_deg)


def heading_error(psi, psi_d):
    """Heading error e = ψ − ψ_d wrapped to (-π, π] (rad).

    Parameters
    ----------
    psi : float or casadi.SX or casadi.MX
        Actual heading ψ (rad).
    psi_d : float or casadi.SX or casadi.MX
        Desired heading ψ_d (rad).

    Returns
    -------
    float or casadi.SX or casadi.MX
        ``e`` (rad, in (-π, π]).

    Examples
    --------
    >>> import math
    >>> round(math.degrees(float(heading_error(math.radians(-179), math.radians(179)))), 6)
    2.0
    """
    return wrap_angle(psi - psi_d)  # eq. (Eq 18a)


def pd_heading(psi, psi_d, r, kp, kd, delta_max):
    """Commanded rudder δ_c = sat(−K_p e − K_d r, ±δ_max) (rad); the yaw rate r stands for ė (ψ̇_d ≈ 0).

    Parameters
    ----------
    psi : float or casadi.SX or casadi.MX
        Actual heading ψ (rad).
    psi_d : float or casadi.SX or casadi.MX
        Desired heading ψ_d (rad).
    r : float or casadi.SX or casadi.MX
        Non-dimensional yaw rate (rad per unit time L/U).
    kp : float
        Proportional gain K_p^c (> 0).
    kd : float
        Derivative gain K_d^c (≥ 0).
    delta_max : float
        Rudder-command saturation (rad).

    Returns
    -------
    float or casadi.SX or casadi.MX
        Commanded rudder angle δ_c (rad, within ±``delta_max``).

    Examples
    --------
    >>> import math
    >>> round(float(pd_heading(0.0, math.radians(5), 0.0, 3.5, 4.0, math.radians(35))), 6)
    0.305433
    >>> float(pd_heading(0.0, 0.0, -0.1, 3.5, 4.0, 0.2))
    0.2
    """
    e = heading_error(psi, psi_d)  # eq. (Eq 18a)
    return saturate(-kp * e - kd * r, delta_max)  # eq. (PD_control)
