"""Scenario-based MPC

One decision of `sb-mpc` (Johansen, Perez & Cristofaro 2016) in Imazu problem 2 (a crossing, the own ship gives
way; the target holds course and speed), at the onset of the give-way duty: the own ship's predicted track under
each control behaviour at full propulsion (coloured by its hazard; the numbers are the alteration from her heading),
the behaviour chosen (black: 30° to starboard), the target's constant-velocity prediction over the 15 L/U horizon
(red dots one L/U apart) and the own ship's safety distance. Right: the tracks that followed.

Full size: `mmg-casadi study imazu --methods sb-mpc --targets hold --out out/sb_mpc_imazu`
"""

import sys
from pathlib import Path

from matplotlib.figure import Figure

from mmg_casadi.guidance.sb_mpc_decision import decision_at
from mmg_casadi.plotting import FIGURE_DPI, marine_axes
from mmg_casadi.scenarios.imazu import imazu_case
from mmg_casadi.scenarios.run import run_scenario
from mmg_casadi.scenarios.scenario import scenario_from_dict

CASE, T_DECISION = 2, 14.75  # the decision at the onset of the give-way duty: +30° to starboard, held

result = run_scenario(scenario_from_dict(imazu_case(CASE, method="sb-mpc", targets="hold", t_max=60.0)))
decision = decision_at(result, T_DECISION)

fig = Figure(figsize=(13, 6.2), layout="constrained")
left, right = fig.subplots(1, 2)
decision.plot(left)
tr = result.trajectory
k = int(abs(tr.t - T_DECISION).argmin())
for i, ship in enumerate(result.scenario.ships):
    x, y = tr.state("x", i), tr.state("y", i)
    right.plot(y, x, color="tab:blue" if i == 0 else "tab:red", lw=2 if i == 0 else 1, label=ship.name)
    right.plot(y[k], x[k], "o", color="k", ms=4)
marine_axes(right)
right.legend(fontsize=8)
right.set_title(f"the tracks (dots: t = {T_DECISION:g} L/U, the decision at left)")
for ax in (left, right):
    ax.set_xlabel("y (east) [L]")
    ax.set_ylabel("x (north) [L]")
fig.savefig(Path(sys.argv[1]) / "sb_mpc_decision.png", dpi=FIGURE_DPI)
row = decision.to_pandas().iloc[decision.chosen]
print(f"chosen: {row['turn_deg']:+.0f} deg at level {row['level']:g}, hazard {row['hazard']:.3g}")
