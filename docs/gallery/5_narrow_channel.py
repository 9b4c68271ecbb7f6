"""Narrow channel

A head-on encounter in a 10 L wide channel whose walls are line sources (paper, section *Narrow Waterways*),
shown for the modified sink-vortex field and the velocity obstacle.

Full size (the paper's fields and the velocity obstacle): `mmg-casadi study narrow-channel --out out/narrow-channel`
"""

import sys

from studies import narrow_channel

narrow_channel.run(sys.argv[1], methods=["modified-vortex", "velocity-obstacle"])
