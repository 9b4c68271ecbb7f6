"""Conflicting responsibilities

Three ships whose COLREG obligations conflict (paper): ship 1 at half speed, ship 2 overtaking it, ship 3 head-on
to both. Shown for the modified sink-vortex field and the velocity obstacle.

Full size (the paper's fields and the velocity obstacle): `mmg-casadi study conflict --out out/conflict`
"""

import sys

from studies import conflict

conflict.run(sys.argv[1], methods=["modified-vortex", "velocity-obstacle"])
