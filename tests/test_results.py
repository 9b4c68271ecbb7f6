"""Tests of the results table (append, resume, crash tolerance), the summary, the progress bar and the figure."""

from __future__ import annotations

import csv
import io
import math

import pytest

from mmg_casadi.errors import InputError
from mmg_casadi.montecarlo.plots import plot_statistics
from mmg_casadi.montecarlo.results import (
    RUN_COLUMNS,
    SUMMARY_COLUMNS,
    ResultsTable,
    Summary,
    mean_ci,
    summarize,
    wilson_interval,
)


def _row(env: int, method: str, run: int, success: bool = True, **extra) -> dict:
    row = {
        "environment": env, "method": method, "run": run, "seed": 12345, "success": success,
        "fleet_success": success, "failure": "" if success else "collision",
        "failure_pair": "" if success else "0-obs1", "failure_time": math.nan if success else 12.25,
        "time_to_goal": 60.0 + run / 3 if success else math.nan, "ce": 0.1 + run / 7, "mcte": 0.2 + run / 11,
        "fleet_time_to_goal": 70.0 + run, "fleet_ce": 0.15, "fleet_mcte": 0.25, "min_distance": 3.0 + run / 13,
        "guidance_call_us": 4.0 + run / 17, "n_ships": 3, "n_obstacles": 1,
        "current_speed": 0.1 * run / 23, "current_direction_deg": -170.0 + run, "wind_speed": 15.0 * run / 29,
        "wind_direction_deg": 33.5 - run,
        "failure_mechanism": "" if success else "obstacle",
        "colregs_risky": run % 3, "colregs_lawful": run % 3 // 2,
        "colregs_score": math.nan if run % 3 == 0 else 0.5 + run / 97,
        "colregs_compliant": None if run % 3 == 0 else run % 3 == run % 3 // 2,
        "colregs_verdicts": ";".join(f"{j + 1}:give-way:0.5:8={int(j < run % 3 // 2)}" for j in range(run % 3)),
        "colregs_rule9": math.nan if run % 2 else 0.25 + run / 101,
        "target_behaviours": "" if run % 2 else f"avoid;late {2 + run / 7:.2f};wrong 41.0;hold",
        "perception_error": math.nan if run % 2 else 0.01 + run / 103,
    }
    for profile in ("published", "iitm_lab", "ntnu_2023"):
        row[f"colregs_verdicts_{profile}"] = row["colregs_verdicts"]
    row.update(extra)
    return row


def _rows(n: int = 12) -> list[dict]:
    return [_row(env, m, r, success=(r % 4 != 3)) for env in (1, 2) for m in ("apf", "vo") for r in range(n)]


def _same(a: dict, b: dict) -> bool:
    for c in RUN_COLUMNS:
        x, y = a[c], b[c]
        if isinstance(x, float) and math.isnan(x):
            if not (isinstance(y, float) and math.isnan(y)):
                return False
        elif x != y:
            return False
    return True


# ---------------------------------------------------------------- Wilson interval and means


def test_wilson_interval_known_value():
    low, high = wilson_interval(95, 100)
    assert low == pytest.approx(0.888, abs=5e-4)
    assert high == pytest.approx(0.978, abs=1e-3)


def test_wilson_interval_edges():
    assert wilson_interval(0, 50)[0] == 0.0
    assert wilson_interval(50, 50)[1] == 1.0
    low, high = wilson_interval(5, 10)
    assert low == pytest.approx(1 - high) and low < 0.5 < high


@pytest.mark.parametrize("k, n", [(1, 0), (-1, 10), (11, 10), (1.5, 10), (True, 10)])
def test_wilson_interval_rejects(k, n):
    with pytest.raises(InputError):
        wilson_interval(k, n)


def test_mean_ci():
    mean, lo, hi = mean_ci([2.0, 4.0, 6.0, 8.0])
    s = math.sqrt(((3**2) + 1 + 1 + 3**2) / 3)
    assert mean == 5.0
    assert lo == pytest.approx(5 - 1.96 * s / 2) and hi == pytest.approx(5 + 1.96 * s / 2)
    assert mean_ci([3.0])[0] == 3.0 and math.isnan(mean_ci([3.0])[1])
    assert all(math.isnan(x) for x in mean_ci([math.nan, None]))


# ---------------------------------------------------------------- results table


def test_read_round_trips_types(tmp_path):
    table = ResultsTable(tmp_path / "runs.csv")
    rows = [_row(1, "apf", 0), _row(1, "apf", 1, success=False)]
    assert table.append(rows) == 2
    back = table.read()
    assert len(back) == 2 and all(_same(a, b) for a, b in zip(rows, back))
    r = back[1]
    assert type(r["environment"]) is int and type(r["success"]) is bool and type(r["ce"]) is float
    assert r["failure"] == "collision" and r["failure_pair"] == "0-obs1" and r["failure_time"] == 12.25
    assert math.isnan(r["time_to_goal"])
    with open(tmp_path / "runs.csv", newline="") as f:
        assert tuple(next(csv.reader(f))) == RUN_COLUMNS


def test_missing_columns_read_back_empty(tmp_path):
    table = ResultsTable(tmp_path / "runs.csv")
    table.append([{"environment": 3, "method": "vo", "run": 9}])
    r = table.read()[0]
    assert r["seed"] is None and r["success"] is None and r["failure"] == "" and math.isnan(r["ce"])


def test_header_written_once_and_duplicates_skipped(tmp_path):
    path = tmp_path / "runs.csv"
    table = ResultsTable(path)
    assert table.append(_rows()[:10]) == 10
    assert table.append(_rows()[5:20]) == 10
    assert table.append([_row(1, "apf", 0), _row(1, "apf", 0)]) == 0
    assert table.append([_row(9, "new", 0), _row(9, "new", 0)]) == 1
    text = path.read_text()
    assert text.count("environment,method,run") == 1
    assert len(table.read()) == 21
    assert len(table.completed()) == 21


def test_resume_after_killed_process(tmp_path):
    rows = _rows()
    reference = ResultsTable(tmp_path / "reference.csv")
    reference.append(rows)
    expected = reference.read()

    path = tmp_path / "runs.csv"
    table = ResultsTable(path)
    table.append(rows[:15])
    table.append(rows[15:30])
    full_line = path.read_text().splitlines()[-1]
    with open(path, "a") as f:
        f.write(full_line.replace(",apf,", ",vo,")[: len(full_line) // 2])

    reopened = ResultsTable(path)
    assert len(reopened.read()) == 30
    assert reopened.completed() == {(r["environment"], r["method"], r["run"]) for r in rows[:30]}
    assert reopened.append(rows[20:]) == len(rows) - 30
    assert path.read_text().endswith("\n")
    got = reopened.read()
    assert len(got) == len(rows)
    assert len({(r["environment"], r["method"], r["run"]) for r in got}) == len(rows)
    assert all(_same(a, b) for a, b in zip(got, expected))
    assert path.read_bytes() == (tmp_path / "reference.csv").read_bytes()


def test_truncated_header_is_rewritten(tmp_path):
    path = tmp_path / "runs.csv"
    path.write_text("environment,meth")
    table = ResultsTable(path)
    assert table.read() == [] and table.completed() == set()
    table.append([_row(1, "apf", 0)])
    assert len(table.read()) == 1
    assert path.read_text().startswith(",".join(RUN_COLUMNS) + "\n")


def test_truncated_line_after_completed_call_is_still_removed(tmp_path):
    path = tmp_path / "runs.csv"
    table = ResultsTable(path)
    table.append([_row(1, "apf", 0)])
    with open(path, "a") as f:
        f.write("1,apf,1,12")
    assert table.completed() == {(1, "apf", 0)}
    table.append([_row(1, "apf", 1)])
    assert [r["run"] for r in table.read()] == [0, 1]


def test_foreign_writer_is_noticed(tmp_path):
    path = tmp_path / "runs.csv"
    a, b = ResultsTable(path), ResultsTable(path)
    a.append([_row(1, "apf", 0)])
    b.append([_row(1, "apf", 1)])
    assert a.append([_row(1, "apf", 1), _row(1, "apf", 2)]) == 1
    assert [r["run"] for r in a.read()] == [0, 1, 2]


def test_bad_rows_and_bad_files(tmp_path):
    table = ResultsTable(tmp_path / "runs.csv")
    with pytest.raises(InputError):
        table.append([{"environment": 1, "method": "apf", "run": 0, "colour": "red"}])
    with pytest.raises(InputError):
        table.append([{"environment": 1, "method": "apf"}])
    with pytest.raises(InputError):
        table.append([_row(1, "apf", 0, failure="sunk")])
    with pytest.raises(InputError):
        table.append([{**_row(1, "apf", 0), "run": 1.5}])
    other = tmp_path / "other.csv"
    other.write_text("a,b,c\n1,2,3\n")
    with pytest.raises(InputError):
        ResultsTable(other).read()


def test_all_failure_kinds_accepted(tmp_path):
    table = ResultsTable(tmp_path / "runs.csv")
    kinds = ["", "collision", "timeout", "diverged", "stalled"]
    table.append([_row(1, "apf", i, success=(k == ""), failure=k) for i, k in enumerate(kinds)])
    assert [r["failure"] for r in table.read()] == kinds


# ---------------------------------------------------------------- summary


def _hand_table() -> list[dict]:
    rows = []
    for run, (ok, t, ce, us) in enumerate([(True, 10.0, 0.1, 2.0), (True, 20.0, 0.3, 4.0),
                                           (False, math.nan, 0.9, 6.0), (True, 30.0, 0.2, 8.0)]):
        rows.append({"environment": 2, "method": "modified-vortex", "run": run, "success": ok,
                     "time_to_goal": t, "ce": ce, "mcte": 0.5, "guidance_call_us": us})
    rows += [{"environment": 1, "method": "vo", "run": r, "success": False, "guidance_call_us": 10.0}
             for r in range(3)]
    rows += [{"environment": 1, "method": "modified-vortex", "run": 0, "success": True, "time_to_goal": 5.0,
              "ce": 0.4, "mcte": 0.1, "guidance_call_us": 1.0}]
    return rows


def test_summary_numbers():
    summary = summarize(_hand_table())
    assert [(r["environment"], r["method"]) for r in summary.rows] == [
        (1, "modified-vortex"), (1, "vo"), (2, "modified-vortex")]
    r = summary.rows[2]
    assert r["runs"] == 4 and r["success_rate"] == 0.75
    assert (r["success_ci_low"], r["success_ci_high"]) == pytest.approx(wilson_interval(3, 4))
    assert r["time_to_goal_mean"] == 20.0
    assert r["time_to_goal_ci_high"] - 20.0 == pytest.approx(1.96 * 10.0 / math.sqrt(3))
    assert r["ce_mean"] == pytest.approx(0.2)  # the failed run's 0.9 is excluded
    assert r["mcte_mean"] == 0.5 and r["mcte_ci_low"] == pytest.approx(0.5)
    assert r["guidance_call_us_mean"] == 5.0  # over all runs
    s = math.sqrt((9 + 1 + 1 + 9) / 3)
    assert r["guidance_call_us_ci_low"] == pytest.approx(5.0 - 1.96 * s / 2)
    vo = summary.rows[1]
    assert vo["success_rate"] == 0.0 and vo["success_ci_low"] == 0.0
    assert math.isnan(vo["time_to_goal_mean"]) and vo["guidance_call_us_mean"] == 10.0
    single = summary.rows[0]
    assert single["time_to_goal_mean"] == 5.0 and math.isnan(single["time_to_goal_ci_low"])
    assert summary.methods == ["modified-vortex", "vo"] and summary.environments == [1, 2]


def test_summary_per_encounter_colregs_rate_and_score():
    # 4 runs: 2 risky encounters (1 kept, score 0.5), none, 3 (3 kept, score 0.9), 1 (0 kept, score 0.2)
    runs = [(2, 1, 0.5), (0, 0, math.nan), (3, 3, 0.9), (1, 0, 0.2)]
    rows = [_row(1, "cv", r, colregs_risky=n, colregs_lawful=k, colregs_score=x) for r, (n, k, x) in enumerate(runs)]
    s = summarize(rows).rows[0]
    assert (s["colregs_risky"], s["colregs_lawful"], s["colregs_encounter_rate"]) == (6, 4, pytest.approx(4 / 6))
    assert (s["colregs_encounter_ci_low"], s["colregs_encounter_ci_high"]) == pytest.approx(wilson_interval(4, 6))
    assert s["colregs_score_mean"] == pytest.approx((2 * 0.5 + 3 * 0.9 + 1 * 0.2) / 6)  # over encounters
    assert s["compliance_runs"] == 2  # the legacy run-level columns are unchanged (runs 1 and 2 judged)
    md = summarize(rows).to_markdown().splitlines()
    assert "COLREG encounters kept [%] (risky)" in md[0] and "| 66.7 [30.0, 90.3] (6) | 0.650 |" in md[2]
    none = summarize([_row(1, "cv", 0, colregs_risky=0, colregs_lawful=0, colregs_score=math.nan)]).rows[0]
    assert none["colregs_risky"] == 0 and math.isnan(none["colregs_encounter_rate"])
    assert math.isnan(none["colregs_encounter_ci_low"]) and math.isnan(none["colregs_score_mean"])


def test_table_of_the_previous_version_is_refused(tmp_path):
    path = tmp_path / "runs.csv"
    version_3 = (*RUN_COLUMNS[:RUN_COLUMNS.index("colregs_risky")], "colregs_compliant", "colregs_encounters",
                 "colregs_risky", "colregs_lawful", "colregs_score")
    path.write_text(",".join(version_3) + "\n")
    with pytest.raises(InputError, match="older version, without the columns colregs_verdicts, colregs_rule9, "
                                         "colregs_verdicts_published"):
        ResultsTable(path).read()
    version_4 = RUN_COLUMNS[:RUN_COLUMNS.index("colregs_rule9")]
    path.write_text(",".join(version_4) + "\n")
    with pytest.raises(InputError, match="older version, without the columns colregs_rule9, colregs_verdicts_pub"):
        ResultsTable(path).read()
    version_5 = RUN_COLUMNS[:RUN_COLUMNS.index("colregs_verdicts_published")]
    path.write_text(",".join(version_5) + "\n")
    with pytest.raises(InputError, match="older version, without the columns colregs_verdicts_published, "
                                         "colregs_verdicts_iitm_lab, colregs_verdicts_ntnu_2023, target_behaviours, "
                                         "perception_error;"):
        ResultsTable(path).read()
    version_6 = RUN_COLUMNS[:RUN_COLUMNS.index("target_behaviours")]
    path.write_text(",".join(version_6) + "\n")
    with pytest.raises(InputError, match="older version, without the columns target_behaviours, perception_error;"):
        ResultsTable(path).read()


def test_summary_from_table_matches_summary_from_rows(tmp_path):
    table = ResultsTable(tmp_path / "runs.csv")
    rows = _rows()
    table.append(rows)
    a, b = summarize(rows).rows, summarize(table.read()).rows
    assert len(a) == len(b) == 4
    for x, y in zip(a, b):
        for c in SUMMARY_COLUMNS:
            assert x[c] == y[c] or (math.isnan(x[c]) and math.isnan(y[c]))


def test_summary_outputs(tmp_path):
    summary = summarize(_hand_table())
    md = summary.to_markdown()
    for method in ("modified-vortex", "vo"):
        assert method in md
    assert "75.0" in md and "n/a" in md
    assert len(md.splitlines()) == 2 + len(summary.rows)
    path = summary.to_csv(tmp_path / "out" / "summary.csv")
    with open(path, newline="") as f:
        table = list(csv.reader(f))
    assert tuple(table[0]) == SUMMARY_COLUMNS and len(table) == 4
    assert table[3][SUMMARY_COLUMNS.index("success_rate")] == "0.75"
    d = summary.to_dict()
    assert list(d) == list(SUMMARY_COLUMNS) and d["runs"] == [1, 3, 4]


def test_to_pandas_is_the_summary_table():
    df = summarize(_hand_table()).to_pandas()
    assert list(df.columns) == list(SUMMARY_COLUMNS) and len(df) == 3
    assert df["runs"].tolist() == [1, 3, 4]


def test_summarize_rejects_rows_without_key():
    with pytest.raises(InputError):
        summarize([{"method": "apf"}])


# ---------------------------------------------------------------- progress


class _Tty(io.StringIO):
    def isatty(self):
        return True


def test_plot_statistics_writes_png(tmp_path):
    rows = [_row(env, m, r, success=(r % 5 != 0)) for env in (1, 2, 3, 4, 5) for m in ("apf", "vo", "mv")
            for r in range(6)]
    path = tmp_path / "fig" / "statistics.png"
    fig = plot_statistics(summarize(rows), path=path)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert len(fig.axes) == 6  # the paper's five panels and the COLREG compliance
    assert [t.get_text() for t in fig.axes[0].get_legend().get_texts()] == ["apf", "vo", "mv"]


def test_plot_statistics_accepts_rows_and_rejects_junk():
    summary = summarize(_hand_table())
    assert len(plot_statistics(summary.rows).axes) == 6
    with pytest.raises(InputError):
        plot_statistics(Summary(rows=[]))
    with pytest.raises(InputError):
        plot_statistics("summary.csv")
