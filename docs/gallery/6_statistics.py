"""Monte Carlo statistics

The six-panel figure of the statistical analysis: the paper's five (success rate, computation time per guidance
call, time to goal, CE and MCTE against the environment, with 95 % confidence intervals) and the own ship's COLREG
compliance. Here from only 4 runs per environment and one method, so the intervals are wide; the paper uses 5000
runs per environment (full-size results: {doc}`paper`).

Full size (the paper's three methods): `mmg-casadi study statistics --runs 5000 --out out/statistics`
"""

import shutil
import sys
import tempfile
from pathlib import Path

from mmg_casadi.montecarlo.study import run_study

out = Path(sys.argv[1])
with tempfile.TemporaryDirectory() as tmp:
    run_study(tmp, runs=4, envs="1-5", methods=["modified-vortex"], workers=1, progress=False)
    shutil.copyfile(Path(tmp) / "statistics.png", out / "statistics.png")
