"""A method of one's own, everywhere: the how-to's plugin from the command line (simulate, study imazu, study
statistics on both backends, study sweep and tune search over its own parameter), installed plugins, name clashes,
and method parameters that a run does not use."""

from __future__ import annotations

import csv
import json
import math
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from mmg_casadi import cli
from mmg_casadi.errors import InputError, ParameterError
from mmg_casadi.guidance import methods, plugins
from mmg_casadi.params import PARAMETERS

ROOT = Path(__file__).resolve().parents[1]
HOWTO = ROOT / "docs" / "howto" / "examples" / "starboard_rule.py"
NAME = "starboard-rule"


@pytest.fixture
def registry():
    """Whatever a test loads leaves the registry and the parameter table as they were."""
    before, loaded = set(methods.METHODS), dict(plugins._LOADED)
    yield
    for name in set(methods.METHODS) - before:
        methods.unregister(name)
    plugins._LOADED.clear()
    plugins._LOADED.update(loaded)
    assert set(methods.METHODS) == before and not any(k.startswith("starboard_rule") for k in PARAMETERS)


def _main(capsys, *argv) -> tuple[int, str]:
    code = cli.main([str(a) for a in argv])
    return code, capsys.readouterr().err


def _rows(path: Path) -> list[dict]:
    with path.open(newline="", encoding="utf-8") as fh:
        return [{k: v for k, v in r.items() if k != "guidance_call_us"} for r in csv.DictReader(fh)]


def test_the_howto_method_runs_in_simulate_and_its_parameter_reaches_the_step(tmp_path, capsys, registry):
    out = {}
    for turn in (20, 50):
        code, err = _main(capsys, "simulate", "head_on", "--plugin", HOWTO, "--method", NAME, "--set",
                          f"starboard_rule_turn_deg={turn}", "--out", tmp_path / str(turn))
        assert code == 0, err
        out[turn] = json.loads((tmp_path / str(turn) / "metrics.json").read_text())
    m = out[50]
    assert m["method"] == NAME and m["params"]["starboard_rule_turn_deg"] == 50.0
    assert m["params"]["starboard_rule_d_cpa"] == PARAMETERS["starboard_rule_d_cpa"].default
    assert not m["collision"] and all(s["reached_goal"] for s in m["ships"])
    # head-on, both ships turn to starboard: the wider alteration passes wider
    d20, d50 = (out[t]["pairs"][0]["min_distance"] for t in (20, 50))
    assert d50 > d20 + 0.5, (d20, d50)


def test_the_howto_method_is_refused_without_its_plugin(tmp_path, capsys):
    code, err = _main(capsys, "simulate", "head_on", "--method", NAME, "--out", tmp_path / "o")
    assert code == 2 and err.count("\n") == 1 and NAME in err and not (tmp_path / "o").exists()


def test_the_howto_method_in_study_statistics_local_and_ray_gives_the_same_rows(tmp_path, capsys, registry):
    pytest.importorskip("ray")
    common = ["study", "statistics", "--plugin", HOWTO, "--methods", f"{NAME},none", "--runs", "4", "--envs", "1",
              "--set", "starboard_rule_d_cpa=5", "--workers", "1"]
    code, err = _main(capsys, *common, "--out", tmp_path / "local")
    assert code == 0, err
    code, err = _main(capsys, *common, "--backend", "ray", "--out", tmp_path / "ray")
    assert code == 0, err
    local, ray = _rows(tmp_path / "local" / "runs.csv"), _rows(tmp_path / "ray" / "runs.csv")
    key = lambda r: (r["method"], int(r["run"]))  # noqa: E731
    assert sorted(local, key=key) == sorted(ray, key=key)
    assert {r["method"] for r in local} == {NAME, "none"} and len(local) == 8
    study = json.loads((tmp_path / "ray" / "runs.params.json").read_text())
    assert study["params"]["starboard_rule_d_cpa"] == 5.0


def test_a_ray_worker_runs_the_shipped_plugin_text_without_the_file(tmp_path, registry):
    """The batch carries the plugin's text: a worker that cannot read the file still builds the same method."""
    ray = pytest.importorskip("ray")
    from mmg_casadi.montecarlo.batching import BatchTask, RayExecutor
    copy = tmp_path / "copy_of_starboard_rule.py"
    copy.write_text(HOWTO.read_text())
    plugins.load(copy)
    shipped = plugins.sources()
    local = BatchTask(1, NAME, (0, 1), plugins=shipped)()
    copy.unlink()
    with RayExecutor(num_cpus=1) as ex:
        (_, rows), = list(ex.run([BatchTask(1, NAME, (0, 1), plugins=shipped)]))
    assert not ray.is_initialized()
    strip = lambda rs: json.dumps([{k: v for k, v in r.items() if k != "guidance_call_us"} for r in rs])  # noqa: E731
    assert strip(rows) == strip(local)  # (NaN as text: a run without a failure time equals one)


def test_the_howto_method_in_study_sweep_over_its_own_parameter(tmp_path, capsys, registry):
    code, err = _main(capsys, "study", "sweep", "--plugin", HOWTO, "--methods", NAME, "--param",
                      "starboard_rule_turn_deg", "--values", "10,60", "--runs", "6", "--envs", "1", "--workers", "1",
                      "--out", tmp_path)
    assert code == 0, err
    rows = {float(r["value"]): r for r in csv.DictReader((tmp_path / "sweep.csv").open())}
    assert set(rows) == {10.0, 40.0, 60.0}  # the default is the baseline
    ce = {v: float(r["mcte_mean"]) for v, r in rows.items()}
    assert len(set(ce.values())) == 3, ce  # each value ran its own guidance


def test_the_howto_method_in_tune_search_over_its_own_parameters(tmp_path, capsys, registry):
    code, err = _main(capsys, "tune", "search", "--plugin", HOWTO, "--method", NAME, "--search",
                      "starboard_rule_turn_deg=20:70", "--search", "starboard_rule_d_cpa=2:8", "--design", "4",
                      "--holdout", "4", "--candidates", "2", "--refine", "0", "--envs", "1", "--workers", "1",
                      "--out", tmp_path)
    assert code == 0, err
    report = json.loads((tmp_path / "report.json").read_text())
    assert report["method"] == NAME and set(report["search_box"]) == {"starboard_rule_turn_deg",
                                                                         "starboard_rule_d_cpa"}
    cands = report["candidates"]
    assert len(cands) == 3 and cands[0]["starboard_rule_turn_deg"] == 40.0
    assert all(20 <= c["starboard_rule_turn_deg"] <= 70 and 2 <= c["starboard_rule_d_cpa"] <= 8 for c in cands)


def test_the_howto_method_in_study_imazu(tmp_path, capsys, registry):
    code, err = _main(capsys, "study", "imazu", "--plugin", HOWTO, "--methods", NAME, "--targets", "hold",
                      "--out", tmp_path)
    assert code == 0, err
    res = json.loads((tmp_path / "metrics.json").read_text())["results"]["hold"][NAME]
    assert len(res["cases"]) == 22 and res["safe"] >= 11


def test_imazu_accepts_a_registered_method(registry):
    from mmg_casadi.scenarios.imazu import imazu_case, run_imazu
    plugins.load(HOWTO)
    assert imazu_case(2, method=NAME)["settings"]["method"] == NAME
    row, = run_imazu(NAME, "hold", cases=(2,), params={"t_max": 40.0})
    assert row["case"] == 2 and row["result"].metrics["method"] == NAME


def test_the_maritime_schema_reader_accepts_a_registered_method(registry):
    from mmg_casadi.scenarios.maritime_schema import traffic_situation_to_scenario
    plugins.load(HOWTO)
    sit = {"version": "0.2.0", "ownShip": {
        "static": {"id": 1, "name": "OS"}, "waypoints": [{"position": {"lat": 58.0, "lon": 10.0}}],
        "initial": {"position": {"lat": 58.0, "lon": 10.0}, "sog": 12.0, "cog": 0.0}}, "targetShips": []}
    sc = traffic_situation_to_scenario(sit, method=NAME, target_method=NAME)[0]
    assert sc.method_of(0) == NAME


UNUSED = [
    (["simulate", "head_on"], "cv_r_look=3"),                                          # shipped method, unused
    (["simulate", "head_on", "--method", "velocity-obstacle"], "k_vor0=-12"),
    (["study", "statistics", "--methods", "modified-vortex", "--runs", "2", "--envs", "1"], "cv_r_look=3"),
    (["study", "sweep", "--param", "cv_r_look", "--values", "0,3", "--runs", "2", "--envs", "1"], "kp=3"),
    (["study", "imazu", "--methods", "modified-vortex"], "vo_speed_weight=1"),
    (["tune", "colregs", "--design", "2", "--holdout", "2", "--candidates", "0"], "k_att=40"),
]


@pytest.mark.parametrize("argv,setting", UNUSED, ids=[" ".join(a[:2]) + " " + s for a, s in UNUSED])
def test_a_method_parameter_that_no_ship_uses_is_refused(tmp_path, capsys, argv, setting):
    code, err = _main(capsys, *argv, "--set", setting, "--out", tmp_path / "o")
    name = "cv_r_look" if "sweep" in argv else setting.split("=")[0]
    assert code == 2 and err.count("\n") == 1, err
    assert err.startswith(f"mmg-casadi: error: {name}: expected a parameter of a method the run uses")
    assert not (tmp_path / "o").exists()


def test_a_plugin_parameter_is_refused_without_its_method_and_unknown_without_its_plugin(tmp_path, capsys, registry):
    code, err = _main(capsys, "simulate", "head_on", "--set", "starboard_rule_d_cpa=3", "--out", tmp_path / "a")
    assert code == 2 and "--set starboard_rule_d_cpa: expected a parameter name" in err
    code, err = _main(capsys, "simulate", "head_on", "--plugin", HOWTO, "--set", "starboard_rule_d_cpa=3",
                      "--out", tmp_path / "b")
    assert code == 2 and "starboard_rule_d_cpa: expected a parameter of a method the run uses (modified-vortex" in err


def test_used_parameters_are_accepted_and_a_study_checks_against_all_of_its_methods(registry):
    from mmg_casadi.scenarios.run import packaged_scenario, run_scenario
    with pytest.raises(ParameterError, match="cv_r_look"):
        run_scenario(packaged_scenario("head_on"), {"cv_r_look": 3.0, "t_max": 1.0})
    r = run_scenario(packaged_scenario("head_on"), {"cv_r_look": 3.0, "t_max": 1.0}, method="colregs-vortex")
    assert r.params["cv_r_look"] == 3.0
    with methods.run_of(["modified-vortex", "colregs-vortex"], {"cv_r_look": 3.0}):  # a study of both methods
        r = run_scenario(packaged_scenario("head_on"), {"cv_r_look": 3.0, "t_max": 1.0})
    assert r.metrics["params"]["cv_r_look"] == 3.0  # metrics.json lists every resolved parameter, as before
    methods.check_used({"k_vor": -5.0, "vo_candidates": 40, "r_safe": 9.0}, ["colregs-vortex"])


def test_params_lists_a_plugins_parameters(tmp_path, capsys, registry):
    code = cli.main(["params", "--plugin", str(HOWTO), "--markdown"])
    out = capsys.readouterr().out
    assert code == 0 and "| `starboard_rule_turn_deg` | 40.0 | (0, 90] deg |" in out


def test_a_name_clash_is_refused_with_one_line_and_nothing_registered(tmp_path, capsys, registry):
    clash = tmp_path / "clash.py"
    clash.write_text(textwrap.dedent("""
        import mmg_casadi as mc
        mc.register(mc.Method("my-first", None, (), "test"))
        mc.register(mc.Method("modified-vortex", None, (), "test: a taken name"))
    """))
    code, err = _main(capsys, "simulate", "head_on", "--plugin", clash, "--out", tmp_path / "o")
    assert code == 2 and err.count("\n") == 1
    assert f"--plugin {clash}: method.name: expected a name not yet registered" in err and "'modified-vortex'" in err
    assert "my-first" not in methods.METHODS  # a plugin that fails registers nothing
    code, err = _main(capsys, "simulate", "head_on", "--plugin", HOWTO, "--plugin", tmp_path / "again.py",
                      "--out", tmp_path / "o")
    assert code == 2 and "no such file" in err


def test_register_refuses_bad_declarations(registry):
    from mmg_casadi import Method, Param
    P = Param("x_gain", 1.0, 0.0, None, "", "a gain", "test")
    with pytest.raises(InputError, match="method.params: expected names that start with the method's prefix 'y_'"):
        methods.register(Method("y", None, (), "test", params=(P,)))
    with pytest.raises(InputError, match="method.inputs"):
        methods.register(Method("x", None, (), "test", inputs=("no_such_input",)))
    with pytest.raises(InputError, match="method.params: expected parameter names not yet in the table"):
        methods.register(Method("x", None, (), "test", prefix="cv_", params=(
            Param("cv_r_look", 1.0, 0.0, None, "", "taken", "test"),)))
    with pytest.raises(InputError, match="method.name"):
        methods.register(Method("a,b", None, (), "test"))
    assert "x" not in methods.METHODS and "y" not in methods.METHODS


def test_a_structural_parameter_is_a_field_of_the_steps_shape(registry):
    """A structural parameter of a method (here, candidate headings) changes the compiled step's shape and key."""
    import casadi as ca
    from mmg_casadi import Command, Method, Param
    from mmg_casadi.closed_loop.problem import build_problem
    from mmg_casadi.scenarios.run import packaged_scenario
    from mmg_casadi.scenarios.scenario import with_method

    def fan(g):
        n = g.layout.option("fan_n")
        cands = [g.psi + 0.2 * k for k in range(n)]
        return Command(ca.vertcat(ca.cos(cands[-1]), ca.sin(cands[-1])))
    methods.register(Method("fan", fan, (), "test", params=(
        Param("fan_n", 3, 1, 9, "", "candidates", "test", kind="int", structural=True),)))
    sc = with_method(packaged_scenario("head_on"), "fan")
    a, b = (build_problem(sc, {"fan_n": n}).layout for n in (3, 5))
    assert a.options == (("fan_n", 3),) and b.option("fan_n") == 5 and a.key() != b.key()
    assert a.np == build_problem(with_method(sc, "none")).layout.np  # no numeric input for it


def test_an_installed_plugin_is_found_through_its_entry_point(tmp_path):
    site = tmp_path / "site"
    (site / "my_methods-0.1.dist-info").mkdir(parents=True)
    (site / "my_methods-0.1.dist-info" / "METADATA").write_text("Metadata-Version: 2.1\nName: my-methods\n"
                                                                 "Version: 0.1\n")
    (site / "my_methods-0.1.dist-info" / "entry_points.txt").write_text(
        "[mmg_casadi.methods]\nhold-on = my_methods:METHOD\n")
    (site / "my_methods.py").write_text(textwrap.dedent("""
        import casadi as ca
        from mmg_casadi import Command, Method, Param
        def _hold(g):
            return Command(ca.vertcat(ca.cos(g.psi + g.P["hold_on_bias"]), ca.sin(g.psi + g.P["hold_on_bias"])))
        METHOD = Method("hold-on", _hold, (), "test", params=(
            Param("hold_on_bias", 0.1, -1.0, 1.0, "rad", "heading bias", "test"),))
    """))
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(site), os.environ.get("PYTHONPATH", "")])}
    run = subprocess.run([sys.executable, "-m", "mmg_casadi.cli", "simulate", "head_on", "--method", "hold-on",
                          "--set", "hold_on_bias=0.2", "--set", "t_max=10", "--out", str(tmp_path / "o")],
                         env=env, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    m = json.loads((tmp_path / "o" / "metrics.json").read_text())
    assert m["method"] == "hold-on" and m["params"]["hold_on_bias"] == 0.2


def test_a_memory_row_and_a_deg_parameter_of_a_plugin(registry):
    """A plugin method's memory row is carried while it is in charge; its *_deg parameter reaches it in rad."""
    import casadi as ca
    from mmg_casadi import Command, Method, Param, simulate
    from mmg_casadi.closed_loop.problem import build_problem
    from mmg_casadi.scenarios.run import packaged_scenario
    from mmg_casadi.scenarios.scenario import with_method

    def latch(g):  # steer the heading held at the first step in charge plus the bias
        held = g.memory["latched"]
        return Command(ca.vertcat(ca.cos(held + g.P["latch_bias"]), ca.sin(held + g.P["latch_bias"])),
                       memory={"latched": held})
    methods.register(Method("latch", latch, (), "test", memory=("latched",), params=(
        Param("latch_bias_deg", 10.0, -90.0, 90.0, "deg", "bias", "test"),)))
    pr = build_problem(with_method(packaged_scenario("head_on"), "latch"), {"t_max": 60.0})
    assert pr.model.values["latch_bias"] == pytest.approx(math.radians(10.0))
    tr = simulate(pr.layout, pr.x0, pr.p)
    react = tr.auxiliary("reactive", 0) > 0.5
    k = int(np.argmax(react))
    psi_d = tr.auxiliary("psi_d", 0)
    assert react.any() and np.allclose(psi_d[k:k + 10], psi_d[k])  # the latched heading plus the bias
