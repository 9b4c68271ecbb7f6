"""Static obstacle

The own ship heads for a goal behind an obstacle of radius L/2 (paper, section *Reactive Guidance*): three cases,
including the obstacle just off the starboard bow where the sink-vortex field fails; shown for the inverse-square
and the modified sink-vortex fields.

Full size (every avoiding method): `mmg-casadi study static-obstacle --out out/static-obstacle`
"""

import sys

from studies import static_obstacle

static_obstacle.run(sys.argv[1], methods=["inverse-square", "modified-vortex"])
