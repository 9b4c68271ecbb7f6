"""Traffic that behaves like traffic: what the target ships do (issue 48).

- :mod:`mmg_casadi.traffic.mix`: the values of the parameter ``targets`` (one behaviour, or a mix drawn per ship);
- :mod:`mmg_casadi.traffic.behaviour`: the behaviours a target can have, their inputs and scenario-file keys (the
  step's part: :mod:`mmg_casadi.closed_loop.behaviours`);
- :mod:`mmg_casadi.traffic.sample`: the per-run draws of a study with a mix.
"""
