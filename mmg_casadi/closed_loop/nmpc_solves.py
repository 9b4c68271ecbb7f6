"""What the ``nmpc`` planner's solves cost: every solve of a run, re-posed from its history, with the solver's own
statistics.

Inside the compiled closed loop the solve (:mod:`mmg_casadi.guidance.nmpc`) leaves only its plan and the tallies;
its time and iteration count are not observable there. :func:`solves_of_run` re-poses each solve of one run: it
simulates the run (:func:`~mmg_casadi.closed_loop.simulation.simulate`, the full history), rebuilds at every step
the planner's inputs from the state exactly as the closed-loop step does (neighbours, the planner's view with its
lookout, the waypoint, the memory rows), and solves the same problem twice: with the compiled solver (the C code the
closed loop runs; its wall time is the cost reported) and with CasADi's ``sqpmethod`` itself (iterations and return
status, :meth:`casadi.Function.stats`). The compiled solution is checked against the plan the closed loop stored
after that step (``max_plan_difference``): the two run the same generated code on the same inputs.

:func:`solve_statistics` sums up a list of solves: median and 99th percentile of the time, the iterations, the
return statuses and how often the planner's failure test fired (:mod:`mmg_casadi.guidance.nmpc`, Fallback).
"""

from __future__ import annotations

import time

import casadi as ca
import numpy as np

from mmg_casadi.closed_loop.problem import build_problem
from mmg_casadi.closed_loop.simulation import simulate
from mmg_casadi.closed_loop.step import ship_kinematics
from mmg_casadi.compiled import compile_function
from mmg_casadi.guidance import methods
from mmg_casadi.guidance.contract import OWN_STATE, GuidanceInputs
from mmg_casadi.guidance.ilos import ilos_step_terms
from mmg_casadi.guidance.nmpc import HORIZON, PLAN, plan_inputs, shape_of
from mmg_casadi.guidance.nmpc_ocp import nlp_solver, solver_function
from mmg_casadi.closed_loop.neighbours import _method_scalars


def _probe(layout):
    """SX Function of the planner's inputs (as the sparse step passes a method's inputs) -> its solve's inputs."""
    spec = methods.get("nmpc")
    names = _method_scalars(layout)
    M = layout.n_ships - 1 + layout.n_obstacles
    sym = {"pos": ca.SX.sym("pos", 2), "vel": ca.SX.sym("vel", 2), "psi": ca.SX.sym("psi"),
           "speed": ca.SX.sym("speed"), "goal": ca.SX.sym("goal", 2), "nb_pos": ca.SX.sym("nb_pos", 2, M),
           "nb_vel": ca.SX.sym("nb_vel", 2, M), "nb_radius": ca.SX.sym("nb_radius", 1, M),
           "active": ca.SX.sym("active", 1, M), "memory": ca.SX.sym("memory", len(spec.memory)),
           "service_rpm": ca.SX.sym("service_rpm"), "P": ca.SX.sym("P", len(names)),
           "walls": ca.SX.sym("walls", 4, layout.n_walls), "half_beam": ca.SX.sym("half_beam"),
           "own": ca.SX.sym("own", len(OWN_STATE))}
    g = GuidanceInputs(pos=sym["pos"], vel=sym["vel"], psi=sym["psi"], speed=sym["speed"], goal=sym["goal"],
                       nb_pos=sym["nb_pos"], nb_vel=sym["nb_vel"], nb_radius=sym["nb_radius"], active=sym["active"],
                       P={k: sym["P"][n] for n, k in enumerate(names)}, layout=layout,
                       memory={k: sym["memory"][j] for j, k in enumerate(spec.memory)},
                       service_rpm=sym["service_rpm"], walls=sym["walls"] if layout.n_walls else None,
                       half_beam=sym["half_beam"] if layout.n_walls else None,
                       own={k: sym["own"][n] for n, k in enumerate(OWN_STATE)})
    q = plan_inputs(g)
    return ca.Function("nmpc_probe", list(sym.values()), [q["need"], q["w0"], q["p"], q["lbw"], q["ubw"]],
                       list(sym), ["need", "w0", "p", "lbw", "ubw"]), names


def solves_of_run(scenario, params: dict | None = None, *, ships=(0,), keep_inputs: bool = False) -> list[dict]:
    """Every solve of the ``nmpc`` ships ``ships`` in one run of ``scenario``, re-posed and solved again.

    Parameters
    ----------
    scenario : Scenario
        The run (its ships in ``ships`` use ``nmpc``).
    params : dict, optional
        Parameter overrides.
    ships : tuple of int, default (0,)
        The ships whose solves are re-posed.
    keep_inputs : bool, default False
        Also return each solve's inputs ``(w0, p, lbw, ubw)`` (key ``inputs``), e.g. to try other solver options.

    Returns
    -------
    list of dict
        Per solve: ``ship``, ``t`` (L/U), ``time_us`` and ``cpu_us`` (the compiled solver's wall and CPU time:
        on a loaded machine the CPU time is the cost), ``iterations`` and
        ``status`` (``sqpmethod``'s), ``f0``, ``f``, ``kkt`` (:func:`~mmg_casadi.guidance.nmpc_ocp.solver_function`),
        ``failed`` (the planner's failure test), ``max_plan_difference`` (the compiled solution against the plan
        the closed loop stored; nan when the solve failed).
    """
    problem = build_problem(scenario, params)
    lay, P_num = problem.layout, problem.p
    traj = simulate(lay, problem.x0, P_num)
    probe, names = _probe(lay)
    Pd = lay.split_params(ca.DM(P_num))
    shape = shape_of(lay)
    max_iter = int(lay.option("nmpc_max_iter"))
    solver = nlp_solver(shape, max_iter)
    compiled = compile_function(solver_function(shape, max_iter))
    kkt_fail = float(Pd["nmpc_kkt_fail"])
    spec = methods.get("nmpc")
    N, S = lay.n_ships, lay.n_obstacles
    S_ = {k: lay.column(k) for k in lay.ship_state}
    E = Pd["env"] if lay.disturbed else None
    scal = ca.vertcat(*[Pd[k] for k in names])
    out = []
    for k in range(len(traj.t) - 1):
        X = traj.states[k]
        kin = [ship_kinematics(ca.DM(X[j]), S_, E, Pd["ships"][j]["stays"]) for j in range(N)]
        for i in ships:
            if lay.methods[i] != "nmpc" or X[i, S_["status"]] != 0:
                continue
            Pi = Pd["ships"][i]
            Xi = X[i]
            others = [j for j in range(N) if j != i]
            pos, vel = kin[i][0], kin[i][1]
            nb_pos = ca.horzcat(*[kin[j][0] for j in others], Pd["obstacles"][0:2, :])
            nb_vel = ca.horzcat(*[kin[j][1] for j in others], ca.DM.zeros(2, S))
            nb_rad = ca.horzcat(*[Pd["ship_radius"] for _ in others], Pd["obstacles"][2:3, :])
            present = ca.horzcat(*[kin[j][2] for j in others], ca.DM.ones(1, S))
            d = ca.sqrt(ca.sum1((nb_pos - ca.repmat(pos, 1, nb_pos.size2())) ** 2))
            active = present * (d < Pd["r_safe"] + Pd[spec.lookout])
            terms = ilos_step_terms(pos, Pi["path"], Xi[S_["idx"]], Xi[S_["y_int"]], Pd["ilos_delta"],
                                    Pd["ilos_k"])
            n_service = Pi["leg_rpm"][0]
            for c in range(1, lay.max_path):
                n_service = Pi["leg_rpm"][c] if Xi[S_["idx"]] > c - 0.5 else n_service
            speed = np.hypot(Xi[S_["u"]], Xi[S_["v"]]) if not lay.disturbed else float(ca.norm_2(vel))
            own = [Xi[S_[key]] for key in ("u", "v", "r", "delta", "n_prop")] + [
                Pi["rpm_min"], Pi["rpm_max"], Pi["engine_rate"], Pi["engine_lag"]]
            need, w0, p, lbw, ubw = probe(pos, vel, Xi[S_["psi"]], speed, terms["wp_next"], nb_pos, nb_vel, nb_rad,
                                          active, ca.vertcat(*[Xi[S_[m]] for m in spec.memory]), n_service, scal,
                                          Pd["walls"] if lay.n_walls else ca.DM(4, 0),
                                          Pi["half_beam"] if lay.n_walls else 0, ca.vertcat(*own))
            if float(need) < 0.5:
                continue
            t0, c0 = time.perf_counter(), time.thread_time()
            w, f0, f, kkt = compiled(w0, p, lbw, ubw)
            elapsed, cpu = time.perf_counter() - t0, time.thread_time() - c0
            solver(x0=w0, p=p, lbx=lbw, ubx=ubw)
            stats = solver.stats()
            w = np.array(w).ravel()
            f0, f, kkt = float(f0), float(f), float(kkt)
            failed = not np.all(np.isfinite(w)) or not np.isfinite(f) or (kkt > kkt_fail and f >= f0)
            stored = np.array([traj.states[k + 1][i, S_[name]] for name in PLAN])
            steered = traj.auxiliary("reactive", i)[k] > 0.5  # the plan is kept only while the planner steers
            out.append({"ship": i, "t": float(traj.t[k]), "time_us": 1e6 * elapsed, "cpu_us": 1e6 * cpu,
                        "iterations": int(stats["iter_count"]), "status": str(stats["return_status"]),
                        "f0": f0, "f": f, "kkt": kkt, "failed": bool(failed),
                        "max_plan_difference": float(np.max(np.abs(stored - w))) if steered and not failed
                        else float("nan"),
                        "rudder_deg": float(np.degrees(w[0])), "nu": float(w[HORIZON]),
                        **({"inputs": tuple(np.array(v).ravel() for v in (w0, p, lbw, ubw))} if keep_inputs else {})})
    return out


def solve_statistics(solves) -> dict:
    """Summary of solves (:func:`solves_of_run`): count, time quantiles, iterations, statuses, failures.

    Parameters
    ----------
    solves : list of dict
        Solves.

    Returns
    -------
    dict
        ``solves``, ``time_us`` and, when every solve has it, ``cpu_us`` (median, p90, p99, max, mean),
        ``iterations`` (median, p90, p99, max, mean),
        ``statuses`` (count per return status), ``failed`` and ``failure_rate``, ``max_iterations_reached``,
        ``max_plan_difference`` (the largest over solves that did not fail).

    Examples
    --------
    >>> s = solve_statistics([{"time_us": 100.0, "iterations": 2, "status": "Solve_Succeeded", "failed": False,
    ...                        "max_plan_difference": 0.0}])
    >>> s["solves"], s["time_us"]["median"], s["failure_rate"]
    (1, 100.0, 0.0)
    """
    solves = list(solves)
    if not solves:
        return {"solves": 0}
    t = np.array([s["time_us"] for s in solves])
    cpu = np.array([s.get("cpu_us", np.nan) for s in solves])
    it = np.array([s["iterations"] for s in solves])
    statuses: dict = {}
    for s in solves:
        statuses[s["status"]] = statuses.get(s["status"], 0) + 1
    q = lambda a: {"median": float(np.median(a)), "p90": float(np.percentile(a, 90)),  # noqa: E731
                   "p99": float(np.percentile(a, 99)), "max": float(np.max(a)), "mean": float(np.mean(a))}
    diffs = [s["max_plan_difference"] for s in solves if not s["failed"]]
    failed = sum(s["failed"] for s in solves)
    return {"solves": len(solves), "time_us": q(t), **({"cpu_us": q(cpu)} if np.all(np.isfinite(cpu)) else {}),
            "iterations": q(it), "statuses": statuses, "failed": failed,
            "failure_rate": failed / len(solves),
            "max_iterations_reached": statuses.get("Maximum_Iterations_Exceeded", 0),
            "max_plan_difference": float(np.nanmax(diffs)) if diffs else float("nan")}
