"""The ``nmpc`` planner (issue 42): its tallies (solves, fallbacks) through state, run outputs and a study's
``tallies.csv``; targets on another method; one closed-loop run and its re-posed solves."""

from __future__ import annotations

import json

import numpy as np
import pytest

from mmg_casadi.cli import main
from mmg_casadi.closed_loop.layout import Layout
from mmg_casadi.closed_loop.state import initial_state, tallies
from mmg_casadi.errors import InputError
from mmg_casadi.guidance import methods
from mmg_casadi.guidance.contract import Method
from mmg_casadi.montecarlo.execution import sampled_scenario
from mmg_casadi.montecarlo.results import TALLIES_KEY, ResultsTable
from mmg_casadi.montecarlo.tallies import TallyTable, summarize, to_markdown
from mmg_casadi.params import PARAMETERS, TARGET_METHODS

SHIPS = [{"start": (0, 0), "heading": 0.3, "speed": 1.0, "path": [[0, 0], [50, 0]]},
         {"start": (40, 0), "heading": 3.1, "speed": 1.0, "path": [[40, 0], [0, 0]]}]


def _row(env, run, solves, fallbacks, method="nmpc"):
    return {"environment": env, "method": method, "run": run,
            TALLIES_KEY: {"nmpc_solves": float(solves), "nmpc_fallbacks": float(fallbacks)}}


def test_tally_table_appends_keeps_the_last_of_a_run_and_sums_per_cell(tmp_path):
    t = TallyTable(tmp_path / "tallies.csv")
    assert t.read() == [] and summarize([]) == [] and to_markdown([]) == ""
    assert t.append([{"environment": 5, "method": "colregs-vortex", "run": 0}]) == 0  # no tallies: no file
    assert not t.path.exists()
    assert t.append([_row(5, 0, 100, 0), _row(5, 1, 50, 5)]) == 2
    assert t.append([_row(5, 1, 60, 6), _row(4, 0, 10, 0)]) == 2  # run 1 again (a resumed batch): the last wins
    with open(t.path, "a", encoding="utf-8") as fh:
        fh.write("5,nmpc,7,3.0")  # a line cut short by an interrupted write is skipped
    rows = t.read()
    assert len(rows) == 3
    cells = {(c["environment"], c["method"]): c for c in summarize(rows)}
    c5 = cells[(5, "nmpc")]
    assert c5["runs"] == 2 and c5["nmpc_solves"] == 160.0 and c5["nmpc_fallbacks"] == 6.0
    assert c5["fallback_rate"] == pytest.approx(6 / 160) and c5["runs_with_fallback"] == 1
    assert cells[(4, "nmpc")]["fallback_rate"] == 0.0 and cells[(4, "nmpc")]["runs_with_fallback"] == 0
    md = to_markdown(summarize(rows)).splitlines()
    assert md[0].startswith("| environment | method | runs |") and len(md) == 4 and "0.0375" in md[2]


def test_tally_rows_are_not_columns_of_runs_csv_but_pass_its_check(tmp_path):
    from mmg_casadi.montecarlo.results import RUN_COLUMNS
    assert TALLIES_KEY not in RUN_COLUMNS
    with pytest.raises(InputError, match="rows\\[0\\]"):
        ResultsTable(tmp_path / "runs.csv").append([{"environment": 5, "method": "nmpc", "run": 0, "bogus": 1}])


def test_layout_and_state_carry_the_tallies_of_the_methods_in_use():
    assert Layout(("colregs-vortex", "none")).tallies == ()
    lay = Layout(("nmpc", "colregs-vortex"))
    assert lay.tallies == ("nmpc_solves", "nmpc_fallbacks")
    x = initial_state(lay, SHIPS)
    assert x[lay.row("nmpc_solves", 0)] == 0.0 and x[lay.row("nmpc_fallbacks", 0)] == 0.0
    assert x[lay.row("nmpc_live", 0)] == 0.3  # other memory rows start at the heading
    x[lay.row("nmpc_solves", 0)] = 7.0
    assert tallies(lay, x) == [{"nmpc_solves": 7.0, "nmpc_fallbacks": 0.0}, {}]


def test_a_tally_must_be_a_memory_row():
    with pytest.raises(InputError, match="method.tallies"):
        methods.register(Method("tally-test", lambda g: None, (), "test", memory=("a",), tallies=("b",)))
    assert "tally-test" not in methods.METHODS


def test_nmpc_is_on_demand_and_the_targets_may_use_another_method():
    assert "nmpc" in methods.offered()
    assert set(TARGET_METHODS) == set(methods.AVOIDING) | set(methods.PLANNERS) | set(methods.ON_DEMAND)
    for name in TARGET_METHODS:
        assert PARAMETERS["targets"].check(name) == name
    with pytest.raises(InputError, match="targets: expected avoid, hold, a method .*nmpc.* or mix:"):
        PARAMETERS["targets"].check("none")
    sc = sampled_scenario(5, "nmpc", 3, params={"targets": "colregs-vortex"})
    assert sc.ships[0].method in (None, "nmpc") and sc.settings.method == "nmpc"
    assert {sh.method for sh in sc.ships[1:]} == {"colregs-vortex"}
    held = sampled_scenario(5, "colregs-vortex", 3, params={"targets": "hold"})
    same = sampled_scenario(5, "colregs-vortex", 3, params={"targets": "colregs-vortex"})
    assert [sh.start for sh in held.ships] == [sh.start for sh in same.ships]  # the same draws, other targets
    assert {sh.method for sh in held.ships[1:]} == {"none"}


def test_targets_refuses_an_unknown_method(capsys):
    assert main(["study", "statistics", "--methods", "nmpc", "--targets", "vortex", "--runs", "1", "--envs", "5",
                 "--out", "/nonexistent/never"]) == 2
    err = capsys.readouterr().err
    assert "--targets: expected avoid, hold, a method (" in err and "nmpc) or mix:" in err and "got 'vortex'" in err
    assert len(err.splitlines()) == 1


def test_head_on_run_records_every_solve_and_no_fallback(tmp_path):
    """Two ``nmpc`` ships head-on: both alter to starboard, pass port to port well clear, and the metrics record
    per ship the solves (at most one per guidance step) and no fallback."""
    assert main(["simulate", "head_on", "--method", "nmpc", "--out", str(tmp_path)]) == 0
    m = json.loads((tmp_path / "metrics.json").read_text())
    assert m["method"] == "nmpc" and m["collision"] is False
    dt = m["params"]["dt"]
    for ship in m["ships"]:
        t = ship["tallies"]
        assert t["nmpc_fallbacks"] == 0.0
        assert 50 <= t["nmpc_solves"] <= m["t_end"] / dt  # at most one solve per step
        assert ship["reached_goal"] and ship["min_distance"] > 10.0  # beyond the planner's passing distance
    enc = m["pairs"][0]["encounters"]["a"][0]
    assert enc["encounter"] == "head-on" and enc["compliant"] is True
    assert enc["rules"]["14"]["starboard_deg"] > 30.0 and enc["rules"]["14"]["port_deg"] == 0.0


@pytest.mark.slow
def test_re_posed_solves_match_the_closed_loop_plan():
    from mmg_casadi.closed_loop.nmpc_solves import solve_statistics, solves_of_run
    from mmg_casadi.scenarios.run import packaged_scenario
    from mmg_casadi.scenarios.scenario import with_method
    solves = solves_of_run(with_method(packaged_scenario("head_on"), "nmpc"))
    s = solve_statistics(solves)
    assert s["solves"] > 50 and s["failed"] == 0
    assert s["max_plan_difference"] < 1e-6  # the same generated code on the same inputs
    assert 1 <= s["iterations"]["median"] <= 10 and np.isfinite(s["time_us"]["p99"])
