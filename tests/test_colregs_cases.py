"""The hand-labelled full-scale COLREG cases (mmg_casadi.scenarios.colregs_cases): the published profile reproduces
every labelled verdict, every loose spot of a looser profile has its case, and a case's verdicts do not depend on
where it happens, which way north is, or the order of its ships."""

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mmg_casadi.colregs.profiles import SCORING_PROFILES
from mmg_casadi.colregs.verdict import RULES
from mmg_casadi.scenarios.colregs_cases import CASES, N_A, agreement, outcomes, simulate_case

POINTS = {"stand-on course keeping", "readily apparent", "own clearance", "safe passing distance",
          "multi-ship excuse", "17(a)(ii)", "17(c)", "14(c)", "TCPA horizon", "ample time", "past and clear"}


@pytest.fixture(scope="module")
def tracks():
    return {name: simulate_case(case) for name, case in CASES.items()}


def test_every_loose_spot_has_a_case_and_every_rule_is_kept_and_broken():
    assert POINTS <= {c.point for c in CASES.values()}
    seen = {}
    for case in CASES.values():
        assert case.rule
        for value in case.labels.values():
            if value != N_A:
                for rule, kept in value[1].items():
                    seen.setdefault(rule, set()).add(kept)
    assert {r for r in RULES if seen.get(r) == {True, False}} == set(RULES) - {"17b"}
    assert seen["17b"] == {False}


@pytest.mark.parametrize("name", list(CASES))
def test_the_published_profile_reproduces_every_labelled_verdict(tracks, name):
    agreed, labelled, wrong = agreement("published", {name: tracks[name]})[name]
    assert wrong == [] and agreed == labelled


def test_the_looser_profiles_disagree_where_the_issue_says(tracks):
    """The laboratory profile misses every full-scale encounter that a give-way ship resolves before 15 L and keeps
    the late, the too close and the not readily apparent give-way; ntnu-2023 reads the 14(c) case as a crossing."""
    lab = agreement("iitm-lab", tracks)
    for name in ("crossing_give_way_late", "crossing_too_close", "crossing_not_apparent", "stand_on_drifts",
                 "head_on_in_doubt"):
        assert lab[name][2], name
    ntnu = agreement("ntnu-2023", tracks)
    assert ("own", "tgt", "role", "head-on", "stand-on") in ntnu["head_on_in_doubt"][2]
    totals = {p: sum(a[0] for a in agreement(p, tracks).values()) for p in SCORING_PROFILES}
    assert totals["published"] > totals["ntnu-2023"] > totals["iitm-lab"]


def _moved(track, angle, shift, order):
    t, pos, psi, active, names = track
    c, s = math.cos(angle), math.sin(angle)
    pos = pos @ np.array([[c, s], [-s, c]]) + np.asarray(shift)
    return t, pos[:, order], (psi + angle)[:, order], active[:, order], [names[i] for i in order]


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(name=st.sampled_from(sorted(CASES)), angle=st.floats(-math.pi, math.pi),
       shift=st.tuples(st.floats(-500.0, 500.0), st.floats(-500.0, 500.0)),
       profile=st.sampled_from(list(SCORING_PROFILES)), seed=st.integers(0, 10))
def test_a_rotated_translated_or_reordered_case_keeps_every_verdict(tracks, name, angle, shift, profile, seed):
    order = list(np.random.default_rng(seed).permutation(len(CASES[name].ships)))
    base = outcomes(tracks[name], profile)
    assert outcomes(_moved(tracks[name], angle, shift, order), profile) == base


def test_a_mirror_image_swaps_port_and_starboard(tracks):
    """The rules are not symmetric under reflection: the mirror image of the lawful head-on (both ships turn to
    starboard) has both ships turning to port, which breaks Rule 14."""
    t, pos, psi, active, names = tracks["head_on_both_starboard"]
    mirrored = (t, pos * np.array([1.0, -1.0]), -psi, active, names)
    got = outcomes(mirrored, "published")
    assert {k: v[1]["14"] for k, v in got.items()} == {("own", "tgt"): False, ("tgt", "own"): False}
