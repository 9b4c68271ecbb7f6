"""Waypoint square

ILOS guidance with PD heading control around a 25 L square (paper, section *Waypoint Tracking*): the path with
ship outlines, the cross-track error and the rudder command against the actual rudder angle. This is the study at
full size; it takes a few seconds.

Full size: `mmg-casadi study waypoint-square --out out/waypoint-square`
"""

import sys

from studies import waypoint_square

waypoint_square.run(sys.argv[1])
