"""`study paper`: every study of the paper and the claim-by-claim report, run with a tiny --runs."""

import json

import pytest

from mmg_casadi.cli import main
from studies import paper


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    out = tmp_path_factory.mktemp("paper")
    res = paper.run(out, runs=2, envs=(1, 5), progress=False)
    return out, res


def test_claims_cover_every_results_section_with_valid_verdicts(report):
    out, res = report
    claims = json.loads((out / "claims.json").read_text())
    assert claims == json.loads(json.dumps(res["claims"]))
    assert len(claims) >= 15 and len({c["id"] for c in claims}) == len(claims)
    for c in claims:
        assert set(c) == {"id", "section", "claim", "paper", "measured", "ci", "verdict"}
        assert c["verdict"] in paper.VERDICTS
    sections = {c["section"] for c in claims}
    assert {"Waypoint tracking", "Inverse square potential", "Dynamic obstacle avoidance",
            "Conflicting responsibility", "Narrow waterways", "Statistical analysis"} <= sections
    md = (out / "claims.md").read_text()
    assert md.count("\n| ") == len(claims) + 1 and "2 runs per environment" in md


def test_claims_report_what_the_studies_measured(report):
    out, res = report
    by_id = {c["id"]: c for c in res["claims"]}
    wp = json.loads((out / "waypoint-square" / "metrics.json").read_text())
    assert by_id["W1"]["measured"] == round(wp["ce"], 4) and by_id["W1"]["paper"] == 0.1203
    stats = json.loads((out / "statistics" / "study.json").read_text())
    assert stats["params"]["vo_cone"] == "huang" and stats["params"]["vo_hold"] is True
    summary = json.loads((out / "statistics" / "metrics.json").read_text())["summary"]
    mv5 = next(r for r in summary if r["environment"] == 5 and r["method"] == "modified-vortex")
    assert by_id["T4"]["measured"] == round(mv5["success_rate"], 4)
    # 2 runs prove nothing: the interval of environment 5's success rate is wide
    lo, hi = by_id["T4"]["ci"]
    assert hi - lo > 0.5


def test_bad_runs_is_refused(tmp_path):
    assert main(["study", "paper", "--runs", "0", "--out", str(tmp_path / "o")]) == 2
    assert main(["study", "paper", "--methods", "none", "--out", str(tmp_path / "o")]) == 2
