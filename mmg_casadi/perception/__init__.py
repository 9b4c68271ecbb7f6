"""What the own ship knows of the other ships: AIS and radar with noise, and a tracker (issue 48).

- :mod:`mmg_casadi.perception.sensors`: the AIS reporting intervals of ITU-R M.1371-5 and the sensors' noise;
- :mod:`mmg_casadi.perception.tracker`: a constant-velocity Kalman filter with nearest-neighbour association;
- :mod:`mmg_casadi.perception.rng`: the random numbers drawn inside the compiled step (MRG32k3a);
- :mod:`mmg_casadi.perception.layer`: the modes, state rows and inputs of the layer and its description;
  the update itself runs in the compiled step (:mod:`mmg_casadi.closed_loop.sensing`).

Off by default (parameter ``perception``): every method then sees the true states, as before.
"""
