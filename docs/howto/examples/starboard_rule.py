"""starboard-rule: a rule-based collision-avoidance method written as a plugin (docs/howto/own_method.md).

While a neighbour within R_safe is on a collision course (its closest point of approach at the present velocities
comes within ``starboard_rule_d_cpa`` and lies ahead in time), the ship steers ``starboard_rule_turn_deg`` to
starboard of the bearing to her waypoint; otherwise she heads for the waypoint. Load it with
``mmg-casadi simulate head_on --plugin starboard_rule.py --method starboard-rule --out out/sr``.
"""

import casadi as ca

from mmg_casadi import Command, GuidanceInputs, Method, Param, register


def starboard_rule(g: GuidanceInputs) -> Command:
    """The method's guidance: CasADi expressions of one ship, built once into the compiled closed-loop step."""
    to_goal = g.goal - g.pos
    bearing = ca.atan2(to_goal[1], to_goal[0])           # x north, y east: headings turn to starboard as they grow
    risk = 0
    for j in range(g.nb_pos.size2()):                     # other ships, then static obstacles
        d = g.nb_pos[:, j] - g.pos                        # relative position (L)
        w = g.nb_vel[:, j] - g.vel                        # relative velocity (U)
        tcpa = -ca.dot(d, w) / (ca.dot(w, w) + 1e-9)      # time to the closest point of approach (L/U)
        dcpa = ca.norm_2(d + tcpa * w)                    # distance at it (L)
        collision_course = ca.logic_and(tcpa > 0, dcpa < g.P["starboard_rule_d_cpa"])
        risk = ca.fmax(risk, g.active[j] * collision_course)  # active: within R_safe
    heading = bearing + risk * g.P["starboard_rule_turn"]  # a *_deg parameter arrives in rad, without _deg
    return Command(ca.vertcat(ca.cos(heading), ca.sin(heading)))


register(Method(
    "starboard-rule", starboard_rule, groups=(), source="docs/howto/own_method.md (an example, not a published "
    "method)",
    params=(
        Param("starboard_rule_turn_deg", 40.0, 0.0, 90.0, "deg", "alteration to starboard of the bearing to the "
              "waypoint while a neighbour is on a collision course", "our choice: a large alteration, readily "
              "apparent (COLREG Rule 8(b))", low_open=True),
        Param("starboard_rule_d_cpa", 4.0, 0.0, None, "L", "a neighbour within R_safe whose passing distance at "
              "the present velocities is below this is on a collision course", "our choice: twice the 2 L "
              "collision distance", low_open=True),
    )))
