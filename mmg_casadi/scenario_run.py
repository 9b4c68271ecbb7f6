"""Run a :class:`~mmg_casadi.scenario.Scenario` through the compiled closed loop and assess the result.

``metrics.json`` schema (stable; distances in L, times non-dimensional L/U_des)::

    {"method": str, "collision": bool, "t_end": float,
     "ships": [{"name", "method", "status": "reached"|"diverged"|"stalled"|"timeout",
                "reached_goal": bool, "time_to_goal": float|null, "ce": float, "mcte": float,
                "collided": bool, "collision_time": float|null, "collision_with": str|null,
                "min_distance": float, "stalled_at": [x, y]|null, "reactive_time": float}],
     "pairs": [{"a", "b", "min_distance", "t_min", "encounter", "compliant",
                "encounter_b", "compliant_b", "t_enter"}]}

``encounter``/``compliant`` are from ship ``a``'s side (``encounter_b``/``compliant_b`` from ``b``'s);
static obstacles appear as ``b = "obstacle<k>"`` with encounter ``"static"``.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import colregs
from .closed_loop import METHODS, PARAM_SOURCES, S_, Layout, default_globals, initial_state, pack_params
from .errors import InputError, ScenarioError
from .metrics import tracking_metrics
from .model import propeller_rpm_for_speed
from .simulation import Trajectory, simulate

#: scenario ``[settings]`` / ``--params`` keys passed to :func:`~mmg_casadi.closed_loop.default_globals` as they are
PARAM_KEYS = tuple(k for k in PARAM_SOURCES if k not in ("goal_tolerance", "gamma_max", "r_safe")) + ("ship_radius",)
LAYOUT_KEYS = ("vo_candidates", "vo_cone")
STALL_WINDOW = 50.0  #: no progress towards the goal for this long at t_max → "stalled"


def load_params_file(path) -> dict:
    """Field / guidance parameters from a TOML file (top level or a ``[params]`` table), e.g. from ``tune apf``."""
    from .scenario import VO_CANDIDATES_MAX, VO_CONES, _is_number, toml_key
    path = Path(path)
    try:
        raw = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as e:
        raise InputError("--params", "an existing, readable TOML file", f"{path} ({e.strerror or e})") from None
    except UnicodeDecodeError:
        raise InputError("--params", "a UTF-8 text file", str(path)) from None
    except tomllib.TOMLDecodeError as e:
        raise InputError("--params", f"valid TOML ({e})", str(path)) from None
    raw = raw.get("params", raw)
    if not isinstance(raw, dict):
        raise InputError("params", "a table of field parameters", raw)
    allowed = set(PARAM_KEYS) | {"gamma_max_deg", "r_safe", "stall_window"} | set(LAYOUT_KEYS)
    out = {}
    for k, v in raw.items():
        field = f"params.{toml_key(k)}"
        if k not in allowed:
            raise InputError(field, f"one of: {', '.join(sorted(allowed))}", k)
        if k == "vo_cone":
            if v not in VO_CONES:
                raise InputError(field, f"one of: {', '.join(VO_CONES)}", v)
            out[k] = v
        elif k == "vo_candidates":
            if isinstance(v, bool) or not isinstance(v, int) or not 1 <= v <= VO_CANDIDATES_MAX:
                raise InputError(field, f"an integer in [1, {VO_CANDIDATES_MAX}]", v)
            out[k] = v
        elif not _is_number(v):
            raise InputError(field, "a finite number", v)
        else:
            out[k] = float(v)
    return out


@dataclass
class ScenarioResult:
    """A simulated scenario: the scenario, its trajectory and the assessed metrics (the JSON schema above)."""

    scenario: object
    trajectory: Trajectory
    metrics: dict
    encounter_labels: dict = field(default_factory=dict)

    def names(self) -> list[str]:
        return [s.name for s in self.scenario.ships]

    def pair_distances(self) -> dict:
        """Distance histories ``{(a, b): d(t)}`` for every ship pair and ship–obstacle pair (NaN while a ship is
        not sailing)."""
        tr = self.trajectory
        mask = tr.sailing_mask()
        names = self.names()
        N = len(names)
        out = {}
        for i in range(N):
            pi = np.column_stack([tr.state("x", i), tr.state("y", i)])
            for j in range(i + 1, N):
                pj = np.column_stack([tr.state("x", j), tr.state("y", j)])
                d = np.linalg.norm(pi - pj, axis=1)
                out[(names[i], names[j])] = np.where(mask[:, i] & mask[:, j], d, np.nan)
            for k, o in enumerate(self.scenario.obstacles):
                d = np.linalg.norm(pi - np.asarray(o.position), axis=1)
                out[(names[i], f"obstacle{k}")] = np.where(mask[:, i], d, np.nan)
        return out

    def own_distance(self) -> np.ndarray:
        """Distance from the own ship to its nearest other agent over time."""
        own = self.names()[0]
        ds = [d for (a, b), d in self.pair_distances().items() if a == own or b == own]
        if not ds:
            return np.full(len(self.trajectory.t), np.inf)
        d = np.vstack(ds)
        return np.min(np.where(np.isnan(d), np.inf, d), axis=0)


def build_problem(sc, params: dict | None = None):
    """Layout, initial state and parameter vector of a scenario (``params`` override ``settings.params``)."""
    st = sc.settings
    merged = dict(getattr(st, "params", {}) or {})
    merged.update(params or {})
    methods = tuple(s.method or st.method for s in sc.ships)
    for i, m in enumerate(methods):
        if m not in METHODS:
            raise ScenarioError(f"ships[{i}].method", f"one of: {', '.join(METHODS)}", m)
    layout_kw = {}
    if "vo_candidates" in merged:
        layout_kw["vo_candidates"] = int(merged["vo_candidates"])
    if "vo_cone" in merged:
        layout_kw["vo_cone"] = str(merged["vo_cone"])
    kmax = max(1 + len(s.waypoints) for s in sc.ships)
    walls = []
    for w in sc.walls:
        pts = np.asarray(w.points, float)
        walls += [(a[0], a[1], b[0], b[1]) for a, b in zip(pts[:-1], pts[1:])]
    layout = Layout(methods=methods, n_obstacles=len(sc.obstacles), n_walls=len(walls), max_path=kmax,
                    **layout_kw)
    overrides = {k: float(v) for k, v in merged.items() if k in PARAM_KEYS}
    if "gamma_max_deg" in merged:
        overrides["gamma_max"] = math.radians(float(merged["gamma_max_deg"]))
    # every override goes through default_globals, which range-checks it against its parameter dataclass
    g = default_globals(dt=st.dt, r_safe=float(merged.get("r_safe", st.r_safe)),
                        collision_distance=st.collision_distance,
                        goal_tolerance=getattr(st, "goal_tolerance", 3.0), t_max=st.t_max, **overrides)
    ships = []
    for s in sc.ships:
        ships.append({"n_rpm": propeller_rpm_for_speed(s.speed), "path": [s.start, *s.waypoints],
                      "stays": s.stays, "start": s.start, "heading": math.radians(s.heading_deg),
                      "speed": s.speed})
    obstacles = [(o.position[0], o.position[1], o.radius) for o in sc.obstacles]
    p = pack_params(layout, g, ships, obstacles, walls)
    x0 = initial_state(layout, ships)
    return layout, x0, p, g, merged


def run_scenario(sc, params: dict | None = None, *, profile=None) -> ScenarioResult:
    """Simulate ``sc`` and assess it (metrics.json schema in the module docstring)."""
    layout, x0, p, g, merged = build_problem(sc, params)
    traj = simulate(layout, x0, p)
    return assess(sc, traj, g, stall_window=float(merged.get("stall_window", STALL_WINDOW)), profile=profile)


def _ship_status(final, t_end, t_max, stall_window):
    st = final[S_["status"]]
    if st == 1:
        return "reached", None
    if st == 2:
        return "diverged", None
    if t_end - final[S_["t_best"]] >= stall_window:
        return "stalled", [float(final[S_["x_best"]]), float(final[S_["y_best"]])]
    return "timeout", None


def assess(sc, traj: Trajectory, g: dict, *, stall_window: float = STALL_WINDOW, profile=None) -> ScenarioResult:
    """Metrics of a trajectory: per-ship outcome, CE, MCTE, collisions; per-pair closest approach and COLREGs."""
    profile = profile or colregs.ColregProfile()
    names = [s.name for s in sc.ships]
    N = len(names)
    S = len(sc.obstacles)
    agent_names = names + [f"obstacle{k}" for k in range(S)]
    mask = traj.sailing_mask()
    t_end = float(traj.t[-1])
    ships = []
    for i, s in enumerate(sc.ships):
        fin = traj.final[i]
        status, where = _ship_status(fin, t_end, g["t_max"], stall_window)
        reached = traj.state("status", i)[1:] == 1
        m = tracking_metrics(traj.t[:-1], traj.state("delta", i)[:-1], traj.auxiliary("y_e", i), reached,
                             delta_max=g["delta_max"])
        t_col = fin[S_["t_collision"]]
        ships.append({
            "name": s.name,
            "method": traj.layout.methods[i],
            "status": status,
            "reached_goal": status == "reached",
            "time_to_goal": float(fin[S_["t_goal"]]) if status == "reached" else None,
            "ce": float(m.ce),
            "mcte": float(m.mcte),
            "collided": bool(t_col >= 0),
            "collision_time": float(t_col) if t_col >= 0 else None,
            "collision_with": agent_names[int(fin[S_["collision_with"]])] if t_col >= 0 else None,
            "min_distance": float(fin[S_["d_min"]]) if fin[S_["d_min"]] < 1e5 else None,
            "stalled_at": where,
            "reactive_time": float(fin[S_["reactive_time"]]),
        })
    pairs = []
    labels: dict = {}
    for i in range(N):
        pi = np.column_stack([traj.state("x", i), traj.state("y", i)])
        for j in range(i + 1, N):
            pj = np.column_stack([traj.state("x", j), traj.state("y", j)])
            a = colregs.assess_pair(traj.t, pi, traj.state("psi", i), pj, traj.state("psi", j),
                                    r_safe=g["r_safe"], collision_distance=g["collision_distance"],
                                    profile=profile, active_a=mask[:, i], active_b=mask[:, j])
            pairs.append({"a": names[i], "b": names[j], "min_distance": float(a.min_distance),
                          "t_min": float(a.t_min), "encounter": a.encounter, "compliant": a.compliant,
                          "encounter_b": a.encounter_b, "compliant_b": a.compliant_b,
                          "t_enter": None if a.t_enter is None else float(a.t_enter)})
            for k, enc, ok in ((i, a.encounter, a.compliant), (j, a.encounter_b, a.compliant_b)):
                if enc not in (None, "none"):
                    tag = f"{enc} {'✓' if ok else '✗' if ok is not None else ''}".strip()
                    labels[k] = ", ".join(filter(None, [labels.get(k), tag]))
        for k, o in enumerate(sc.obstacles):
            d = np.linalg.norm(pi - np.asarray(o.position), axis=1)
            d = np.where(mask[:, i], d, np.inf)
            kmin = int(np.argmin(d))
            pairs.append({"a": names[i], "b": f"obstacle{k}", "min_distance": float(d[kmin]),
                          "t_min": float(traj.t[kmin]), "encounter": "static" if d[kmin] <= g["r_safe"] else "none",
                          "compliant": None, "encounter_b": None, "compliant_b": None, "t_enter": None})
    collision = any(p["min_distance"] < g["collision_distance"] for p in pairs)
    metrics = {"method": sc.settings.method, "collision": bool(collision), "t_end": t_end,
               "ships": ships, "pairs": pairs}
    return ScenarioResult(sc, traj, metrics, labels)


def write_outputs(res: ScenarioResult, out, *, figure_name: str = "scenario.png", tracking: bool = False) -> None:
    """Write ``trajectory.npz``, ``trajectory.csv``, ``metrics.json`` and the figure(s) into ``out``."""
    from .cli import write_json
    from .plotting import plot_scenario, plot_tracking
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    res.trajectory.to_npz(out / "trajectory.npz")
    res.trajectory.to_csv(out / "trajectory.csv", names=res.names())
    if tracking:
        plot_tracking(res, out / figure_name)
    else:
        plot_scenario(res, out / figure_name)
    write_json(out / "metrics.json", res.metrics)
