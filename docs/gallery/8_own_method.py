"""Your own method

The rule-based method of the how-to "Write your own method" (`docs/howto/examples/starboard_rule.py`, a plugin of
40 lines) beside the paper's modified sink-vortex in the head-on, crossing and overtaking encounters: it turns
`starboard_rule_turn_deg` to starboard of its waypoint while a ship within R_safe would pass closer than
`starboard_rule_d_cpa`.

Full size: `mmg-casadi study colregs --plugin docs/howto/examples/starboard_rule.py --methods
starboard-rule,modified-vortex --out out/own_method`
"""

import sys
from pathlib import Path

from mmg_casadi import load_plugin
from studies import colregs

load_plugin(Path(__file__).resolve().parents[1] / "howto" / "examples" / "starboard_rule.py")
colregs.run(sys.argv[1], methods=["starboard-rule", "modified-vortex"])
