"""Tests of the paired summary of ``studies.traffic_perception`` on hand-made rows (no simulation)."""

from __future__ import annotations

import math

import pytest
from scipy.stats import binomtest

from mmg_casadi.errors import InputError
from mmg_casadi.montecarlo.stats import wilson
from studies import traffic_perception as tp


def _row(run: int, success: bool, compliant, risky: int, lawful: int, error=math.nan) -> dict:
    return {"environment": 5, "method": "vo", "run": run, "success": success, "colregs_compliant": compliant,
            "colregs_risky": risky, "colregs_lawful": lawful, "perception_error": error}


def _rows():
    # 10 runs; the baseline fails run 9, the sensor condition fails runs 0-3 and succeeds on run 9
    perfect = [_row(r, r != 9, None if r % 5 == 0 else r % 2 == 0, 0 if r % 5 == 0 else 2, 1) for r in range(10)]
    perfect = [{**r, "colregs_lawful": 0 if r["colregs_risky"] == 0 else 1 + (r["colregs_compliant"] is True)}
               for r in perfect]
    ais = [{**r, "success": r["run"] > 3, "perception_error": 0.01 * (r["run"] + 1)} for r in perfect]
    ais.append(_row(10, True, True, 1, 1, 0.5))  # a run the baseline lacks is not counted
    return {"perfect": perfect, "ais": ais}


def test_summary_pairs_each_condition_with_perfect_knowledge():
    table = tp.summarize(_rows(), runs=11, length_m=100.0)
    base, ais = table
    assert (base["condition"], ais["condition"]) == ("perfect", "ais")
    assert base["runs"] == ais["runs"] == 10 and "success_diff" not in base
    assert base["success_rate"] == 0.9 and ais["success_rate"] == 0.6
    assert (ais["success_ci_low"], ais["success_ci_high"]) == wilson(6, 10)
    # discordant runs: 0-3 (only perfect succeeds) and 9 (only ais): McNemar on 1 of 5
    assert ais["success_diff"] == pytest.approx(-0.3)
    assert ais["success_p"] == pytest.approx(binomtest(1, 5, 0.5).pvalue)
    assert ais["success_diff_low"] < -0.3 < ais["success_diff_high"]
    # runs 0 and 5 had no risky encounter: 8 runs judged, 16 encounters, 12 kept
    assert (base["colregs_risky"], base["colregs_lawful"]) == (16, 12)
    assert base["compliance_rate"] == 0.75 and (base["compliance_ci_low"], base["compliance_ci_high"]) == wilson(12, 16)
    assert ais["kept_runs"] == 8 and ais["kept_diff"] == 0.0 and ais["kept_p"] == 1.0
    assert math.isnan(base["perception_error_m"])
    assert ais["perception_error_m"] == pytest.approx(100.0 * 0.055)


def test_runs_beyond_the_requested_count_are_left_out():
    table = tp.summarize(_rows(), runs=5)
    assert [r["runs"] for r in table] == [5, 5]
    assert table[1]["success_rate"] == 0.2


def test_markdown_names_the_paired_change_and_the_mix(tmp_path):
    table = tp.summarize(_rows(), runs=10)
    md = tp.markdown(table, "mix:avoid=1")
    assert "| 5 | vo | ais | 60.0 [31.3, 83.2] | -30.0 [" in md
    assert "`mix:avoid=1`" in md
    tp.plot(table, tmp_path / "f.png")
    assert (tmp_path / "f.png").stat().st_size > 1000


def test_conditions_and_a_bad_mix():
    assert tp.CONDITIONS == ("perfect", "ais", "ais-radar", "mix", "hold")
    assert tp.conditions()["ais-radar"] == {"perception": "ais-radar"}
    with pytest.raises(InputError, match="targets"):
        tp.conditions("mix:avoid=0.5")
