"""colregs-vortex close-quarters filter (Rule 17(b)): a heading that turns the ship into the collision cone of
whatever is within ``r_cq`` is replaced by the admissible one closest to a readily apparent starboard alteration
of the present heading; others are left alone."""

import math

import casadi as ca
import numpy as np
import pytest

from mmg_casadi.guidance.colregs_vortex import ColregsVortexParams, colregs_vortex
from mmg_casadi.guidance.fields import heading_of
from mmg_casadi.guidance.velocity_obstacle import heading_feasible

CV = ColregsVortexParams()
KW = dict(lam_sink=-100.0, k_vor0=-10.0, r_safe=15.0, r_tol=2.0, gamma_max=5 * math.pi / 8) | CV.as_dict()
OWN = dict(own_pos=[0.0, 0.0], own_psi=0.0, own_vel=[1.0, 0.0])
# a ship meeting the own ship head-on 10 L ahead, beyond r_cq, at 1.6 U (TCPA 3.8 < t_act: the give-way ship
# escalates) and a buoy (static) on the own starboard bow
HEAD_ON = ([10.0, 0.0], [-1.6, 0.0])


def heading(nb_pos, nb_vel, **override):
    nb_pos, nb_vel = ca.DM(nb_pos).T, ca.DM(nb_vel).T
    v = colregs_vortex(goal=[50.0, 0.0], nb_pos=nb_pos, nb_vel=nb_vel, active=[1.0] * nb_pos.size2(), **OWN,
                       **(KW | override))
    return float(heading_of(v))


def feasible(h, nb_pos, nb_vel, active):
    return int(heading_feasible([0.0, 0.0], 1.0, h, ca.DM(nb_pos).T, ca.DM(nb_vel).T, active,
                                collision_distance=CV.d_cq))


def next_heading(h):
    """The heading the own ship (heading 0) turns through next on its way to ``h``."""
    return max(-CV.dpsi_cq, min(CV.dpsi_cq, h))


@pytest.mark.parametrize("buoy", [[2.0, 3.0], [1.5, 3.5], [2.5, 4.0]])
def test_turn_through_a_close_buoy_is_refused(buoy):
    pos, vel = [HEAD_ON[0], buoy], [HEAD_ON[1], [0.0, 0.0]]
    assert math.hypot(*buoy) < CV.r_cq
    free = heading(pos, vel, r_cq=0.0)  # the field alone: a starboard turn (Rule 8) into the buoy's cone
    h = heading(pos, vel)
    assert free > 0 and not feasible(next_heading(free), pos, vel, [0, 1])
    assert feasible(h, pos, vel, [0, 1])
    # the admissible candidate closest to a readily apparent starboard alteration of the present heading (0)
    n = 80
    cands = [-math.pi + 2 * math.pi * j / n for j in range(n)]
    best = min(abs(c - CV.dpsi_min) for c in cands if feasible(c, pos, vel, [0, 1]))
    assert abs(h - CV.dpsi_min) == pytest.approx(best, abs=1e-9)


def test_admissible_field_heading_is_left_alone():
    pos, vel = [HEAD_ON[0], [3.0, -3.5]], [HEAD_ON[1], [0.0, 0.0]]  # buoy inside r_cq on the port bow
    assert math.hypot(3.0, -3.5) < CV.r_cq
    assert heading(pos, vel) == pytest.approx(heading(pos, vel, r_cq=0.0), abs=1e-12)


def test_nothing_beyond_r_cq_is_filtered():
    pos, vel = [HEAD_ON[0], [2.0, 3.0]], [HEAD_ON[1], [0.0, 0.0]]
    r = math.hypot(2.0, 3.0)
    assert heading(pos, vel, r_cq=r - 0.01) == pytest.approx(heading(pos, vel, r_cq=0.0), abs=1e-12)
    assert heading(pos, vel, r_cq=r + 0.01) != pytest.approx(heading(pos, vel, r_cq=0.0), abs=1e-3)


@pytest.mark.parametrize("nb, nb_vel", [([3.0, -2.6], [0.0, 1.0]), ([4.0, 1.0], [-0.6, -0.3]),
                                        ([2.0, 3.5], [0.3, -0.9])])
def test_the_ship_never_turns_towards_a_close_ship(nb, nb_vel):
    # whatever the rules want: either the heading the own ship turns through next keeps the straight-line
    # passing distance from a ship within r_cq at least d_cq, or the heading it is given does
    assert math.hypot(*nb) < CV.r_cq

    def passing_distance(h):
        rel_p, rel_v = np.array(nb), np.array(nb_vel) - [math.cos(h), math.sin(h)]
        if rel_v @ rel_v < 1e-12:  # the neighbour's own velocity: the range stays
            return np.linalg.norm(rel_p)
        return np.linalg.norm(rel_p + rel_v * max(0.0, -rel_p @ rel_v / (rel_v @ rel_v)))

    free = heading([nb], [nb_vel], r_cq=0.0)
    h = heading([nb], [nb_vel])
    assert passing_distance(next_heading(free)) < CV.d_cq  # the situation needs the filter
    assert max(passing_distance(next_heading(h)), passing_distance(h)) >= CV.d_cq - 1e-6



def crossing_from_port(tcpa, passing):
    """A design-speed ship crossing from port at 90° (the own ship stands on), CPA ``passing`` after ``tcpa``,
    passing ahead of the own ship."""
    v = np.array([0.0, 1.0])
    rel = v - [1.0, 0.0]
    return list(-rel * tcpa + passing * np.array([rel[1], -rel[0]]) / np.linalg.norm(rel)), list(v)


@pytest.mark.parametrize("passing, filtered", [(2.5, False), (1.5, True)])
def test_a_held_ship_is_filtered_only_on_a_collision_course_while_the_give_way_ship_can_act(passing, filtered):
    # within r_cq, TCPA 5 above t_act: the give-way ship can still act, the own ship keeps her course (17(a)(i));
    # a passing distance inside d_cq but outside the collision distance r_tol is left to the give-way ship
    pos, vel = crossing_from_port(5.0, passing)
    assert math.hypot(*pos) < CV.r_cq and 5.0 > CV.t_act and passing < CV.d_cq
    assert (passing < KW["r_tol"]) == filtered
    assert not feasible(0.0, [pos], [vel], [1])  # inside the d_cq cone: the filter would have turned her
    h = heading([pos], [vel])
    assert heading([pos], [vel], r_cq=0.0) == pytest.approx(0.0, abs=1e-9)  # the rules alone: hold
    if filtered:  # on a collision course the last resort acts, to starboard
        assert h > math.radians(10.0)
    else:
        assert h == pytest.approx(0.0, abs=1e-9)
    # once the TCPA is below t_act the stand-on ship acts alone (17(a)(ii)), whatever the passing distance
    pos, vel = crossing_from_port(3.5, passing)
    assert abs(heading([pos], [vel])) > math.radians(10.0)


def test_symbolic_function_matches_numeric_call_with_the_filter_acting():
    x = ca.SX.sym("x", 2)
    nb = ca.SX.sym("nb", 2, 2)
    nb_vel = ca.DM([[-1.6, 0.0], [0.0, 0.0]])
    f = ca.Function("cv", [x, nb], [colregs_vortex(x, 0.0, [1.0, 0.0], [50.0, 0.0], nb, nb_vel, [1, 1], **KW)])
    args = (ca.DM([0.0, 0.0]), ca.DM([[10.0, 2.0], [0.0, 3.0]]))  # the first buoy case above
    h_sym = float(heading_of(f(*args)))
    assert h_sym == pytest.approx(heading([HEAD_ON[0], [2.0, 3.0]], [HEAD_ON[1], [0.0, 0.0]]), abs=1e-12)
    assert h_sym != pytest.approx(heading([HEAD_ON[0], [2.0, 3.0]], [HEAD_ON[1], [0.0, 0.0]], r_cq=0.0), abs=1e-3)


@pytest.mark.parametrize("field, name, value, table_value", [
    ("r_cq", "cv_r_cq", -1.0, -1.0), ("d_cq", "cv_d_cq", 0.0, 0.0), ("dpsi_cq", "cv_dpsi_cq_deg", 0.0, 0.0),
    ("dpsi_cq", "cv_dpsi_cq_deg", 4.0, math.degrees(4.0))])
def test_filter_parameters_are_range_checked(field, name, value, table_value):
    from mmg_casadi.closed_loop.layout import default_globals
    from mmg_casadi.errors import ParameterError
    with pytest.raises(ParameterError, match=name):
        ColregsVortexParams(**{field: value})
    with pytest.raises(ParameterError, match=name):
        default_globals(**{name: table_value})
