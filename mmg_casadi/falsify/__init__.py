"""Falsification: search an environment's sampling envelope for the traffic that breaks a method.

A Monte Carlo study (:mod:`mmg_casadi.montecarlo`) says how often a method fails in a random sample of traffic; a
falsifier looks for the situations of least robustness inside the same envelope, which random sampling reaches only
by chance. The pieces:

* :mod:`~mmg_casadi.falsify.envelope`: the environment's sampling envelope as a parameter vector (starts, goals,
  headings, speeds, obstacles, optionally current and wind), with the sampler's rules as constraints, a projection
  onto them and the map to a scenario;
* :mod:`~mmg_casadi.falsify.robustness`: the objectives (collision margin, grounding margin, COLREG rule scores)
  evaluated exactly on the compiled rollout, and the smooth collision margin with its exact gradient with respect to
  the envelope's parameters (adjoint of the ``mapaccum`` rollout, from CasADi);
* :mod:`~mmg_casadi.falsify.search`: random sampling, CMA-ES and the multi-start projected gradient search at the
  same simulation budget;
* :mod:`~mmg_casadi.falsify.report`: failures clustered by encounter geometry, scenario files that ``mmg-casadi
  simulate`` replays exactly, a figure per failure and the robustness trace.
"""
