"""COLREG machinery: geometry, encounter classification, rule scoring, pair assessment (numpy post-processing).

The encounter scorer, :func:`mmg_casadi.colregs.scorer.score_encounters`, judges only encounters with a risk of
collision (Rule 7), classifies them at the onset of risk and gives every rule a verdict and a graded score under a
named profile (:mod:`mmg_casadi.colregs.profiles`); :mod:`mmg_casadi.colregs.score` and
:mod:`mmg_casadi.colregs.assess` are the earlier pair scorer the runners still use.
"""
