"""COLREG encounters

Head-on, crossing and overtaking encounters (paper, section *Dynamic Obstacle Avoidance*, COLREG Rules 13–15),
here with two of the five avoiding methods (the full study runs every one): paths with R_safe circles, and the distance between the ships while
inside R_safe with the 2 L collision line.

Full size (every avoiding method): `mmg-casadi study colregs --out out/colregs`
"""

import sys

from studies import colregs

colregs.run(sys.argv[1], methods=["modified-vortex", "velocity-obstacle"])
