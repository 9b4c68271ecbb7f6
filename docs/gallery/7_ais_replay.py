"""AIS replay

A target replays its recorded track exactly (interpolated in time inside the compiled closed loop) while the own
ship, handed over at 10:02 from her recorded state, gives way to it with colregs-vortex. The tracks come from the
shipped synthetic AIS sample `mmg_casadi/data/ais/synthetic_ais.csv` (fictitious ships, MMSIs 999000001-3); the
third ship's reports begin later and it is left out.

Full size (the same run): `mmg-casadi replay mmg_casadi/data/ais/synthetic_ais.csv --own 999000001 --start
2026-05-04T10:02:00 --method colregs-vortex --out replay.toml` then `mmg-casadi simulate replay.toml --out
out/replay` (the scenario is shipped as `ais_replay`: `mmg-casadi simulate ais_replay --out out/replay`)
"""

import sys
from importlib import resources
from pathlib import Path

from mmg_casadi.scenarios.ais_replay import ais_scenario, load_ais_csv, parse_time
from mmg_casadi.scenarios.run import run_scenario, write_outputs

sample = resources.files("mmg_casadi").joinpath("data", "ais", "synthetic_ais.csv")
sc, report = ais_scenario(load_ais_csv(sample), "999000001", targets="track", method="colregs-vortex",
                          start=parse_time("2026-05-04T10:02:00", "start"))
res = run_scenario(sc)
write_outputs(res, Path(sys.argv[1]), figure_name="ais_replay.png")
pair = res.metrics["pairs"][0]
print(f"left out: {report['left_out']}; CPA {pair['min_distance']:.2f} L at t = {pair['t_min']:g} L/U; "
      f"collision: {res.metrics['collision']}")
