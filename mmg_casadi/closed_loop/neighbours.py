"""The neighbours a method sees in the sparse step: the active ones gathered into a few slots.

A method sees its neighbours within R_safe; in the sparse step (:func:`~mmg_casadi.closed_loop.step.build_closed_loop_step`
with ``sparse=True``) a never-inlined Function gathers the active ones, in order, into 1, 2 or 4 slots (all M when
more are active) and evaluates the method on those only. Exact because every method ignores an inactive neighbour
(a masked term adds an exact zero; ``tests/test_sparse_step.py`` checks every registered method).
"""

from __future__ import annotations

import functools

import casadi as ca

from mmg_casadi.closed_loop.layout import GLOBAL_PARAMS, Layout
from mmg_casadi.guidance import methods
from mmg_casadi.guidance.contract import OWN_STATE
from mmg_casadi.guidance.methods import GuidanceInputs, command_vector, forget_on_unregister

SLOTS = (1, 2, 4)
"""Neighbour counts for which :func:`within_range` has a gathered branch (more active ones: all M)."""


def _method_scalars(layout: Layout) -> tuple[str, ...]:
    return GLOBAL_PARAMS + layout.method_inputs


def _memory_vector(names, memory: dict):
    return ca.vertcat(*[memory[k] for k in names]) if names else ca.SX(0, 1)


def dispatch_args(layout: Layout, g: GuidanceInputs) -> list:
    """The arguments after the active count of :func:`within_range`'s Function, from a ship's guidance inputs.

    Parameters
    ----------
    layout : Layout
        Closed-loop layout of the step.
    g : GuidanceInputs
        The ship's guidance inputs (all its neighbours, masked by ``active``).

    Returns
    -------
    list
        ``[pos, vel, psi, speed, goal, nb_pos, nb_vel, nb_radius, active, memory, service_rpm, scalars]``: CasADi
        expressions, ``scalars`` the method's named parameters stacked; in a layout with walls, then ``walls``
        and ``half_beam`` (the land test's).
    """
    spec_memory = tuple(g.memory)
    args = [g.pos, g.vel, g.psi, g.speed, g.goal, g.nb_pos, g.nb_vel, g.nb_radius, g.active,
            _memory_vector(spec_memory, g.memory), g.service_rpm,
            ca.vertcat(*[g.P[k] for k in _method_scalars(layout)])]
    if layout.n_walls:  # the walls and the half beam of the methods' land test
        args += [g.walls, g.half_beam]
    if g.own:  # the ship's own state, for a method with own_state
        args.append(ca.vertcat(*[g.own[k] for k in OWN_STATE]))
    return args


@functools.lru_cache(maxsize=None)
def within_range(layout: Layout, method: str, m: int) -> ca.Function:
    """Never-inlined Function ``(k, pos, vel, psi, speed, goal, nb_pos, nb_vel, nb_radius, active, memory, service_rpm, P)``
    → the method's command as one column (:func:`~mmg_casadi.guidance.methods.command_vector`), evaluating the method on the ``k`` active neighbours only (gathered in their
    order into 1, 2 or 4 slots, the unused slots inactive) or on all ``m`` when more are active; with none
    active and no walls it returns (1, 0) without evaluating the method (the step does not read it). Exact only
    because every method ignores an inactive neighbour (a masked term adds an exact zero; a test checks each
    registered method).

    Parameters
    ----------
    layout : Layout
        Closed-loop layout of the step.
    method : str
        A registered method with a builder.
    m : int
        Number of neighbours (other ships and obstacles) of the ship.
    """
    spec = methods.get(method)
    names = _method_scalars(layout)
    sym = [ca.SX.sym("pos", 2), ca.SX.sym("vel", 2), ca.SX.sym("psi"), ca.SX.sym("speed"), ca.SX.sym("goal", 2),
           ca.SX.sym("nb_pos", 2, m), ca.SX.sym("nb_vel", 2, m), ca.SX.sym("nb_radius", 1, m),
           ca.SX.sym("active", 1, m), ca.SX.sym("memory", len(spec.memory)), ca.SX.sym("service_rpm"),
           ca.SX.sym("P", len(names))]
    pos, vel, psi, speed, goal, nb_pos, nb_vel, nb_rad, active, mem, rpm, pv = sym
    P = {k: pv[n] for n, k in enumerate(names)}
    walls = half_beam = None
    if layout.n_walls:
        walls, half_beam = ca.SX.sym("walls", 4, layout.n_walls), ca.SX.sym("half_beam")
        sym += [walls, half_beam]
    own = {}
    if spec.own_state:
        own_v = ca.SX.sym("own", len(OWN_STATE))
        sym.append(own_v)
        own = {k: own_v[n] for n, k in enumerate(OWN_STATE)}

    def branch(slots):
        if slots >= m:
            g_pos, g_vel, g_rad, g_act = nb_pos, nb_vel, nb_rad, active
        else:
            cols = [[ca.SX.zeros(2, 1), ca.SX.zeros(2, 1), ca.SX(0), ca.SX(0)] for _ in range(slots)]
            before = ca.SX(0)  # active neighbours before column j
            for j in range(m):
                for q in range(slots):
                    take = ca.logic_and(active[j] == 1, before == q)
                    src = (nb_pos[:, j], nb_vel[:, j], nb_rad[j], active[j])
                    cols[q] = [ca.if_else(take, s_, d_) for s_, d_ in zip(src, cols[q])]
                before = before + active[j]
            g_pos = ca.horzcat(*[cq[0] for cq in cols])
            g_vel = ca.horzcat(*[cq[1] for cq in cols])
            g_rad = ca.horzcat(*[cq[2] for cq in cols])
            g_act = ca.horzcat(*[cq[3] for cq in cols])
        g = GuidanceInputs(pos=pos, vel=vel, psi=psi, speed=speed, goal=goal, nb_pos=g_pos, nb_vel=g_vel,
                           nb_radius=g_rad, active=g_act, P=P, layout=layout,
                           memory={k: mem[j] for j, k in enumerate(spec.memory)}, service_rpm=rpm, walls=walls,
                           half_beam=half_beam, own=own)
        return ca.Function(f"{method.replace('-', '')}_{layout.key()}_m{m}_s{min(slots, m)}", sym,
                           [command_vector(spec, spec.builder(g))], {"cse": True})

    sizes = [s for s in SLOTS if s < m]
    by_size = {s: branch(s) for s in sizes}
    cases = [by_size[min(s for s in sizes if s >= max(k, 1))] for k in range(max(sizes) + 1)]
    if layout.n_walls == 0:
        # nothing within R_safe and no walls: the step follows ILOS and never reads the method's vector
        idle = ca.DM.zeros(spec.command_size(), 1)
        idle[0] = 1.0
        cases[0] = ca.Function(f"{method.replace('-', '')}_{layout.key()}_m{m}_idle", sym, [idle])
    cond = ca.Function.conditional(f"within_{method.replace('-', '')}_{layout.key()}_m{m}", cases, branch(m))
    xm = [ca.MX.sym(f"a{n}", *cond.size_in(n)) for n in range(cond.n_in())]
    return ca.Function(f"within_range_{method.replace('-', '')}_{layout.key()}_m{m}", xm, [cond(*xm)],
                       {"never_inline": True})


forget_on_unregister(within_range.cache_clear)
