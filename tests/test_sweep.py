"""`mmg-casadi study sweep` (studies/sweep.py): one parameter swept, every value paired against a baseline."""

import json

import pytest

from mmg_casadi.cli import main
from mmg_casadi.errors import InputError
from studies.sweep import parse_values


def test_parse_values():
    assert parse_values("r_safe", "10,15, 20") == [10.0, 15.0, 20.0]
    with pytest.raises(InputError, match="values"):
        parse_values("r_safe", "10,,15")
    with pytest.raises(InputError, match="values"):
        parse_values("r_safe", "10,ten")
    with pytest.raises(InputError, match="values"):
        parse_values("r_safe", "10,10")
    with pytest.raises(InputError, match="param"):
        parse_values("r_saf", "10")


@pytest.mark.parametrize("argv,field", [(["--param", "nope", "--values", "1"], "param"),
                                        (["--param", "r_safe", "--values", "-1"], "values")])
def test_bad_sweep_exits_2(tmp_path, capsys, argv, field):
    out = tmp_path / "o"
    assert main(["study", "sweep", *argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and field in err[0]


@pytest.mark.slow
def test_small_sweep_pairs_values_on_the_same_runs(tmp_path):
    out = tmp_path / "sw"
    assert main(["study", "sweep", "--param", "r_safe", "--values", "10,20", "--runs", "6", "--envs", "1",
                 "--workers", "1", "--out", str(out)]) == 0
    m = json.loads((out / "metrics.json").read_text())
    assert m["baseline"] == 15.0 and m["values"] == [15.0, 10.0, 20.0]
    rows = {r["value"]: r for r in m["rows"]}
    assert rows[15.0]["difference"] == 0.0 and rows[15.0]["p_value"] == 1.0
    for r in rows.values():
        assert r["runs"] == 6
        n_fail = sum(r[f"failures_{k}"] for k in ("collision", "stalled", "timeout", "diverged"))
        assert n_fail == round(6 * (1 - r["success_rate"]))
        assert r["value_only"] - r["baseline_only"] == round(6 * r["difference"])
    assert (out / "sweep.png").exists() and (out / "sweep.md").exists()
    assert (out / "r_safe=10" / "runs.csv").exists()
