"""PD heading control (mmg_casadi.guidance.heading_control)."""

from __future__ import annotations

import math

import casadi as ca
import pytest

from mmg_casadi.guidance.heading_control import PdHeadingParams, heading_error, pd_heading
from mmg_casadi.errors import ParameterError

D35 = math.radians(35.0)


def test_params_defaults():
    p = PdHeadingParams()
    assert (p.kp, p.kd, p.delta_max_deg) == (3.5, 4.0, 35.0)
    assert p.delta_max == pytest.approx(D35)
    assert PdHeadingParams(delta_max_deg=45.0).delta_max == pytest.approx(math.pi / 4)
    assert PdHeadingParams(kd=0.0).kd == 0.0


@pytest.mark.parametrize("kwargs, field", [
    ({"kp": 0.0}, "kp"), ({"kp": -1.0}, "kp"), ({"kd": -0.1}, "kd"),
    ({"delta_max_deg": 0.0}, "delta_max_deg"), ({"delta_max_deg": 46.0}, "delta_max_deg"),
    ({"kp": "fast"}, "kp"),
])
def test_params_validation(kwargs, field):
    with pytest.raises(ParameterError) as err:
        PdHeadingParams(**kwargs)
    assert err.value.field == field


@pytest.mark.parametrize("psi_deg, psi_d_deg, e_deg", [
    (10.0, 0.0, 10.0), (0.0, 10.0, -10.0), (-179.0, 179.0, 2.0), (179.0, -179.0, -2.0),
    (-179.5, 179.5, 1.0), (90.0, -90.0, 180.0), (350.0, 0.0, -10.0),
])
def test_heading_error_wraps(psi_deg, psi_d_deg, e_deg):
    e = float(heading_error(math.radians(psi_deg), math.radians(psi_d_deg)))
    assert math.degrees(e) == pytest.approx(e_deg)
    assert -math.pi < e <= math.pi


def test_pd_sign_turns_towards_desired_heading():
    # desired heading to starboard of the current one → positive (starboard) rudder
    assert float(pd_heading(0.0, math.radians(5.0), 0.0, 3.5, 4.0, D35)) == pytest.approx(3.5 * math.radians(5.0))
    # a yaw rate already towards starboard is damped
    assert float(pd_heading(0.0, 0.0, 0.05, 3.5, 4.0, D35)) == pytest.approx(-0.2)


def test_pd_saturates():
    assert float(pd_heading(0.0, math.radians(90.0), 0.0, 3.5, 4.0, D35)) == pytest.approx(D35)
    assert float(pd_heading(0.0, math.radians(-90.0), 0.0, 3.5, 4.0, D35)) == pytest.approx(-D35)
    assert float(pd_heading(0.0, 0.0, 1.0, 3.5, 4.0, D35)) == pytest.approx(-D35)


def test_pd_across_pi_gives_small_rudder():
    d = float(pd_heading(math.radians(-179.0), math.radians(179.0), 0.0, 3.5, 4.0, D35))
    assert d == pytest.approx(-3.5 * math.radians(2.0))  # port, the short way round
    d = float(pd_heading(math.radians(-179.5), math.radians(179.5), 0.0, 3.5, 4.0, D35))
    assert abs(d) < math.radians(4.0)


def test_pd_symbolic_gains_and_gradient():
    psi, psi_d, r = ca.SX.sym("psi"), ca.SX.sym("psi_d"), ca.SX.sym("r")
    kp, kd, dmax = ca.SX.sym("kp"), ca.SX.sym("kd"), ca.SX.sym("dmax")
    dc = pd_heading(psi, psi_d, r, kp, kd, dmax)
    f = ca.Function("pd", [psi, psi_d, r, kp, kd, dmax], [dc, ca.gradient(dc, ca.vertcat(kp, kd))])
    val, grad = f(0.1, 0.0, 0.01, 2.0, 3.0, D35)
    assert float(val) == pytest.approx(-0.2 - 0.03)
    assert [float(g) for g in ca.vertsplit(grad)] == pytest.approx([-0.1, -0.01])
    mx = pd_heading(ca.MX.sym("psi"), 0.0, 0.0, 3.5, 4.0, D35)
    assert isinstance(mx, ca.MX)
