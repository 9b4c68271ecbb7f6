"""One decision of ``sb-mpc`` as numbers: every behaviour's predicted track and hazard, and the one chosen.

:func:`decide` evaluates the method's hazard Function (:func:`~mmg_casadi.guidance.sb_mpc_cost.hazard_function`)
for one ship's situation, given in numbers as the closed loop gives it to the method in calm water;
:func:`decision_at` reads that situation from a simulated scenario (:func:`~mmg_casadi.scenarios.run.run_scenario`)
at a time. The result, :class:`Decision`, has ``.plot(ax)`` (the behaviours' tracks coloured by hazard, the chosen
one bold, the neighbours' constant-velocity predictions) and ``.to_pandas()`` (one row per behaviour).

Examples
--------
A head-on meeting 20 L ahead: the behaviour of least hazard is an alteration to starboard at full speed.

>>> d = decide([0.0, 0.0], [1.0, 0.0], 0.0, [60.0, 0.0], [[20.0], [0.0]], [[-1.0], [0.0]])
>>> row = d.to_pandas().iloc[d.chosen]
>>> bool(row["turn_deg"] > 0), float(row["level"])
(True, 1.0)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from mmg_casadi.closed_loop.layout import Layout, step_values
from mmg_casadi.guidance.contract import GuidanceInputs
from mmg_casadi.guidance.sb_mpc import CODE, MEMORY, NAME, decision_inputs
from mmg_casadi.guidance.sb_mpc_cost import LEVELS, behaviours, hazard_function
from mmg_casadi.params import resolve
from mmg_casadi.vessel.mmg import propeller_rpm_for_speed
from mmg_casadi.vessel.library import load_vessel


@dataclass(frozen=True)
class Decision:
    """The behaviours of one decision of ``sb-mpc`` (:func:`decide`).

    Parameters
    ----------
    pos : numpy.ndarray (2,)
        Own position (L).
    psi : float
        Own heading (rad).
    course_wp : float
        The course to the waypoint (rad), from which the offsets are measured.
    turn_deg, offset_deg, level, hazard, collision : numpy.ndarray (B,)
        Per behaviour: alteration from the present heading and course offset from the course to the waypoint
        (degrees), propulsion level (fraction of the service rpm), total hazard and its neighbours' part (the sum
        over the neighbours).
    waypoint, held : numpy.ndarray of bool (B,)
        The behaviours "the course to the waypoint at full propulsion" and "the course and level held".
    x, y : numpy.ndarray (S, B)
        Predicted own positions at the samples (L).
    times : numpy.ndarray (S,)
        Sample times after the decision (L/U).
    chosen : int
        The behaviour of least hazard.
    nb_pos, nb_vel : numpy.ndarray (2, M)
        Neighbours' positions (L) and velocities (U) at the decision.
    active : numpy.ndarray (M,)
        Neighbours within the sensing range (1/0).
    d_safe : float
        The safety distance of the collision risk (L).
    inputs : tuple of casadi.DM
        The numeric arguments of the decision's Functions
        (:func:`~mmg_casadi.guidance.sb_mpc_cost.hazard_function`, and
        :func:`~mmg_casadi.guidance.sb_mpc_cost.plan_function` after ``due`` and ``held``).
    """

    pos: np.ndarray
    psi: float
    course_wp: float
    turn_deg: np.ndarray
    offset_deg: np.ndarray
    level: np.ndarray
    hazard: np.ndarray
    collision: np.ndarray
    waypoint: np.ndarray
    held: np.ndarray
    x: np.ndarray
    y: np.ndarray
    times: np.ndarray
    chosen: int
    nb_pos: np.ndarray
    nb_vel: np.ndarray
    active: np.ndarray
    d_safe: float
    inputs: tuple = ()

    def to_pandas(self):
        """One row per behaviour: ``turn_deg``, ``offset_deg``, ``level``, ``waypoint``, ``held``, ``hazard``,
        ``collision``, ``chosen``.

        Returns
        -------
        pandas.DataFrame
            The behaviours in the method's order.
        """
        import pandas as pd

        return pd.DataFrame({"turn_deg": self.turn_deg, "offset_deg": self.offset_deg, "level": self.level,
                             "waypoint": self.waypoint, "held": self.held,
                             "hazard": self.hazard, "collision": self.collision,
                             "chosen": np.arange(self.hazard.size) == self.chosen})

    def plot(self, ax=None, *, levels=(1.0,)):
        """Draw the predicted tracks of the behaviours at the propulsion ``levels`` (coloured by hazard on a log
        scale, the chosen one bold and black), the neighbours' constant-velocity predictions over the horizon and the
        own ship's safety distance at the decision.

        Parameters
        ----------
        ax : matplotlib Axes, optional
            Axes to draw in (a new figure if omitted).
        levels : sequence of float, default (1.0,)
            Propulsion levels whose behaviours are drawn (the chosen one always is).

        Returns
        -------
        matplotlib.figure.Figure
            The figure.
        """
        import matplotlib.pyplot as plt
        from matplotlib import cm, colors

        from mmg_casadi.plotting import marine_axes

        if ax is None:
            _, ax = plt.subplots(figsize=(7, 7))
        marine_axes(ax)
        finite = np.clip(self.hazard, 1e-3, 1e6)
        norm = colors.LogNorm(vmin=max(finite.min(), 1e-3), vmax=max(finite.max(), 10 * finite.min()))
        cmap = plt.get_cmap("viridis")
        for b in range(self.hazard.size):
            if b == self.chosen or self.held[b] or not any(abs(self.level[b] - lv) < 1e-9 for lv in levels):
                continue
            ax.plot(np.r_[self.pos[1], self.y[:, b]], np.r_[self.pos[0], self.x[:, b]], color=cmap(norm(finite[b])),
                    lw=1.0, alpha=0.9, ls="-." if self.waypoint[b] else "-")
            ax.annotate(f"{self.turn_deg[b]:+.0f}°", (self.y[-1, b], self.x[-1, b]), fontsize=7,
                        color=cmap(norm(finite[b])))
        c = self.chosen
        ax.plot(np.r_[self.pos[1], self.y[:, c]], np.r_[self.pos[0], self.x[:, c]], color="k", lw=2.5,
                label=f"chosen: {self.turn_deg[c]:+.0f}° from the heading, level {self.level[c]:g}")
        ax.plot(self.pos[1], self.pos[0], "ko", ms=5)
        ax.annotate("", xy=(self.pos[1] + 2.5 * math.sin(self.psi), self.pos[0] + 2.5 * math.cos(self.psi)),
                    xytext=(self.pos[1], self.pos[0]), arrowprops={"arrowstyle": "->", "color": "k", "lw": 1.5})
        theta = np.linspace(0.0, 2 * math.pi, 90)
        ax.plot(self.pos[1] + self.d_safe * np.sin(theta), self.pos[0] + self.d_safe * np.cos(theta), "k:", lw=0.8,
                label=f"d_safe = {self.d_safe:g} L")
        for j in range(self.nb_pos.shape[1]):
            if not self.active[j]:
                continue
            px = self.nb_pos[0, j] + self.nb_vel[0, j] * np.concatenate([[0.0], self.times])
            py = self.nb_pos[1, j] + self.nb_vel[1, j] * np.concatenate([[0.0], self.times])
            ax.plot(py, px, color="tab:red", lw=1.2, ls="--")
            ax.plot(py[1:], px[1:], ".", color="tab:red", ms=3)
            ax.plot(py[0], px[0], "o", color="tab:red", ms=6)
        sm = cm.ScalarMappable(norm=norm, cmap=cmap)
        ax.figure.colorbar(sm, ax=ax, shrink=0.7, label="hazard of the behaviour")
        ax.legend(loc="best", fontsize=8)
        ax.set_title(f"sb-mpc decision: {self.hazard.size} behaviours over {self.times[-1]:g} L/U")
        return ax.figure


def decide(pos, vel, psi, goal, nb_pos, nb_vel, *, active=None, params: dict | None = None, memory: dict | None = None,
           service_rpm: float | None = None, vessel: str = "kcs", walls=None, half_beam: float = 0.0) -> Decision:
    """Evaluate one decision of ``sb-mpc`` for a situation given in numbers (calm water, scene units of ``vessel``).

    Parameters
    ----------
    pos, vel : sequence of float (2,)
        Own position (L) and velocity over the ground (U).
    psi : float
        Own heading (rad).
    goal : sequence of float (2,)
        The waypoint being tracked (L).
    nb_pos, nb_vel : array_like (2, M)
        Neighbours' positions (L) and velocities (U); a static obstacle has zero velocity.
    active : array_like (M,), optional
        Neighbours the method sees (default: those within ``sb_mpc_range``).
    params : dict, optional
        Parameter overrides (:data:`mmg_casadi.params.PARAMETERS`).
    memory : dict, optional
        The method's memory rows (default: none held, a fresh decision).
    service_rpm : float, optional
        The ship's service propeller speed (default: that of her design speed).
    vessel : str, default "kcs"
        The own hull.
    walls : array_like (4, W), optional
        Wall and land segments (L).
    half_beam : float, default 0
        Half the own beam (L), with ``walls``.

    Returns
    -------
    Decision
        Every behaviour's predicted track and hazard.
    """
    resolved = resolve(params or {})
    values = step_values(resolved)
    pos, vel = ca.DM(np.asarray(pos, float)), ca.DM(np.asarray(vel, float))
    nb_pos, nb_vel = np.asarray(nb_pos, float).reshape(2, -1), np.asarray(nb_vel, float).reshape(2, -1)
    m = nb_pos.shape[1]
    if active is None:
        dist = np.hypot(nb_pos[0] - float(pos[0]), nb_pos[1] - float(pos[1]))
        active = (dist < values["sb_mpc_range"]).astype(float)
    active = np.asarray(active, float).reshape(1, m)
    if service_rpm is None:
        service_rpm = propeller_rpm_for_speed(1.0, load_vessel(vessel).ship)
    options = tuple((k, resolved[k]) for k in ("sb_mpc_samples", "sb_mpc_substeps"))
    walls_dm = None if walls is None else ca.DM(np.asarray(walls, float).reshape(4, -1))
    layout = Layout((NAME,), vessels=(vessel,), options=options,
                    n_walls=0 if walls_dm is None else walls_dm.size2())
    mem = {"sb_course": float(psi), "sb_state": 0.0, "sb_clock": 0.0} if memory is None else dict(memory)
    g = GuidanceInputs(pos=pos, vel=vel, psi=float(psi), speed=float(ca.norm_2(vel)), goal=ca.DM(np.asarray(goal, float)),
                       nb_pos=ca.DM(nb_pos), nb_vel=ca.DM(nb_vel), nb_radius=ca.DM.zeros(1, m), active=ca.DM(active),
                       P=values, layout=layout, memory=mem, service_rpm=float(service_rpm), walls=walls_dm,
                       half_beam=half_beam)
    d = decision_inputs(g, vessel)
    haz = hazard_function(m, resolved["sb_mpc_samples"], resolved["sb_mpc_substeps"],
                          0 if walls_dm is None else walls_dm.size2())
    args = [ca.evalf(a) if isinstance(a, ca.SX) else a for a in d["args"]]  # numbers built with SX operations
    hazard, x, y, collision, course, level, offset = (np.array(v) for v in haz(*args))
    hazard = hazard.ravel()
    chosen = int(np.argmin(hazard))  # the first of the least, as the fold in the step
    level_idx = np.round(level.ravel()).astype(int)
    b = behaviours()
    samples = resolved["sb_mpc_samples"]
    turn = np.degrees(np.angle(np.exp(1j * (course.ravel() - float(psi)))))
    return Decision(pos=np.array(pos).ravel(), psi=float(psi), course_wp=float(ca.evalf(d["chi_wp"])), turn_deg=turn,
                    offset_deg=np.degrees(offset.ravel()), level=np.array([LEVELS[k] for k in level_idx]),
                    hazard=hazard, collision=collision.ravel(), waypoint=b["waypoint"] > 0.5,
                    held=b["held"] > 0.5, x=x, y=y,
                    times=resolved["sb_mpc_horizon"] / samples * np.arange(1, samples + 1), chosen=chosen,
                    nb_pos=nb_pos, nb_vel=nb_vel, active=active.ravel(), d_safe=float(values["sb_mpc_d_safe"]),
                    inputs=tuple(args))


def decision_at(result, t: float, *, ship: int = 0) -> Decision:
    """The decision ``ship`` would make at time ``t`` of a simulated scenario (calm water): its state, waypoint,
    memory and neighbours (other ships present, then obstacles) read from the result.

    Parameters
    ----------
    result : ScenarioResult
        A result of :func:`~mmg_casadi.scenarios.run.run_scenario` in which ``ship`` uses ``sb-mpc``.
    t : float
        Time (L/U); the stored state nearest to it is used.
    ship : int, default 0
        The deciding ship.

    Returns
    -------
    Decision
        The behaviours at that state.
    """
    traj, sc = result.trajectory, result.scenario
    k = int(np.argmin(np.abs(traj.t - t)))
    lay = traj.layout
    S = traj.states[k]
    col = lay.column

    def velocity(i):
        u, v, p = S[i, col("u")], S[i, col("v")], S[i, col("psi")]
        return [u * math.cos(p) - v * math.sin(p), u * math.sin(p) + v * math.cos(p)]

    others = [j for j in range(lay.n_ships) if j != ship and S[j, col("status")] == 0]
    nb_pos = [[S[j, col("x")] for j in others] + [o.position[0] for o in sc.obstacles],
              [S[j, col("y")] for j in others] + [o.position[1] for o in sc.obstacles]]
    vels = [velocity(j) for j in others] + [[0.0, 0.0] for _ in sc.obstacles]
    nb_vel = np.array(vels, float).T.reshape(2, -1)
    spec = sc.ships[ship]
    idx = int(round(S[ship, col("idx")]))
    goal = spec.waypoints[min(idx, len(spec.waypoints) - 1)]
    memory = {name: float(S[ship, col(name)]) for name in MEMORY}
    memory["sb_state"] = memory["sb_state"] if memory["sb_state"] > CODE / 2 else 0.0
    params = {k_: v for k_, v in result.params.items() if k_.startswith("sb_mpc_")}
    return decide([S[ship, col("x")], S[ship, col("y")]], velocity(ship), S[ship, col("psi")], goal, nb_pos, nb_vel,
                  params=params, memory=memory,
                  service_rpm=propeller_rpm_for_speed(spec.speed, load_vessel(lay.vessel(ship)).ship),
                  vessel=lay.vessel(ship))
