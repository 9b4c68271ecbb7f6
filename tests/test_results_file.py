"""The one results file (docs/results/current.toml, studies/results.py): README's tables and task outputs are its
rendering, README states no result outside them, new rows and profiles grow the tables, and README's five tasks
print what it shows (the quick ones here; all of them in a fresh environment in the slow test)."""

from __future__ import annotations

import copy
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from studies import results

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")
DATA = results.load()
QUICK_TASKS = ("simulate", "method", "manoeuvre", "python")


def _outside_blocks(text: str) -> str:
    text = re.sub(r"<!-- results:[\w-]+ -->.*?<!-- /results -->", "", text, flags=re.S)
    return re.sub(r"```.*?```", "", text, flags=re.S)


def test_readme_is_a_short_guide_with_every_table_from_the_file():
    assert len(README.splitlines()) <= 250
    found = results.blocks(README)
    assert set(found) == set(results.BLOCKS), set(results.BLOCKS) ^ set(found)
    assert results.render_text(README, DATA) == README, "README differs from the results file: " \
                                                          "python -m studies.results render"
    for name in ("quick", "claims", "tasks"):
        assert name in DATA, f"the results file has no {name}"


def test_readme_states_no_result_outside_the_generated_blocks():
    prose = _outside_blocks(README)
    assert "%" not in prose
    assert not re.search(r"\b\d+\.\d+ ?(L|L/U|kn|m|s)\b(?!/)", prose.replace("18.6 s", "")), \
        re.findall(r"\b\d+\.\d+ ?(?:L|L/U|kn|m|s)\b", prose)
    for page in ("getting_started.md", "index.md", "results.md"):
        text = _outside_blocks((ROOT / "docs" / page).read_text(encoding="utf-8"))
        assert "%" not in text.replace("95 %", ""), page


def test_rows_are_consistent():
    for r in DATA.get("statistics", []):
        assert r["success_ci"][0] <= r["success"] <= r["success_ci"][1]
        assert r["kept_ci"][0] <= r["kept"] <= r["kept_ci"][1] and r["encounters"] > 0
    for r in DATA.get("imazu", []):
        assert 0 <= r["kept"] <= r["encounters"] and 0 <= r["safe"] <= r["cases"] == 22
        assert len(r["unsafe"]) == r["cases"] - r["safe"]
    q = DATA["quick"]
    assert q["waypoint_square"]["ce"] == pytest.approx(0.1367, abs=5e-5)
    assert {c["study"] for c in q["cases"]} == {"static-obstacle", "colregs", "conflict", "narrow-channel"}


def _row(profile, method, success=0.9, kept=0.8):
    return {"profile": profile, "method": method, "environment": 5, "runs": 100, "seed": 0, "success": success,
            "success_ci": [success - 0.05, success + 0.04], "encounters": 50, "kept": kept,
            "kept_ci": [kept - 0.1, kept + 0.08], "score": 0.9, "roles": {"head-on": 0.75},
            "command": f"mmg-casadi study statistics --set colregs_profile={profile} --out DIR"}


def test_a_new_profile_and_new_planners_grow_the_tables(monkeypatch):
    monkeypatch.setattr(results, "default_profile", lambda: "iitm-lab")  # the default first, whichever it is
    data = {"statistics": [_row("iitm-lab", "colregs-vortex"), _row("ntnu-2023", "colregs-vortex", kept=0.5)]}
    before = results.statistics_table(data)
    grown = copy.deepcopy(data)
    grown["statistics"] += [_row("published", "colregs-vortex", kept=0.6), _row("iitm-lab", "sb-mpc", 0.97, 0.91),
                            _row("ntnu-2023", "sb-mpc", 0.97, 0.7), _row("iitm-lab", "nmpc", 0.99, 0.93)]
    table = results.statistics_table(grown)
    head = table.splitlines()[0]
    assert head.count("kept [95 % CI]") == before.splitlines()[0].count("kept [95 % CI]") + 1
    assert [ln.split("|")[1].strip() for ln in table.splitlines()[2:5]] == ["colregs-vortex", "sb-mpc", "nmpc"]
    assert "| nmpc | 99.0 % [94.0, 103.0] | 93.0 % [83.0, 101.0] (50) | 75.0 % | – | – | – | – | – |" in table
    assert head.index("`iitm-lab`") < head.index("`ntnu-2023`") < head.index("`published`")
    monkeypatch.setattr(results, "default_profile", lambda: "published")  # the lead changes the default
    head = results.statistics_table(grown).splitlines()[0]
    assert head.index("`published`") < head.index("`iitm-lab`") < head.index("`ntnu-2023`")
    assert "iitm-lab" not in results.statistics_table({"statistics": [_row("published", "nmpc")]})


@pytest.mark.parametrize("task", QUICK_TASKS)
def test_readme_task_prints_what_the_readme_shows(task, tmp_path):
    t = next(t for t in DATA["tasks"] if t["id"] == task)
    assert f"```sh\n{t['command']}\n```" in README and t["output"].rstrip() in README
    assert results.run_task(t["command"], tmp_path) == t["output"]


@pytest.mark.slow
def test_the_readme_study_task_prints_what_the_readme_shows(tmp_path):
    t = next(t for t in DATA["tasks"] if t["id"] == "study")
    assert results.run_task(t["command"], tmp_path) == t["output"]


@pytest.mark.slow
def test_readme_tasks_in_a_fresh_environment(tmp_path):
    """A clone of this commit, a new virtual environment with `pip install .`, an empty compile cache: the five
    tasks print what README shows (about 5 minutes on 2 cores)."""
    clone = tmp_path / "clone"
    subprocess.run(["git", "clone", "-q", str(ROOT), str(clone)], check=True)
    subprocess.run([sys.executable, "-m", "venv", str(tmp_path / "venv")], check=True)
    py = tmp_path / "venv" / "bin" / "python"
    subprocess.run([str(py), "-m", "pip", "install", "-q", str(clone)], check=True, capture_output=True)
    env = dict(os.environ, MMG_CASADI_CACHE=str(tmp_path / "cache"))
    work = tmp_path / "work"
    work.mkdir()
    for t in DATA["tasks"]:
        proc = subprocess.run([str(py), "-c", "import sys; from studies.results import run_task; "
                               "sys.stdout.write(run_task(sys.argv[1], __import__('pathlib').Path(sys.argv[2])))",
                               t["command"], str(work)], env=env, capture_output=True, text=True, cwd=work)
        assert proc.returncode == 0, proc.stderr[-3000:]
        assert proc.stdout == t["output"], t["id"]
