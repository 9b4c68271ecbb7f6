"""The project's Sphinx extension: what the docs build generates from code before Sphinx reads the sources.

On ``builder-inited`` it writes into ``docs/_generated/`` (not in git):

* ``parameters.md`` — the parameter table, :func:`mmg_casadi.params.markdown_table`;
* ``flat_api.rst`` — a table of ``mmg_casadi.__all__`` pointing at the modules that define the names;
* ``claims.md`` — ``docs/claims.md`` when it exists, else a placeholder;
* ``results_<block>.md`` — the tables of the results file ``docs/results/current.toml`` (:mod:`studies.results`);
* ``gallery.md`` and ``gallery/<script>/*.png`` (and ``*.gif``) — every script in ``docs/gallery/`` run in its own process
  (``python SCRIPT OUT_DIR``), its figures embedded under its docstring;

and copies ``notebooks/*.ipynb`` into ``docs/notebooks/`` so that myst-nb executes them. A gallery script that
fails is a build warning (an error under ``-W``). Gallery results are reused while neither the script nor any
source file of the packages changed (a hash stamp next to the figures). References to ``mmg_casadi.NAME`` of the
flat API resolve to the object where NAME is defined.
"""

from __future__ import annotations

import ast
import hashlib
import os
import shutil
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from sphinx.util import logging

logger = logging.getLogger(__name__)

DOCS = Path(__file__).resolve().parents[1]
ROOT = DOCS.parent
GENERATED = DOCS / "_generated"
PACKAGES = ("mmg_casadi", "studies", "tuning")

CLAIMS_PLACEHOLDER = """\
```{note}
The table of the paper's claims and what this code gets for each of them is not in this build yet
(`docs/claims.md` is missing). Until then, `make run` writes every study's numbers to `out/*/metrics.json`.
```
"""


def _write(path: Path, text: str) -> None:
    """Write ``text`` unless the file already holds it (so Sphinx does not see a changed source)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    if not path.exists() or path.read_text(encoding="utf-8") != text:
        path.write_text(text, encoding="utf-8")


def write_parameters() -> None:
    from mmg_casadi.params import markdown_table
    _write(GENERATED / "parameters.md", markdown_table() + "\n")


def write_flat_api() -> None:
    """A table of ``mmg_casadi.__all__``: the flat name, the object where it is defined, its summary line."""
    import importlib
    import inspect

    from sphinx.pycode import ModuleAnalyzer

    import mmg_casadi
    rows = []
    for name, (module, original) in sorted(_flat_names().items(), key=lambda kv: kv[0].lower()):
        obj = getattr(importlib.import_module(module), original)
        if inspect.isfunction(obj) or inspect.isclass(obj):
            doc = inspect.getdoc(obj) or ""
        else:
            doc = "\n".join(ModuleAnalyzer.for_module(module).find_attr_docs().get(("", original), []))
        summary = doc.strip().split("\n\n")[0].replace("\n", " ")
        rows += [f"   * - ``mc.{name}``", f"     - :py:obj:`~{module}.{original}`", f"     - {summary}"]
    missing = sorted(set(mmg_casadi.__all__) - set(_flat_names()))
    if missing:
        logger.warning("mmg_casadi.__all__ names not imported from a submodule in __init__.py: %s", missing,
                       type="mmg_docs", subtype="flat_api")
    head = [".. list-table::", "   :header-rows: 1", "   :widths: 20 25 55", "",
            "   * - name", "     - defined as", "     - summary"]
    _write(GENERATED / "flat_api.rst", "\n".join(head + rows) + "\n")


def _flat_names() -> dict[str, tuple[str, str]]:
    """``mmg_casadi.__all__`` name → (defining module, name there), read from the package's imports."""
    import mmg_casadi
    lazy = getattr(mmg_casadi, "_PUBLIC", None)  # the flat names loaded on first use: name -> (module, name there)
    if lazy is not None:
        return {k: tuple(v) for k, v in lazy.items() if k in mmg_casadi.__all__}
    tree = ast.parse(Path(mmg_casadi.__file__).read_text(encoding="utf-8"))
    out = {}
    for node in tree.body:
        if isinstance(node, ast.ImportFrom) and node.module:
            module = f"mmg_casadi.{node.module}" if node.level == 1 else node.module
            if module.startswith("mmg_casadi."):
                for alias in node.names:
                    out[alias.asname or alias.name] = (module, alias.name)
    return {k: v for k, v in out.items() if k in mmg_casadi.__all__}


def write_claims() -> None:
    src = DOCS / "claims.md"
    _write(GENERATED / "claims.md", src.read_text(encoding="utf-8") if src.exists() else CLAIMS_PLACEHOLDER)


def copy_notebooks() -> None:
    dest = DOCS / "notebooks"
    dest.mkdir(exist_ok=True)
    wanted = {p.name for p in (ROOT / "notebooks").glob("*.ipynb")}
    for stale in dest.glob("*.ipynb"):
        if stale.name not in wanted:
            stale.unlink()
    for name in wanted:
        src, dst = ROOT / "notebooks" / name, dest / name
        if not dst.exists() or dst.read_bytes() != src.read_bytes():
            shutil.copyfile(src, dst)


# -- gallery -------------------------------------------------------------------------------------------------

def _source_hash() -> str:
    h = hashlib.sha256()
    for pkg in PACKAGES:
        for f in sorted((ROOT / pkg).rglob("*")):
            if f.is_file() and f.suffix in (".py", ".toml"):
                h.update(f.relative_to(ROOT).as_posix().encode() + b"\0" + f.read_bytes())
    return h.hexdigest()


def _script_doc(script: Path) -> tuple[str, str]:
    """Title (first docstring line) and body (the rest, Markdown) of a gallery script."""
    doc = ast.get_docstring(ast.parse(script.read_text(encoding="utf-8"))) or ""
    title, _, body = doc.partition("\n")
    if not title.strip():
        raise ValueError(f"{script.name}: a gallery script starts with a docstring whose first line is its title")
    return title.strip(), body.strip()


def _figures(out: Path) -> list[Path]:
    """The figures (PNG) and animations (GIF) a gallery script wrote, in name order."""
    return sorted([*out.glob("*.png"), *out.glob("*.gif")])


def _run_script(script: Path, out: Path, stamp: str) -> tuple[Path, float, str | None]:
    """Run ``script`` into ``out`` unless the stamp says its figures are current; returns (script, seconds, error)."""
    done = out / ".stamp"
    if done.exists() and done.read_text() == stamp and _figures(out):
        return script, 0.0, None
    shutil.rmtree(out, ignore_errors=True)
    out.mkdir(parents=True)
    t0 = time.perf_counter()
    env = dict(os.environ, MPLBACKEND="Agg")
    proc = subprocess.run([sys.executable, str(script), str(out)], cwd=ROOT, env=env, capture_output=True,
                          text=True)
    seconds = time.perf_counter() - t0
    if proc.returncode != 0:
        return script, seconds, (proc.stderr or proc.stdout)[-3000:]
    if not _figures(out):
        return script, seconds, "wrote no PNG or GIF into its output directory"
    done.write_text(stamp)
    return script, seconds, None


def build_gallery(workers: int) -> None:
    scripts = sorted((DOCS / "gallery").glob("*.py"))
    stamp_base = _source_hash()
    jobs = []
    for s in scripts:
        stamp = hashlib.sha256((stamp_base + s.read_text(encoding="utf-8")).encode()).hexdigest()
        jobs.append((s, GENERATED / "gallery" / s.stem, stamp))
    with ThreadPoolExecutor(max_workers=max(1, workers)) as pool:
        results = list(pool.map(lambda j: _run_script(*j), jobs))
    sections = []
    for (script, seconds, error), (_, out, _) in zip(results, jobs):
        if error:
            logger.warning("gallery script %s failed:\n%s", script.name, error, type="mmg_docs", subtype="gallery")
            continue
        if seconds:
            logger.info("gallery: %s ran in %.1f s", script.name, seconds)
        title, body = _script_doc(script)
        parts = [f"## {title}", "", body, ""]
        for png in _figures(out):
            rel = png.relative_to(DOCS).as_posix()
            what = "animation" if png.suffix == ".gif" else "short run"
            parts += [f":::{{figure}} /{rel}", ":width: 100%", "", f"`{png.name}` ({what})", ":::", ""]
        parts += [f"Short-run script: `docs/gallery/{script.name}`", ""]
        sections.append("\n".join(parts))
    _write(GENERATED / "gallery.md", "\n".join(sections))


# -- CLI reference -------------------------------------------------------------------------------------------

def cli_commands(parser, path=("mmg-casadi",)):
    """``(command path, parser, help)`` of every command of ``parser``, depth first (``parser`` itself first)."""
    import argparse
    out = [(path, parser, parser.description or "")]
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            helps = {a.dest: a.help or "" for a in action._choices_actions}
            for name, sub in action.choices.items():
                for p, s, h in cli_commands(sub, path + (name,)):
                    out.append((p, s, helps.get(name, "") if p == path + (name,) else h))
    return out


def _cell(text) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def _cli_rows(parser) -> list[str]:
    import argparse
    rows = []
    for a in parser._actions:
        if isinstance(a, (argparse._HelpAction, argparse._SubParsersAction)):
            continue
        if a.option_strings:
            name = ", ".join(f"`{o}`" for o in a.option_strings)
            arg = "" if a.nargs == 0 else f"`{a.metavar or a.dest.upper()}`"
        else:
            name, arg = f"`{a.metavar or a.dest}`", "positional"
        if a.required and a.option_strings:
            default = "required"
        elif a.nargs == 0 or a.default in (None, [], argparse.SUPPRESS) or not a.option_strings:
            default = ""
        else:
            default = f"`{a.default}`"
        extra = " (repeatable)" if isinstance(a, argparse._AppendAction) else ""
        rows.append(f"| {name} | {arg} | {default} | {_cell((a.help or '') + extra)} |")
    return rows


def write_cli() -> None:
    """``cli.md``: one section per command of :func:`mmg_casadi.cli.build_parser`, usage and every option."""
    from mmg_casadi.cli import build_parser
    old = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = "110"  # argparse wraps the usage line at the terminal width
    try:
        parts = []
        for path, parser, help_text in cli_commands(build_parser()):
            if len(path) == 1:
                continue
            level = "#" * min(len(path), 4)
            parts += [f"{level} {' '.join(path)}", "", _cell(help_text).rstrip(".") + ".", "",
                      "```text", parser.format_usage().strip(), "```", ""]
            rows = _cli_rows(parser)
            if rows:
                parts += ["| option | argument | default | meaning |", "|---|---|---|---|", *rows, ""]
    finally:
        if old is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = old
    _write(GENERATED / "cli.md", "\n".join(parts))


# -- file formats --------------------------------------------------------------------------------------------

def _check_keys(what: str, documented, actual) -> None:
    """A build warning (an error under -W) when the documented keys are not exactly the code's."""
    missing, extra = sorted(set(actual) - set(documented)), sorted(set(documented) - set(actual))
    if missing or extra:
        logger.warning("docs/_ext/mmg_docs.py documents the %s out of step with the code: undocumented %s, "
                       "no longer in the code %s", what, missing, extra, type="mmg_docs", subtype="formats")


def _table(head: tuple[str, ...], rows) -> list[str]:
    return ["| " + " | ".join(head) + " |", "|" + "---|" * len(head),
            *("| " + " | ".join(_cell(c) for c in r) + " |" for r in rows), ""]


RUN_COLUMN_DOCS = {
    "environment": ("int", "environment 1–5 of the paper's statistical analysis"),
    "method": ("str", "guidance method of every ship of the run"),
    "run": ("int", "run index within (environment, method); the scenario depends only on (environment, run, seed)"),
    "seed": ("int", "base seed of the sampler"),
    "success": ("bool", "the own ship (ship 0) reached its goal without a collision"),
    "fleet_success": ("bool", "every ship reached its goal without a collision"),
    "failure": ("str", "`\"\"` on success, else one of the run failures below"),
    "failure_pair": ("str", "collision partners: `0-j` (ship j), `0-obs<k>` (obstacle k), `0-wall<k>` (wall "
                     "segment k)"),
    "failure_time": ("float, L/U", "time of the collision or of the stall; empty otherwise"),
    "time_to_goal": ("float, L/U", "own ship's time to its goal (empty when it did not arrive)"),
    "ce": ("float", "own ship's control effort, eq. (controller_effort_equation)"),
    "mcte": ("float, L", "own ship's mean cross-track error, eq. (crosstrack_metric_equation)"),
    "fleet_time_to_goal": ("float, L/U", "mean time to goal over the ships that reached their goals"),
    "fleet_ce": ("float", "mean CE over the ships that reached their goals"),
    "fleet_mcte": ("float, L", "mean MCTE over the ships that reached their goals"),
    "min_distance": ("float, L", "own ship's closest approach to any ship or obstacle centre"),
    "guidance_call_us": ("float, µs", "measured time of one guidance call of the method in this run's layout"),
    "n_ships": ("int", "ships in the scenario, own ship included"),
    "n_obstacles": ("int", "static obstacles"),
    "current_speed": ("float, U", "sampled uniform current (0 without `--current`)"),
    "current_direction_deg": ("float, deg", "direction the current flows towards"),
    "wind_speed": ("float, m/s", "sampled true wind speed (0 without `--wind`)"),
    "wind_direction_deg": ("float, deg", "direction the wind comes from"),
    "failure_mechanism": ("str", "`\"\"` on success, else one of the failure mechanisms below"),
    "colregs_risky": ("int", "encounter scorer: the own ship's encounters with a risk of collision"),
    "colregs_lawful": ("int", "encounter scorer: of those, the ones it was compliant in"),
    "colregs_score": ("float", "encounter scorer: mean graded score of those encounters (0–1)"),
    "colregs_compliant": ("bool", "encounter scorer: every risky encounter kept (empty without one; secondary)"),
    "colregs_verdicts": ("str", "encounter scorer: each risky encounter as `other:role:score:rule=0|1/...` "
                         "(`:e` appended where an excuse by a give-way duty to another ship changed a verdict), "
                         "encounters separated by `;` (`mmg_casadi.montecarlo.encounter_summary`); profile "
                         "`colregs_profile`"),
    "colregs_verdicts_published": ("str", "the same encounters' verdicts under the `published` profile"),
    "colregs_verdicts_iitm_lab": ("str", "the same under the `iitm-lab` profile"),
    "colregs_verdicts_ntnu_2023": ("str", "the same under the `ntnu-2023` profile"),
    "colregs_rule9": ("float", "COLREG Rule 9(a): the own ship's share of her time in a narrow channel on its "
                      "starboard side (kept from 0.9; `mmg_casadi.colregs.narrow_channel`); empty when she was "
                      "never in one"),
    "target_behaviours": ("str", "what each target ship did, in ship order, `;`-separated: the study's `targets` "
                          "(`avoid`, `hold`) or, with a mix, each target's draw: `late DELAY`, `wrong TURN`, "
                          "`intent TIME course ±DEG` or `intent TIME speed FACTOR` (L/U, deg; "
                          "`mmg_casadi.traffic.sample.describe`)"),
    "perception_error": ("float, L", "with `perception`: the mean distance between where the own ship's method saw "
                         "a target and where it was, over the time known targets were within R_safe; empty with "
                         "perfect knowledge (`mmg_casadi.perception.layer.perception_error`)"),
}

ENCOUNTER_DOCS = {
    "profile": "the scoring profile whose verdicts the row counts (`colregs_verdicts_<profile>`)",
    "environment": "environment", "method": "method",
    "group": "`all`, a role (`head-on`, `give-way`, `stand-on`, `overtaking`, `overtaken`) or a rule "
             "(`rule 8` … `rule 17c`)",
    "n": "risky encounters of the group (for a rule: those in which it applies)",
    "kept": "of those, the ones kept (every applicable rule; for a rule: that rule)",
    "rate": "`kept / n`", "ci_low": "Wilson 95 % interval, low", "ci_high": "Wilson 95 % interval, high",
    "score_mean": "mean graded score of the group's encounters (0–1)",
    "excused": "of the group's encounters, those whose verdict an excuse by a give-way duty to another ship changed",
}

PAIR_DOCS = {
    "profile": "the scoring profile of both methods' verdicts",
    "environment": "environment", "method_a": "method A", "method_b": "method B",
    "pairs": "encounters both methods had: same run, same other ship, same occurrence",
    "rate_a": "A's compliance over the pairs", "rate_b": "B's compliance over the pairs",
    "both": "pairs both kept", "a_only": "pairs only A kept", "b_only": "pairs only B kept",
    "neither": "pairs neither kept", "difference": "`rate_a - rate_b`",
    "ci_low": "Newcombe 95 % interval of the difference, low", "ci_high": "Newcombe 95 % interval, high",
    "p_value": "exact McNemar test on the discordant pairs",
    "unpaired_a": "encounters only A had (B never came into risk with that ship)", "unpaired_b": "the same for B",
}

OUTCOME_DOCS = {
    "reached": "came within `goal_tolerance` of its final waypoint",
    "diverged": "the state left the model's envelope (|u|, |v| < 3, |r| < 5); `ce`/`mcte` are null",
    "stalled": "made no progress towards its goal during the last `stall_window` before `t_max`; `stalled_at` "
               "is the position closest to the goal",
    "timeout": "none of the above by `t_max`",
    "grounded": "touched land: her voyage ended there (held where she touched, engine stopped, rudder amidships; a "
                "static hazard to the others); never `reached`, `time_to_goal` is null",
    "collided": "came within the collision distance of a ship or an obstacle, or touched a wall: her voyage ended "
                "there as for `grounded`",
}

RUN_FAILURE_DOCS = {
    "collision": "the own ship came within `collision_distance` of an obstacle centre or, of a ship's, times the "
                 "two ships' mean length (in L), or touched a wall (a collision wins over every other failure)",
    "grounding": "the own ship touched land: its centre came within half its beam of an edge of a land polygon",
    "timeout": "no collision, the own ship's outcome is `timeout`",
    "diverged": "no collision, the own ship's outcome is `diverged`",
    "stalled": "no collision, the own ship's outcome is `stalled`",
}

MECHANISM_DOCS = {
    "started-too-close": "the collision was decided by the initial positions and headings (the paper's first "
                         "mechanism): it happened no later than the KCS's 90° turn time with full rudder, or the "
                         "agent hit could not be avoided from the start by the own ship alone",
    "obstacle-near-goal": "hit a static obstacle whose centre lies within `near_goal_distance` of the own goal "
                          "(the paper's second mechanism, static)",
    "near-goal": "hit a ship while one of the two was within `near_goal_distance` of its own goal (the paper's "
                 "second mechanism)",
    "ship-ship": "any other collision with a ship",
    "obstacle": "any other collision with a static obstacle",
    "grounding": "touched land (the run's failure `grounding`)",
    "stalled": "no collision, goal not reached: stalled",
    "timeout": "no collision, goal not reached: timed out",
    "diverged": "no collision, goal not reached: diverged",
}


def _summary_doc(column: str):
    from mmg_casadi.montecarlo.failures import MECHANISMS
    from mmg_casadi.montecarlo.results import METRICS
    fixed = {
        "environment": "environment", "method": "method", "runs": "runs in the cell",
        "success_rate": "fraction of runs with `success`", "success_ci_low": "Wilson 95 % interval, low",
        "success_ci_high": "Wilson 95 % interval, high",
        "compliance_runs": "runs with a risky encounter",
        "compliance_rate": "fraction of those with `colregs_compliant`",
        "compliance_ci_low": "Wilson 95 % interval, low", "compliance_ci_high": "Wilson 95 % interval, high",
        "colregs_risky": "sum of `colregs_risky` over the runs", "colregs_lawful": "sum of `colregs_lawful`",
        "colregs_encounter_rate": "`colregs_lawful / colregs_risky` (per encounter)",
        "colregs_encounter_ci_low": "Wilson 95 % interval, low",
        "colregs_encounter_ci_high": "Wilson 95 % interval, high",
        "colregs_score_mean": "mean of `colregs_score`",
    }
    if column in fixed:
        return fixed[column]
    for m in METRICS:
        over = " over the successful runs" if m != "guidance_call_us" else " over every run"
        for suffix, text in (("_mean", "mean of `{m}`" + over), ("_ci_low", "normal 95 % interval of the mean, low"),
                             ("_ci_high", "normal 95 % interval of the mean, high")):
            if column == m + suffix:
                return text.format(m=m)
    for mech in MECHANISMS:
        if column == f"failures_{mech.replace('-', '_')}":
            return f"failed runs with `failure_mechanism` = `{mech}`"
    return None


def write_formats() -> None:
    """``formats_*.md``: scenario keys, result columns, statuses and mechanisms from the code's own tuples."""
    import dataclasses

    from mmg_casadi.closed_loop.outcome import OUTCOMES, RUN_FAILURES
    from mmg_casadi.guidance.methods import METHODS
    from mmg_casadi.montecarlo.failures import MECHANISMS
    from mmg_casadi.montecarlo.results import RUN_COLUMNS, SUMMARY_COLUMNS
    from mmg_casadi.params import PARAMETERS
    from mmg_casadi.scenarios import scenario as S
    from mmg_casadi.scenarios import geojson_land as GJ
    from mmg_casadi.vessel.library import VESSELS

    methods = ", ".join(f"`{m}`" for m in METHODS)
    ship_defaults = {f.name: f.default for f in dataclasses.fields(S.ShipSpec)
                     if f.default is not dataclasses.MISSING}
    obstacle_defaults = {f.name: f.default for f in dataclasses.fields(S.ObstacleSpec)
                         if f.default is not dataclasses.MISSING}
    lo, hi = S.SPEED_RANGE
    tables = {
        "settings": ("table", "required", "scenario-wide settings: `method` and any parameter of the table"),
        "ships": ("array of tables", "required, ≥ 1", "the ships; the first is the own ship"),
        "obstacles": ("array of tables", "none", "static circular obstacles"),
        "walls": ("array of tables", "none", "channel walls, each a polyline"),
        "land": ("array of tables", "none", "land, each a polygon; touching it is a grounding"),
        "environment": ("table", "calm water", "uniform current and steady wind (aliases of table parameters)"),
        "chart": ("table", "none", "land from a GeoJSON file (Polygon/MultiPolygon features), after `[[land]]`"),
    }
    ship = {
        "name": ("string", "`ship<i>`", "", "unique name"),
        "start": ("[x, y]", "required", "L", "start position"),
        "heading": ("number", "required", "deg", "initial heading, from x (north) towards y (east)"),
        "speed": ("number", "required", "U", f"speed on the first leg (sets the propeller rpm), in [{lo}, {hi}]"),
        "waypoints": ("list of [x, y]", "required", "L", "at least one; the last one is the goal"),
        "method": ("string", "`settings.method`" if ship_defaults.get("method") is None else ship_defaults["method"],
                   "", f"this ship's method: {methods}"),
        "stays": ("bool", f"`{str(ship_defaults['stays']).lower()}`", "",
                  "after reaching its goal the ship stays as an obstacle"),
        "speeds": ("list of numbers", "`speed` on every leg", "U",
                   f"speed on the leg to each waypoint, one per waypoint, each in [{lo}, {hi}]"),
        "vessel": ("string", "the table's `vessel`" if ship_defaults.get("vessel") is None else ship_defaults["vessel"],
                   "", "hull: " + ", ".join(f"`{v}`" for v in VESSELS)),
        "length_m": ("number > 0", "its vessel's", "m", "the ship's own length, as a traffic situation gives it, "
                     "written back by `convert`: its collision geometry (two ships collide within "
                     "`collision_distance` times their mean length in L, the default hull's 230 m); it still sails "
                     "its vessel's model"),
        "beam_m": ("number > 0", "its vessel's", "m", "the ship's own beam (maritime-schema `dimensions.width`): it "
                   "touches a wall or land at half of it"),
        "metadata": ("table", "none", "", "further static data kept as read (maritime-schema names: `id`, `mmsi`, "
                     "`imo`, `shipType`, `sogMax`, `dimensions.height`, ...) and written back by `convert`; "
                     "strings, finite numbers, booleans, arrays and tables (no datetimes)"),
        "behaviour": ("string", "none (her method)", "",
                      "a target's behaviour (`mmg_casadi.traffic`): `avoid` (her method), `hold` (course and speed), "
                      "`late` (her method acts once it has wanted to for `late_delay`), `wrong` (to port by "
                      "`wrong_turn` in a head-on or crossing risk), `intent` (holds her route, whose waypoint is "
                      "where she changes her mind); not the first ship"),
        "route": ("string", "the parameter `route`", "", "`plan`: her route is planned around the land clearing every "
                  "polygon by `route_clearance` (`mmg_casadi.scenarios.routes`); `as-given`: her waypoints as "
                  "written"),
        "late_delay": ("number >= 0", "required with `late`", "L/U", "a late ship's delay"),
        "wrong_turn": ("number in (0, 90]", "required with `wrong`", "deg", "a wrong-way ship's turn to port"),
        "track": ("string or table", "none (simulated)", "L/U, L",
                  "a replayed ship's recorded track: a CSV file with the columns `t, x, y` (relative to the scenario "
                  "file's folder) or `{t = [...], x = [...], y = [...]}`, times increasing from at or before 0; the "
                  "ship follows it interpolated in time instead of being simulated, and takes no `start`, "
                  "`heading`, `speed`, `waypoints`, `speeds` or `method` (not the first ship)"),
    }
    obstacle = {
        "position": ("[x, y]", "required", "L", "centre"),
        "radius": ("number > 0", f"`{obstacle_defaults['radius']}`", "L", "radius"),
    }
    wall = {"points": ("list of [x, y]", "required", "L",
                       "polyline of ≥ 2 points; each consecutive pair is one wall segment")}
    land = {"points": ("list of [x, y]", "required", "L",
                       "polygon of ≥ 3 points (closed: the last joins the first), with an area; no ship starts and "
                       "no waypoint lies inside; its edges act like walls and a ship whose centre comes within "
                       "half its beam of one grounds")}
    chart = {
        "land_file": ("string", "required", "", "GeoJSON file (RFC 7946, lon/lat on WGS-84) relative to the scenario "
                      "file's folder; each Polygon's exterior ring is one land polygon (interior rings ignored)"),
        "origin": ("[lat, lon]", "the converted scenario's reference", "deg",
                   "the local frame's (0, 0): positions are projected on the azimuthal equidistant plane about it, "
                   "as the maritime-schema import does; required unless the file's header records a reference"),
        "length_m": ("number > 0", "`230.0` (or the header's)", "m", "metres per ship length L"),
    }
    _check_keys("top-level scenario tables", tables, S.TOP_KEYS)
    _check_keys("[chart] keys", chart, GJ.CHART_KEYS)
    _check_keys("[[land]] keys", land, S.LAND_KEYS)
    _check_keys("[[ships]] keys", ship, S.SHIP_KEYS)
    _check_keys("[[obstacles]] keys", obstacle, S.OBSTACLE_KEYS)
    _check_keys("[[walls]] keys", wall, S.WALL_KEYS)

    def param_row(key, name):
        p = PARAMETERS[name]
        default = str(p.default).lower() if p.kind == "bool" else str(p.default)
        allowed = p.allowed().removeprefix("a number in ").removeprefix("one of: ")
        return (f"`{key}`", p.kind, f"`{default}`", allowed, p.meaning)

    out = ["### Tables", ""]
    out += _table(("table", "type", "default", "meaning"), ((f"`[{k}]`" if v[0] == "table" else f"`[[{k}]]`",
                                                            *v) for k, v in tables.items()))
    out += ["### `[settings]`", "",
            "`method` and every parameter of the table (see {doc}`concepts`, where each has its source). "
            "`dt`, `t_max`, `r_safe`, `collision_distance` and `goal_tolerance` are the scenario's settings "
            "proper; the others override the parameter for this scenario. Allowed values include the unit.", ""]
    rows = [("`method`", "string", "required", methods, "guidance method of every ship without its own")]
    rows += [param_row(k, k) for k in S.SETTINGS_KEYS if k != "method"]
    out += _table(("key", "type", "default", "allowed", "meaning"), rows)
    for title, spec in (("`[[ships]]`", ship), ("`[[obstacles]]`", obstacle), ("`[[walls]]`", wall),
                        ("`[[land]]`", land), ("`[chart]`", chart)):
        out += [f"### {title}", ""]
        out += _table(("key", "type", "default", "unit", "meaning"), ((f"`{k}`", *v) for k, v in spec.items()))
    out += ["### `[environment]`", "",
            "Each key is an alias of a parameter of the table; giving it also in `[settings]` is an error.", ""]
    out += _table(("key", "type", "default", "allowed", "meaning"),
                  (param_row(k, v) for k, v in S.ENVIRONMENT_KEYS.items()))
    _write(GENERATED / "formats_scenario.md", "\n".join(out))

    _check_keys("runs.csv columns", RUN_COLUMN_DOCS, RUN_COLUMNS)
    out = _table(("column", "type, unit", "meaning"),
                 ((f"`{c}`", *RUN_COLUMN_DOCS.get(c, ("", ""))) for c in RUN_COLUMNS))
    _write(GENERATED / "formats_runs.md", "\n".join(out))

    docs = {c: _summary_doc(c) for c in SUMMARY_COLUMNS}
    _check_keys("summary.csv columns", {c for c, d in docs.items() if d}, SUMMARY_COLUMNS)
    out = _table(("column", "meaning"), ((f"`{c}`", docs[c] or "") for c in SUMMARY_COLUMNS))
    _write(GENERATED / "formats_summary.md", "\n".join(out))

    from mmg_casadi.montecarlo.encounter_summary import ENCOUNTER_COLUMNS, PAIR_COLUMNS
    for name, documented, columns in (("colregs.csv", ENCOUNTER_DOCS, ENCOUNTER_COLUMNS),
                                      ("colregs_comparisons.csv", PAIR_DOCS, PAIR_COLUMNS)):
        _check_keys(f"{name} columns", documented, columns)
    out = _table(("column", "meaning"), ((f"`{c}`", ENCOUNTER_DOCS[c]) for c in ENCOUNTER_COLUMNS))
    out += ["", "`colregs_comparisons.csv`:", ""]
    out += _table(("column", "meaning"), ((f"`{c}`", PAIR_DOCS[c]) for c in PAIR_COLUMNS))
    _write(GENERATED / "formats_colregs.md", "\n".join(out))

    _check_keys("ship outcomes", OUTCOME_DOCS, OUTCOMES)
    _check_keys("run failures", RUN_FAILURE_DOCS, RUN_FAILURES)
    _check_keys("failure mechanisms", MECHANISM_DOCS, MECHANISMS)
    out = ["### Ship status (`metrics.json` `ships[].status`)", ""]
    out += _table(("status", "meaning"), ((f"`{k}`", OUTCOME_DOCS.get(k, "")) for k in OUTCOMES))
    out += ["### Run failure (`runs.csv` `failure`)", "", "`\"\"` when the run succeeded.", ""]
    out += _table(("failure", "meaning"), ((f"`{k}`", RUN_FAILURE_DOCS.get(k, "")) for k in RUN_FAILURES))
    out += ["### Failure mechanism (`runs.csv` `failure_mechanism`)", "",
            "Checked in this order; the first that applies wins ({py:mod}`mmg_casadi.montecarlo.failures`). "
            "`\"\"` when the run succeeded.", ""]
    out += _table(("mechanism", "meaning"), ((f"`{k}`", MECHANISM_DOCS.get(k, "")) for k in MECHANISMS))
    _write(GENERATED / "formats_status.md", "\n".join(out))

    from mmg_casadi.scenarios import run as run_module
    _write(GENERATED / "formats_metrics.rst", inspect_doc(run_module) + "\n")


def write_metrics_schema() -> None:
    """``metrics.schema.json``: the packaged JSON Schema of ``metrics.json``, for the download link of formats.md."""
    from mmg_casadi.scenarios.metrics_schema import SCHEMA_FILE, schema_text
    _write(GENERATED / SCHEMA_FILE, schema_text())


def write_scoring_profiles() -> None:
    """``colregs_profiles.md``: every threshold of the encounter scorer's profiles, its value in each profile and
    its meaning (:class:`mmg_casadi.colregs.profiles.ScoringProfile`); the sources are the profiles' docstrings."""
    import dataclasses
    import inspect

    from numpydoc.docscrape import NumpyDocString

    from mmg_casadi.colregs.profiles import SCORING_PROFILES, ScoringProfile, scoring_profile
    meaning = {}
    for p in NumpyDocString(inspect.getdoc(ScoringProfile))["Parameters"]:
        for name in p.name.split(","):
            meaning[name.strip()] = " ".join(p.desc)
    profiles = [scoring_profile(n) for n in SCORING_PROFILES]

    def fmt(v):
        return "—" if v is None else "∞" if v == float("inf") else f"{v:.4g}" if isinstance(v, float) else str(v)

    fields = [f.name for f in dataclasses.fields(ScoringProfile) if f.name != "name"]
    _check_keys("scoring profile fields", meaning, ["name", *fields])
    rows = ((f"`{f}`", *(fmt(getattr(p, f)) for p in profiles), meaning.get(f, "")) for f in fields)
    _write(GENERATED / "colregs_profiles.md", "\n".join(_table(("threshold", *(f"`{n}`" for n in SCORING_PROFILES),
                                                                  "meaning"), rows)))


RESULT_FIGURES = {"sweep_rsafe.png": ("results/issue12/sweep_rsafe/sweep.csv", "r_safe")}
"""Figures of committed full-size sweeps (table ``docs/``-relative, swept parameter), drawn again at build time."""


def write_result_figures() -> None:
    """Draw the committed full-size results of :data:`RESULT_FIGURES` with the current figure code (resolution,
    axis units) into ``_generated/results/``."""
    import csv

    from studies.sweep import plot_sweep

    def value(text: str):
        for kind in (int, float):
            try:
                return kind(text)
            except ValueError:
                pass
        return text

    for name, (table, param) in RESULT_FIGURES.items():
        out = GENERATED / "results" / name
        out.parent.mkdir(parents=True, exist_ok=True)
        with open(DOCS / table, newline="", encoding="utf-8") as f:
            rows = [{k: value(v) for k, v in r.items()} for r in csv.DictReader(f)]
        plot_sweep(rows, param, out)


def write_results() -> None:
    """Every table of the one results file (``docs/results/current.toml``) rendered as the README renders it, into
    ``_generated/results_<block>.md`` for the {include} directives of ``results.md``."""
    from studies.results import BLOCKS, load
    data = load()
    for name, render in BLOCKS.items():
        _write(GENERATED / f"results_{name}.md", render(data))


def inspect_doc(obj) -> str:
    import inspect
    return inspect.getdoc(obj) or ""


def _reexported(target: str) -> str | None:
    """``module.NAME[.rest]`` where ``module`` re-exports NAME from another module: the name where it is defined."""
    import importlib
    parts = target.split(".")
    for k in range(len(parts) - 1, 1, -1):
        try:
            mod = importlib.import_module(".".join(parts[:k]))
        except ImportError:
            continue
        obj = getattr(mod, parts[k], None)
        home = getattr(obj, "__module__", None)
        if obj is None or home is None or home == mod.__name__ or not home.startswith("mmg_casadi."):
            return None
        return ".".join([home, obj.__qualname__, *parts[k + 1:]])
    return None


def resolve_flat_name(app, env, node, contnode):
    """Let ``mmg_casadi.NAME`` of the flat API, and a name a module re-exports (``mmg_casadi.guidance.methods.Method``
    of :mod:`mmg_casadi.guidance.contract`), resolve to the object where NAME is defined."""
    target = node.get("reftarget", "")
    if node.get("refdomain") != "py" or not target.startswith("mmg_casadi."):
        return None
    flat = _flat_names().get(target.split(".", 1)[1])
    where = ".".join(flat) if flat is not None else _reexported(target)
    if where is None:
        return None
    node["reftarget"] = where
    domain = env.get_domain("py")
    return domain.resolve_xref(env, node["refdoc"], app.builder, node["reftype"], where, node, contnode)


def generate(app) -> None:
    GENERATED.mkdir(exist_ok=True)
    write_parameters()
    write_flat_api()
    write_claims()
    write_cli()
    write_formats()
    write_metrics_schema()
    write_scoring_profiles()
    write_result_figures()
    write_results()
    copy_notebooks()
    build_gallery(app.config.mmg_gallery_workers)


def setup(app):
    app.add_config_value("mmg_gallery_workers", 2, "env")
    app.connect("builder-inited", generate)
    app.connect("missing-reference", resolve_flat_name)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
