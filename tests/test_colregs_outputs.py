"""The encounter scorer in the outputs: the ``colregs_profile`` parameter, ``encounters`` of every ship pair in
``metrics.json`` and the Monte Carlo's ``colregs_risky``/``colregs_lawful``/``colregs_score`` columns."""

import json
import math

import numpy as np
import pytest

from mmg_casadi.cli import main
from mmg_casadi.colregs.profiles import SCORING_PROFILES
from mmg_casadi.colregs.verdict import RULES
from mmg_casadi.errors import InputError
from mmg_casadi.montecarlo.execution import own_ship_encounters, run_scenarios
from mmg_casadi.params import PARAMETERS, resolve
from mmg_casadi.scenarios.encounters import colregs_cases
from mmg_casadi.scenarios.run import run_scenario
from mmg_casadi.scenarios.scenario import scenario_from_dict, with_method, with_params


def _two_ships(offset, heading_b=180.0, method="none"):
    """Ship a from (0, 0) east; ship b ``offset`` L to the side, head-on (180°) or on a parallel course (0°)."""
    start_b, goal_b = ([50.0, offset], [0.0, offset]) if heading_b == 180.0 else ([0.0, offset], [50.0, offset])
    return scenario_from_dict({
        "settings": {"method": method, "t_max": 60.0},
        "ships": [{"name": "a", "start": [0.0, 0.0], "heading": 0.0, "speed": 1.0, "waypoints": [[50.0, 0.0]]},
                  {"name": "b", "start": start_b, "heading": heading_b, "speed": 1.0, "waypoints": [goal_b]}]})


def test_colregs_profile_is_a_table_parameter():
    p = PARAMETERS["colregs_profile"]
    assert (p.default, p.kind, p.group, p.choices) == ("published", "choice", "outcome", tuple(SCORING_PROFILES))
    assert resolve({"colregs_profile": "ntnu-2023"})["colregs_profile"] == "ntnu-2023"
    with pytest.raises(InputError, match=r"^colregs_profile: expected one of: published, iitm-lab, ntnu-2023, got 'woerner'$"):
        resolve({"colregs_profile": "woerner"})


@pytest.mark.parametrize("offset", [0.0, 2.5])
def test_head_on_on_a_collision_course_is_one_unlawful_encounter_per_ship(offset):
    # 0 L (they collide) or 2.5 L abeam (< d_risk, 1 nm), nobody alters course: Rule 14 broken by both
    r = run_scenario(_two_ships(offset))
    pair = r.metrics["pairs"][0]
    for side, own in (("a", "a"), ("b", "b")):
        (e,) = pair["encounters"][side]
        assert (e["own"], e["applicable"], e["encounter"], e["role"], e["profile"]) == (own, True, "head-on",
                                                                                        "head-on", "published")
        assert e["compliant"] is False and e["rules"]["14"]["verdict"] is False and e["score"] < 0.5
        assert set(e["rules"]) == set(RULES) and e["onset"]["cpa"] == pytest.approx(offset, abs=0.05)
    assert pair["encounter"] == "head-on" and pair["compliant"] is False  # the legacy keys are still there
    assert json.loads(json.dumps(r.metrics))["params"]["colregs_profile"] == "published"
    row = run_scenarios([_two_ships(offset)], time_guidance_calls=False)[0]
    assert (row["colregs_risky"], row["colregs_lawful"]) == (1, 0)
    assert row["colregs_score"] == pytest.approx(pair["encounters"]["a"][0]["score"], abs=0.05)
    assert row["colregs_compliant"] is False and row["colregs_verdicts"].startswith("1:head-on:")


@pytest.mark.parametrize("offset, heading_b", [(60.0, 180.0), (8.0, 0.0)])
def test_a_pass_far_apart_has_no_encounter(offset, heading_b):
    # head-on 60 L abeam (never within R_safe), and a parallel course 8 L abeam (inside R_safe, never a risk)
    pair = run_scenario(_two_ships(offset, heading_b)).metrics["pairs"][0]
    for side in "ab":
        (e,) = pair["encounters"][side]
        assert e["applicable"] is False and e["compliant"] is None and e["score"] is None
    row = run_scenarios([_two_ships(offset, heading_b)], time_guidance_calls=False)[0]
    assert (row["colregs_risky"], row["colregs_lawful"]) == (0, 0) and math.isnan(row["colregs_score"])


def test_monte_carlo_columns_agree_with_metrics_json_and_follow_the_profile():
    sc = with_method(colregs_cases()["crossing"], "modified-vortex")
    for profile in SCORING_PROFILES:
        case = with_params(sc, {"colregs_profile": profile})
        own = run_scenario(case).metrics["pairs"][0]["encounters"]["a"]
        row = run_scenarios([case], chunk=101, time_guidance_calls=False)[0]  # odd chunk: every step kept
        risky = [e for e in own if e["applicable"]]
        assert {e["profile"] for e in own} == {profile}
        assert row["colregs_risky"] == len(risky) == 1
        assert row["colregs_lawful"] == sum(e["compliant"] for e in risky)
        assert row["colregs_score"] == pytest.approx(np.mean([e["score"] for e in risky]), abs=1e-9)


def test_own_ship_encounters_ignores_ships_out_of_risk_range():
    t = np.linspace(0.0, 40.0, 81)
    own = np.column_stack([t, 0 * t, 0 * t, 0 * t])
    head_on = np.column_stack([50.0 - t, 2.0 + 0 * t, np.pi + 0 * t, 0 * t])
    far = np.column_stack([t, 40.0 + 0 * t, 0 * t, 0 * t])
    two = own_ship_encounters(t, np.stack([own, head_on], axis=1))
    three = own_ship_encounters(t, np.stack([own, head_on, far], axis=1))
    assert two == three and (two["colregs_risky"], two["colregs_lawful"]) == (1, 0)
    assert own_ship_encounters(t, np.stack([own, far], axis=1))["colregs_risky"] == 0


def test_cli_records_the_profile(tmp_path, capsys):
    path = tmp_path / "head_on.toml"
    path.write_text('[settings]\nmethod = "none"\nt_max = 5.0\n[[ships]]\nname = "a"\nstart = [0.0, 0.0]\n'
                    'heading = 0.0\nspeed = 1.0\nwaypoints = [[50.0, 0.0]]\n[[ships]]\nname = "b"\n'
                    'start = [20.0, 1.0]\nheading = 180.0\nspeed = 1.0\nwaypoints = [[0.0, 1.0]]\n')
    out = tmp_path / "out"
    assert main(["simulate", str(path), "--set", "colregs_profile=ntnu-2023", "--out", str(out)]) == 0
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["params"]["colregs_profile"] == "ntnu-2023"
    assert {e["profile"] for side in "ab" for e in metrics["pairs"][0]["encounters"][side]} == {"ntnu-2023"}
    assert main(["simulate", str(path), "--set", "colregs_profile=strict", "--out", str(out)]) == 2
    assert "colregs_profile: expected one of: published, iitm-lab, ntnu-2023" in capsys.readouterr().err
