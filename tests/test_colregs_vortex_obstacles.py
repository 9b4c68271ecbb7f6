"""colregs-vortex and static obstacles: circled only while the range closes (the rules' layer: the close-quarters
filter is switched off with r_cq = 0)."""

import math

import casadi as ca
import pytest

from mmg_casadi.guidance.colregs_vortex import ColregsVortexParams, colregs_vortex
from mmg_casadi.guidance.fields import heading_of, modified_vortex

MV_KW = dict(lam_sink=-100.0, k_vor0=-10.0, r_safe=15.0, r_tol=2.0, gamma_max=5 * math.pi / 8)
KW = MV_KW | ColregsVortexParams().as_dict() | {"r_cq": 0.0}
OWN = dict(own_pos=[0.0, 0.0], own_psi=0.0, own_vel=[1.0, 0.0])
GOAL = [50.0, 0.0]


def heading(obstacle, method="colregs"):
    """Desired heading (deg) of the own ship at the origin heading north at the goal, one buoy."""
    args = dict(goal=GOAL, nb_pos=ca.DM(obstacle), nb_vel=ca.DM([0.0, 0.0]), active=[1.0], **OWN)
    v = colregs_vortex(**args, **KW) if method == "colregs" else modified_vortex(**args, **MV_KW)
    return math.degrees(float(heading_of(v)))


def test_buoy_being_left_behind_is_not_circled():
    # abeam to port and the range opening: no vortex (the paper's still turns the ship about it)
    assert heading([-1.0, -6.0]) == pytest.approx(0.0, abs=1e-12)
    assert heading([-1.0, -6.0], method="modified") < -1.0
