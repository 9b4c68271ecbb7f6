"""Animations of the paper's cases

One animation per case of the paper, each ship under the modified sink-vortex field: on the left the whole run,
on the right a close-up that follows the own ship with every hull to scale, each ship's R_safe circle, the
heading the guidance orders (dotted, from the bow) and the COLREG role of each encounter the scorer finds, from
the onset of risk until it is released. Watch who turns first: in the head-on case both ships turn to starboard
together; in the crossing the give-way ship turns while the stand-on ship's field turns her too.

Full size (any scenario, any method): `mmg-casadi simulate head_on --animate head_on.gif --out out/head_on`
(`--animate run.mp4` with the extra `mmg-casadi[video]`)
"""

import sys
from pathlib import Path

from mmg_casadi.animation import animate
from mmg_casadi.scenarios.run import run_scenario

out = Path(sys.argv[1])
for case in ("static_obstacle", "head_on", "crossing", "overtaking", "conflict", "narrow_channel"):
    animate(run_scenario(case), out / f"{case}.gif", max_frames=60)
