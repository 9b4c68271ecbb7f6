"""Standard encounter sets: situations of one own ship and one to three target ships, each target in a requested
COLREG encounter, sampled from a description file and checked with the encounter scorer.

The description (TOML) follows the idea of DNV's ship traffic generator (trafficgen,
github.com/dnv-opensource/ship-traffic-generator; Sandvik et al., "Generating structured set of encounters for
verifying automated collision and grounding avoidance systems", ICMASS 2023, the paper shipped as
``docs/source/ICMASS23_verfying_caga_systems.pdf`` of that repository): per target the desired encounter type and
ranges of its relative bearing, relative speed and the time until it meets the own ship. It is written in this
package's units (ship lengths L, design speed U, times L/U, angles in degrees from x/north towards y/east)::

    [set]
    situations = 110          # situations to write; situation i is of group i mod (number of groups)
    seed = 2023               # the whole set follows from it (situation i draws from the seed sequence [seed, i])
    max_attempts = 400        # draws per situation before the description is refused
    min_range = 20.0          # L, every target starts at least this far from the own ship
    target_separation = 4.0   # L, targets holding course pass each other at least this far apart
    profile = "iitm-lab"      # scorer profile of the classification check (colregs_profile)
    method = "modified-vortex"  # the own ship's method written into the files (targets: "none")
    t_max = 300.0             # horizon written into the files

    [own_ship]
    start = [0.0, 0.0]        # L
    course = 0.0              # degrees
    speed = 0.7               # fraction of the design speed
    leg = 100.0               # L, the own ship's goal lies this far ahead on her course

    [encounters.overtaking]   # optional: ranges replacing the defaults of one encounter type
    speed_ratio = [0.3, 0.5]

    [[groups]]                # situations with these targets (a type, or a table of a type and its ranges)
    name = "HO+CR-GW"
    targets = ["head-on", {type = "crossing-give-way", bearing = [30.0, 90.0]}]

Encounter types, named from the own ship's side: ``head-on`` (Rule 14), ``crossing-give-way`` (the target on the
own ship's starboard side, Rule 15), ``crossing-stand-on`` (the target on her port side, Rule 17),
``overtaking`` (the own ship overtakes, Rule 13) and ``overtaken`` (the target overtakes her; trafficgen's
"overtaking-stand-on"). Ranges of a target, each ``[low, high]``:

* ``bearing``: relative bearing of the target from the own ship's bow at the start (degrees, to starboard
  positive; an interval may pass 180°, e.g. ``[157.5, 202.5]``);
* ``relative_course``: target course minus own course (degrees, same convention);
* ``speed_ratio``: target speed / own speed (trafficgen's ``relativeSpeed``);
* ``tcpa``: time to the closest point of approach if both hold course (L/U);
* ``cpa``: distance at that point (L); 0 is a collision course; below the profile's ``d_risk`` (4 L for
  ``iitm-lab``), where the scorer sees a risk of collision.

Sampling (ours): bearing, speed ratio, TCPA and CPA (with a random passing side) are drawn uniformly; the target's
course then follows from the relative geometry (:func:`solve_target`: the start position on the bearing and the
relative velocity that give that TCPA and CPA), and a draw is rejected if no course gives the speed ratio, if the
course lies outside ``relative_course``, if the target starts closer than ``min_range`` or if two targets would
pass closer than ``target_separation``. A situation that passes these geometric checks is then **classified**: the
ships sail straight lines (every ship with method ``"none"``) and :func:`~mmg_casadi.colregs.scorer.score_encounters`
must find, for every target, exactly one encounter with a risk of collision from each side, beginning after the
start, with the own ship in the requested role and the target in the complementary one
(:data:`ROLES`); otherwise the situation is drawn again. The share that passes this check is reported.

Defaults of the ranges (:data:`DEFAULT_RANGES`) follow the COLREG sectors as the scorer reads them: head-on
within 10° of ahead and of reciprocal courses (COLREG Rule 14(a): "reciprocal or nearly reciprocal courses"; inside
both scorer profiles' head-on sectors, 22.5° ``iitm-lab`` and 13° ``ntnu-2023``); crossing targets from 22.5° off
the bow (outside the head-on sector) to 105° (short of Rule 13(b)'s 112.5°, 22.5° abaft the beam, where overtaking
begins); overtaking and overtaken targets within 22.5° of ahead or astern on courses within 30° of the own ship's.
Speed ratios follow trafficgen's ``encounter_settings.json`` (``relativeSpeed``: head-on and crossing 0.5–1.5,
overtaking give-way 0.25–0.75, stand-on 1.5–2), narrowed where a target would leave the speeds a scenario allows
(:data:`~mmg_casadi.scenarios.scenario.SPEED_RANGE`) at the default own speed 0.7.

Examples
--------
>>> d = description_from_dict({"set": {"situations": 2, "seed": 1}, "groups": [{"targets": ["head-on"]}]})
>>> s = generate(d)
>>> [x.id for x in s.situations], s.stats["accepted"]
(['s000_HO', 's001_HO'], 2)
"""

from __future__ import annotations

import dataclasses
import json
import math
import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np

from mmg_casadi.colregs.profiles import SCORING_PROFILES, scoring_profile
from mmg_casadi.colregs.scorer import score_encounters
from mmg_casadi.errors import InputError, ScenarioError
from mmg_casadi.readers import is_finite, load_json
from mmg_casadi.guidance import methods as registry
from mmg_casadi.io import read_toml, write_text
from mmg_casadi.params import check_value
from mmg_casadi.scenarios.maritime_export import dump_traffic_situation
from mmg_casadi.scenarios.scenario import SPEED_RANGE, Scenario, Settings, dump_scenario, scenario_from_dict

ENCOUNTER_TYPES = ("head-on", "crossing-give-way", "crossing-stand-on", "overtaking", "overtaken")
"""Encounter types a target may be asked for, named from the own ship's side."""
ROLES = {"head-on": ("head-on", "head-on"), "crossing-give-way": ("give-way", "stand-on"),
         "crossing-stand-on": ("stand-on", "give-way"), "overtaking": ("overtaking", "overtaken"),
         "overtaken": ("overtaken", "overtaking")}
"""Per encounter type, the scorer's role (:data:`~mmg_casadi.colregs.roles.ROLES`) of the own ship and of the target."""
SHORT = {"head-on": "HO", "crossing-give-way": "CR-GW", "crossing-stand-on": "CR-SO", "overtaking": "OT-GW",
         "overtaken": "OT-SO"}
"""Short names (trafficgen's titles) used to name a group without a ``name``."""
RANGE_KEYS = ("bearing", "relative_course", "speed_ratio", "tcpa", "cpa")
DEFAULT_RANGES = {
    "head-on": {"bearing": (-10.0, 10.0), "relative_course": (170.0, 190.0), "speed_ratio": (0.5, 1.5),
                "tcpa": (25.0, 40.0), "cpa": (0.0, 1.0)},
    "crossing-give-way": {"bearing": (22.5, 105.0), "relative_course": (-157.5, -22.5), "speed_ratio": (0.5, 1.5),
                          "tcpa": (30.0, 45.0), "cpa": (0.0, 1.0)},
    "crossing-stand-on": {"bearing": (-105.0, -22.5), "relative_course": (22.5, 157.5), "speed_ratio": (0.5, 1.5),
                          "tcpa": (30.0, 45.0), "cpa": (0.0, 1.0)},
    "overtaking": {"bearing": (-22.5, 22.5), "relative_course": (-30.0, 30.0), "speed_ratio": (0.3, 0.6),
                   "tcpa": (70.0, 100.0), "cpa": (0.0, 1.0)},
    "overtaken": {"bearing": (157.5, 202.5), "relative_course": (-30.0, 30.0), "speed_ratio": (1.4, 1.7),
                  "tcpa": (70.0, 100.0), "cpa": (0.0, 1.0)},
}
"""Default ranges of each encounter type (module docstring): degrees, speed ratio, L/U, L."""
SET_DEFAULTS = {"situations": 55, "seed": 0, "max_attempts": 400, "min_range": 20.0, "target_separation": 4.0,
                "profile": "iitm-lab", "method": registry.DEFAULT, "t_max": 300.0}
OWN_DEFAULTS = {"start": (0.0, 0.0), "course": 0.0, "speed": 0.7, "leg": 100.0}
MAX_SITUATIONS = 10_000
"""Largest number of situations of one set."""
MAX_TARGETS = 3
"""Largest number of targets of one situation."""
PASS_MARGIN = 15.0
"""L: the own ship reaches each closest point of approach at least this far before her goal (R_safe, ours)."""
CHECK_DT = 0.25
"""Sample step (L/U) of the straight-line trajectories of the classification check (the default guidance step)."""
DECIMALS = 6
"""Positions, headings and speeds are written rounded to this many decimals (and checked as written)."""


@dataclass(frozen=True)
class TargetSpec:
    """One requested target: its encounter type and the ranges it is drawn from (module docstring).

    Parameters
    ----------
    type : str
        One of :data:`ENCOUNTER_TYPES`.
    bearing, relative_course, speed_ratio, tcpa, cpa : tuple of float
        ``(low, high)`` ranges: degrees, degrees, target/own speed, L/U, L.
    """

    type: str
    bearing: tuple[float, float]
    relative_course: tuple[float, float]
    speed_ratio: tuple[float, float]
    tcpa: tuple[float, float]
    cpa: tuple[float, float]


@dataclass(frozen=True)
class Group:
    """Situations sharing one list of requested targets.

    Parameters
    ----------
    name : str
        Name used in the situation ids.
    targets : tuple of TargetSpec
        The targets, one to :data:`MAX_TARGETS`.
    """

    name: str
    targets: tuple[TargetSpec, ...]


@dataclass(frozen=True)
class Description:
    """A validated description of an encounter set (module docstring); build it with :func:`description_from_dict`.

    Parameters
    ----------
    situations, seed, max_attempts : int
        Situations to write, seed of the set, draws per situation.
    min_range, target_separation : float
        Smallest start range of a target and smallest straight-line passing distance of two targets (L).
    profile, method : str
        Scorer profile of the check; the own ship's method written into the files.
    t_max : float
        Horizon written into the files (L/U).
    own_start : tuple of float
        Own ship's start (L).
    own_course, own_speed, own_leg : float
        Own ship's course (degrees), speed (fraction of the design speed) and route length (L).
    groups : tuple of Group
        The groups; situation ``i`` belongs to group ``i mod len(groups)``.
    source : str
        Where the description came from (a file name, ``"standard"``).
    """

    situations: int
    seed: int
    max_attempts: int
    min_range: float
    target_separation: float
    profile: str
    method: str
    t_max: float
    own_start: tuple[float, float]
    own_course: float
    own_speed: float
    own_leg: float
    groups: tuple[Group, ...]
    source: str = "<dict>"

    def to_dict(self) -> dict:
        """The description with every default filled in, shaped like the file (JSON-ready).

        Returns
        -------
        dict
            Tables ``set``, ``own_ship`` and ``groups`` (per target its ``type`` and ranges as ``[low, high]`` lists).
        """
        return {"set": {k: getattr(self, k) for k in SET_DEFAULTS},
                "own_ship": {"start": list(self.own_start), "course": self.own_course, "speed": self.own_speed,
                             "leg": self.own_leg},
                "groups": [{"name": g.name, "targets": [{"type": t.type, **{k: list(getattr(t, k))
                                                                            for k in RANGE_KEYS}}
                                                        for t in g.targets]} for g in self.groups]}


@dataclass(frozen=True)
class Situation:
    """One generated situation.

    Parameters
    ----------
    id : str
        ``s<index>_<group name>``, the file stem.
    group : str
        Name of its group.
    scenario : Scenario
        The scenario (own ship first, then ``target1``, ...).
    attempts : int
        Draws it took (the last one accepted).
    targets : tuple of dict
        Per target: ``name``, ``type``, the drawn ``bearing``, ``relative_course``, ``speed_ratio``, ``tcpa``,
        ``cpa`` (signed: positive when the target passes to starboard of the own ship's relative track) and
        ``start_range``.
    """

    id: str
    group: str
    scenario: Scenario
    attempts: int
    targets: tuple = ()


@dataclass(frozen=True)
class EncounterSet:
    """A generated set: the description, the situations and the draw statistics.

    Parameters
    ----------
    description : Description
        What was generated.
    situations : tuple of Situation
        In order.
    stats : dict
        ``attempts`` (draws), ``checked`` (draws that passed the geometric checks and were classified),
        ``accepted`` (= situations), ``acceptance_share`` (``accepted / checked``), and the same per group
        (``groups``).
    """

    description: Description
    situations: tuple
    stats: dict = field(default_factory=dict)


def _number(value, key: str, allowed: str) -> float:
    if not is_finite(value):
        raise InputError(key, allowed, value)
    return float(value)


def _integer(value, key: str, low: int, high: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise InputError(key, f"an integer in [{low}, {high}]", value)
    return int(value)


def _table(value, key: str, allowed) -> dict:
    if not isinstance(value, dict):
        raise InputError(key or "description", "a table", value)
    for k in value:
        if k not in allowed:
            raise InputError(f"{key}.{k}" if key else k, f"a known key (one of: {', '.join(allowed)})")
    return value


def _interval(value, key: str, name: str) -> tuple[float, float]:
    """A checked ``[low, high]`` range of quantity ``name``."""
    kinds = {"bearing": ("degrees, high - low at most 360", None, None),
             "relative_course": ("degrees, high - low at most 360", None, None),
             "speed_ratio": ("target speed / own speed, 0 < low", 0.0, None),
             "tcpa": ("L/U, 0 < low", 0.0, None), "cpa": ("L, 0 <= low", 0.0, None)}
    unit, low_bound, _ = kinds[name]
    allowed = f"a range [low, high] of two numbers with low <= high ({unit})"
    if not isinstance(value, list) or len(value) != 2:
        raise InputError(key, allowed, value)
    lo, hi = (_number(v, key, allowed) for v in value)
    if lo > hi or (name in ("bearing", "relative_course") and hi - lo > 360.0):
        raise InputError(key, allowed, value)
    if low_bound is not None and (lo < 0.0 or (name != "cpa" and lo <= 0.0)):
        raise InputError(key, allowed, value)
    return (lo, hi)


def _ranges(table: dict, key: str, base: dict) -> dict:
    """``base`` with the ranges of ``table`` (keys of :data:`RANGE_KEYS`) replaced, checked."""
    out = dict(base)
    for k in RANGE_KEYS:
        if k in table:
            out[k] = _interval(table[k], f"{key}.{k}", k)
    return out


def _type(value, key: str) -> str:
    if not isinstance(value, str) or value not in ENCOUNTER_TYPES:
        raise InputError(key, f"one of: {', '.join(ENCOUNTER_TYPES)}", value)
    return value


def description_from_dict(d: dict, source: str = "<dict>") -> Description:
    """A validated :class:`Description` from a dict shaped like a description file (module docstring).

    Parameters
    ----------
    d : dict
        The description (tables ``set``, ``own_ship``, ``encounters``, ``groups``; only ``groups`` is required).
    source : str, optional
        Where it came from, kept in the result.

    Returns
    -------
    Description
        The validated description, defaults filled in.

    Raises
    ------
    InputError
        A malformed entry, named by its dotted key (``groups[1].targets[0].bearing``) with the allowed values.

    Examples
    --------
    >>> description_from_dict({"groups": [{"targets": ["overtaken"]}]}).groups[0].targets[0].speed_ratio
    (1.4, 1.7)
    >>> description_from_dict({"groups": [{"targets": ["crossing"]}]})
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.InputError: groups[0].targets[0]: expected one of: head-on, crossing-give-way, crossing-stand-on, overtaking, overtaken, got 'crossing'
    """
    top = _table(d, "", ("set", "own_ship", "encounters", "groups"))
    st = {**SET_DEFAULTS, **_table(top.get("set", {}), "set", tuple(SET_DEFAULTS))}
    situations = _integer(st["situations"], "set.situations", 1, MAX_SITUATIONS)
    seed = _integer(st["seed"], "set.seed", 0, 2 ** 63 - 1)
    attempts = _integer(st["max_attempts"], "set.max_attempts", 1, 100_000)
    min_range = _number(st["min_range"], "set.min_range", "a number of ship lengths > 0")
    separation = _number(st["target_separation"], "set.target_separation", "a number of ship lengths >= 0")
    if min_range <= 0.0:
        raise InputError("set.min_range", "a number of ship lengths > 0", min_range)
    if separation < 0.0:
        raise InputError("set.target_separation", "a number of ship lengths >= 0", separation)
    if not isinstance(st["profile"], str) or st["profile"] not in SCORING_PROFILES:
        raise InputError("set.profile", f"one of: {', '.join(SCORING_PROFILES)}", st["profile"])
    method = registry.get(st["method"], "set.method").name
    t_max = check_value("t_max", st["t_max"], field="set.t_max", cls=InputError)
    own = {**OWN_DEFAULTS, **_table(top.get("own_ship", {}), "own_ship", tuple(OWN_DEFAULTS))}
    start = own["start"]
    if not isinstance(start, (list, tuple)) or len(start) != 2:
        raise InputError("own_ship.start", "a point [x, y] of two finite numbers (ship lengths)", start)
    start = tuple(_number(v, "own_ship.start", "a point [x, y] of two finite numbers (ship lengths)") for v in start)
    course = _number(own["course"], "own_ship.course", "a finite number of degrees")
    lo, hi = SPEED_RANGE
    speed = _number(own["speed"], "own_ship.speed", f"a number in [{lo:g}, {hi:g}] (fraction of design speed)")
    if not lo <= speed <= hi:
        raise InputError("own_ship.speed", f"a number in [{lo:g}, {hi:g}] (fraction of design speed)", speed)
    leg = _number(own["leg"], "own_ship.leg", "a number of ship lengths > 0")
    if leg <= 0.0:
        raise InputError("own_ship.leg", "a number of ship lengths > 0", leg)
    if leg / speed > t_max:
        raise InputError("set.t_max", f"a horizon of at least the own ship's voyage time leg / speed = "
                         f"{leg / speed:g} L/U", t_max)
    enc = _table(top.get("encounters", {}), "encounters", ENCOUNTER_TYPES)
    defaults = {t: _ranges(_table(enc.get(t, {}), f"encounters.{t}", RANGE_KEYS), f"encounters.{t}",
                           DEFAULT_RANGES[t]) for t in ENCOUNTER_TYPES}
    if "groups" not in top:
        raise InputError("groups", "at least one [[groups]] table (required)")
    if not isinstance(top["groups"], list) or not top["groups"]:
        raise InputError("groups", "an array of at least one [[groups]] table", top["groups"])
    profile = scoring_profile(st["profile"])
    groups = []
    for i, g in enumerate(top["groups"]):
        g = _table(g, f"groups[{i}]", ("name", "targets"))
        key = f"groups[{i}].targets"
        if not isinstance(g.get("targets"), list) or not 1 <= len(g["targets"]) <= MAX_TARGETS:
            raise InputError(key, f"a list of 1 to {MAX_TARGETS} targets (an encounter type or a table with "
                             "'type' and ranges)", g.get("targets"))
        targets = []
        for j, t in enumerate(g["targets"]):
            tk = f"{key}[{j}]"
            if isinstance(t, dict):
                t = _table(t, tk, ("type",) + RANGE_KEYS)
                kind = _type(t.get("type"), f"{tk}.type")
                ranges = _ranges(t, tk, defaults[kind])
            else:
                kind = _type(t, tk)
                ranges = defaults[kind]
            spec = TargetSpec(kind, **ranges)
            _check_target(spec, tk, speed, leg, profile)
            targets.append(spec)
        name = g.get("name", "+".join(SHORT[t.type] for t in targets))
        if not isinstance(name, str) or not name or not all(c.isascii() and (c.isalnum() or c in "_-+")
                                                            for c in name):
            raise InputError(f"groups[{i}].name", "a non-empty name of ASCII letters, digits, '_', '-', '+'", name)
        groups.append(Group(name, tuple(targets)))
    return Description(situations, seed, attempts, min_range, separation, st["profile"], method, t_max, start,
                       course, speed, leg, tuple(groups), source)


def _check_target(t: TargetSpec, key: str, own_speed: float, leg: float, profile) -> None:
    """Ranges a situation can be drawn from: target speeds allowed, CPA with a risk, CPA before the goal."""
    lo, hi = SPEED_RANGE
    if t.speed_ratio[0] * own_speed < lo - 1e-9 or t.speed_ratio[1] * own_speed > hi + 1e-9:
        raise InputError(f"{key}.speed_ratio", f"a range within [{lo / own_speed:.4g}, {hi / own_speed:.4g}] (target "
                         f"speeds in [{lo:g}, {hi:g}] U at own ship speed {own_speed:g})", list(t.speed_ratio))
    if t.cpa[1] >= profile.d_risk:
        raise InputError(f"{key}.cpa", f"a range below the profile's d_risk = {profile.d_risk:g} L (no risk of "
                         "collision, hence no encounter, otherwise)", list(t.cpa))
    if own_speed * t.tcpa[1] + PASS_MARGIN > leg:
        raise InputError(f"{key}.tcpa", f"a range up to (own_ship.leg - {PASS_MARGIN:g} L) / own_ship.speed = "
                         f"{(leg - PASS_MARGIN) / own_speed:.4g} L/U (the own ship meets the target before her goal)",
                         list(t.tcpa))


def load_description(path) -> Description:
    """Read and validate a description file (TOML, module docstring).

    Parameters
    ----------
    path : str or Path
        The file.

    Returns
    -------
    Description
        The validated description, defaults filled in.

    Raises
    ------
    InputError
        A missing or unreadable file (its field is the path), invalid TOML (field ``toml``) or a malformed entry.
    """
    return description_from_dict(read_toml(path, "description"), source=str(path))


STANDARD = "standard_encounters.toml"
"""File name of the shipped description in ``mmg_casadi/data/``."""


def standard_description() -> Description:
    """The shipped description ``mmg_casadi/data/standard_encounters.toml``: single-target head-on, crossing
    give-way and stand-on, overtaking and overtaken situations and two- and three-target combinations, the kind of
    set of Sandvik et al. (ICMASS 2023).

    Returns
    -------
    Description
        The shipped description (source ``"standard"``).

    Examples
    --------
    >>> d = standard_description()
    >>> d.situations, len(d.groups), sorted({len(g.targets) for g in d.groups})
    (110, 22, [1, 2, 3])
    """
    text = resources.files("mmg_casadi").joinpath("data", STANDARD).read_text(encoding="utf-8")
    return description_from_dict(tomllib.loads(text), source="standard")


def _unit(deg: float) -> np.ndarray:
    a = math.radians(deg)
    return np.array([math.cos(a), math.sin(a)])


def _wrap(deg: float) -> float:
    """``deg`` in [-180, 180)."""
    return (deg + 180.0) % 360.0 - 180.0


def _within(deg: float, interval: tuple[float, float]) -> bool:
    """Whether angle ``deg`` lies in ``interval`` read modulo 360."""
    lo, hi = interval
    return (deg - lo) % 360.0 <= hi - lo + 1e-9


def solve_target(own_course: float, own_speed: float, bearing: float, speed_ratio: float, tcpa: float,
                 cpa: float) -> list[tuple[float, float]]:
    """Target courses and start ranges that put a target on ``bearing`` meeting the own ship as asked.

    With the own velocity ``v_o``, the target's start ``r0 = rho e(bearing)`` relative to the own ship and the
    relative velocity ``w u`` (``|u| = 1``), holding course gives TCPA ``tcpa`` and CPA ``|cpa|`` exactly when
    ``r0 = (-tcpa w + i cpa) u`` (complex numbers, ``i`` a quarter turn to starboard). For each ``w`` this fixes
    ``u``; the target speed ``|v_o + w u| = speed_ratio |v_o|`` leaves one equation in ``w`` in
    ``(0, (1 + speed_ratio) |v_o|]``, solved by a scan and :func:`scipy.optimize.brentq`.

    Parameters
    ----------
    own_course, own_speed : float
        Own course (degrees) and speed (U).
    bearing : float
        Relative bearing of the target from the own bow (degrees).
    speed_ratio : float
        Target speed / own speed.
    tcpa : float
        Time to the closest point of approach (L/U), > 0.
    cpa : float
        Signed distance at it (L): positive, the target passes on the starboard side of the relative track.

    Returns
    -------
    list of (float, float)
        ``(course, range)`` pairs: target course (degrees in [-180, 180)) and start range (L); empty, one or two.

    Examples
    --------
    A head-on target at the same speed on a collision course 30 L/U away starts 60 L ahead, heading back:

    >>> [(round(c, 6), round(r, 6)) for c, r in solve_target(0.0, 1.0, 0.0, 1.0, 30.0, 0.0)]
    [(-180.0, 60.0)]
    """
    vo = complex(*(own_speed * _unit(own_course)))
    eb = complex(*_unit(own_course + bearing))
    target = speed_ratio * own_speed

    def velocity(w):
        u = eb / (-tcpa * w + 1j * cpa)
        return vo + w * u / np.abs(u)

    def g(w):
        return float(abs(velocity(w)) - target)

    top = (1.0 + speed_ratio) * own_speed * (1.0 + 1e-9)
    grid = np.linspace(top * 1e-6, top, 801)
    values = np.abs(velocity(grid)) - target
    from scipy.optimize import brentq  # about 0.5 s to import: only when a situation is solved
    out = []
    for k in np.flatnonzero(np.sign(values[:-1]) * np.sign(values[1:]) <= 0):
        if values[k] == 0.0 and k > 0:  # found as the end of the previous interval
            continue
        w = grid[k] if values[k] == 0.0 else brentq(g, grid[k], grid[k + 1], xtol=1e-13, rtol=1e-13)
        v = velocity(w)
        out.append((_wrap(math.degrees(math.atan2(v.imag, v.real))), float(abs(complex(-tcpa * w, cpa)))))
    return out


def _draw_target(rng, spec: TargetSpec, d: Description):
    """One draw of a target: ``(values, course, start range)`` or None if the geometry rejects it."""
    bearing = float(rng.uniform(*spec.bearing))
    ratio = float(rng.uniform(*spec.speed_ratio))
    tcpa = float(rng.uniform(*spec.tcpa))
    cpa = float(rng.uniform(*spec.cpa)) * (1.0 if rng.random() < 0.5 else -1.0)
    pick = float(rng.random())
    options = [(c, r) for c, r in solve_target(d.own_course, d.own_speed, bearing, ratio, tcpa, cpa)
               if _within(c - d.own_course, spec.relative_course) and r >= d.min_range]
    if not options:
        return None
    course, rng_start = options[min(int(pick * len(options)), len(options) - 1)]
    values = {"type": spec.type, "bearing": _wrap(bearing), "relative_course": _wrap(course - d.own_course),
              "speed_ratio": ratio, "tcpa": tcpa, "cpa": cpa, "start_range": rng_start}
    return values, course, rng_start


def _round(x: float) -> float:
    return round(float(x), DECIMALS) + 0.0


def _scenario(d: Description, drawn: list) -> Scenario | None:
    """The scenario of one draw, every number rounded as written; None if two ships start closer than the
    collision distance."""
    voyage = d.own_leg / d.own_speed
    own_start = np.asarray(d.own_start)
    goal = own_start + d.own_leg * _unit(d.own_course)
    ships = [{"name": "own", "start": [_round(v) for v in own_start], "heading": _round(_wrap(d.own_course)),
              "speed": _round(d.own_speed), "waypoints": [[_round(v) for v in goal]]}]
    for j, (values, course, rho) in enumerate(drawn):
        start = own_start + rho * _unit(d.own_course + values["bearing"])
        speed = values["speed_ratio"] * d.own_speed
        end = start + speed * voyage * _unit(course)
        ships.append({"name": f"target{j + 1}", "start": [_round(v) for v in start], "heading": _round(course),
                      "speed": _round(speed), "waypoints": [[_round(v) for v in end]], "method": "none"})
    starts = [s["start"] for s in ships]
    if any(math.dist(a, b) < Settings.collision_distance for k, a in enumerate(starts) for b in starts[:k]):
        return None
    return scenario_from_dict({"settings": {"method": d.method, "t_max": d.t_max}, "ships": ships})


def straight_lines(sc: Scenario, t_end: float, dt: float = CHECK_DT):
    """Every ship of ``sc`` on a straight line at her start heading and speed: ``t``, positions, headings, speeds.

    Parameters
    ----------
    sc : Scenario
        The scenario.
    t_end : float
        Last sample time (L/U).
    dt : float, optional
        Sample step (L/U).

    Returns
    -------
    tuple of numpy.ndarray
        ``t`` (T,), ``pos`` (T, N, 2), ``psi`` (T, N) in rad and ``speed`` (T, N), as
        :func:`~mmg_casadi.colregs.scorer.score_encounters` takes them.
    """
    t = np.arange(0.0, t_end + 0.5 * dt, dt)
    start = np.array([s.start for s in sc.ships])
    vel = np.array([s.speed * _unit(s.heading_deg) for s in sc.ships])
    pos = start[None, :, :] + t[:, None, None] * vel[None, :, :]
    psi = np.broadcast_to(np.radians([s.heading_deg for s in sc.ships]), (t.size, len(sc.ships)))
    speed = np.broadcast_to([s.speed for s in sc.ships], (t.size, len(sc.ships)))
    return t, pos, psi, speed


def _separated(sc: Scenario, t_end: float, limit: float) -> bool:
    """Whether every two targets holding course stay at least ``limit`` apart up to ``t_end``."""
    ships = sc.ships[1:]
    for a in range(len(ships)):
        for b in range(a + 1, len(ships)):
            p = np.subtract(ships[a].start, ships[b].start)
            v = ships[a].speed * _unit(ships[a].heading_deg) - ships[b].speed * _unit(ships[b].heading_deg)
            vv = float(v @ v)
            tc = 0.0 if vv == 0.0 else min(max(-float(p @ v) / vv, 0.0), t_end)
            if float(np.hypot(*(p + tc * v))) < limit:
                return False
    return True


def classified(sc: Scenario, types, profile="iitm-lab", t_end: float | None = None) -> bool:
    """Whether every target of ``sc`` meets the own ship in the requested encounter from both sides.

    The ships sail straight lines (:func:`straight_lines`); for target ``j`` the scorer must find exactly one
    encounter with a risk of collision of the pair (own, target ``j``) and one of (target ``j``, own), both
    beginning after the start, with the roles :data:`ROLES` ``[types[j - 1]]``.

    Parameters
    ----------
    sc : Scenario
        The scenario, own ship first.
    types : sequence of str
        The requested encounter type of each target (:data:`ENCOUNTER_TYPES`).
    profile : str or ScoringProfile, optional
        The scorer's profile.
    t_end : float, optional
        End of the check (L/U); default: the own ship's voyage time to her goal.

    Returns
    -------
    bool
        True if every target meets the own ship in its requested encounter, with the expected roles.

    Examples
    --------
    >>> from mmg_casadi.scenarios.scenario import Settings, ShipSpec
    >>> sc = Scenario(Settings("none"), [ShipSpec("own", [0, 0], 0, 1, [[80, 0]]),
    ...                                  ShipSpec("t", [60, 0], 180, 1, [[-20, 0]])])
    >>> classified(sc, ["head-on"]), classified(sc, ["crossing-give-way"])
    (True, False)
    """
    own = sc.ships[0]
    if t_end is None:
        t_end = math.dist(own.start, own.goal) / own.speed
    t, pos, psi, speed = straight_lines(sc, t_end)
    found = {}
    for e in score_encounters(t, pos, psi, speed, profile=profile):
        if e.applicable and (e.own == 0 or e.other == 0):
            found.setdefault((e.own, e.other), []).append(e)
    for j, kind in enumerate(types, start=1):
        for pair, role in zip(((0, j), (j, 0)), ROLES[kind]):
            got = found.get(pair, [])
            if len(got) != 1 or got[0].role != role or got[0].onset["t"] <= 0.0:
                return False
    return True


def generate(d: Description) -> EncounterSet:
    """Draw every situation of ``d`` (module docstring); deterministic for ``d.seed``.

    Parameters
    ----------
    d : Description
        The description.

    Returns
    -------
    EncounterSet
        The description, the ``d.situations`` accepted situations in order and the draw statistics.

    Raises
    ------
    InputError
        A group that yields no accepted situation within ``d.max_attempts`` draws (``groups[i]``).
    """
    voyage = d.own_leg / d.own_speed
    situations = []
    per_group = [{"name": g.name, "situations": 0, "target_draws": 0, "attempts": 0, "checked": 0, "accepted": 0}
                 for g in d.groups]
    for i in range(d.situations):
        gi = i % len(d.groups)
        group = d.groups[gi]
        rng = np.random.default_rng([d.seed, i])
        stats = per_group[gi]
        for attempt in range(1, d.max_attempts + 1):
            stats["attempts"] += 1
            drawn = [_target(rng, spec, d, f"groups[{gi}].targets[{j}]", stats) for j, spec in enumerate(group.targets)]
            sc = _scenario(d, drawn)
            if sc is None or not _separated(sc, voyage, d.target_separation):
                continue
            stats["checked"] += 1
            if classified(sc, [t.type for t in group.targets], d.profile, voyage):
                stats["accepted"] += 1
                stats["situations"] += 1
                targets = tuple({"name": f"target{j + 1}", **values} for j, (values, _, _) in enumerate(drawn))
                situations.append(Situation(f"s{i:03d}_{group.name}", group.name, sc, attempt, targets))
                break
        else:
            raise InputError(f"groups[{gi}]", f"targets that pass each other and meet the own ship in the requested "
                             f"encounters within set.max_attempts = {d.max_attempts} draws (situation {i} found "
                             "none; widen the ranges or raise max_attempts)", group.name)
    total = {k: sum(g[k] for g in per_group) for k in ("target_draws", "attempts", "checked", "accepted")}
    share = total["accepted"] / total["checked"] if total["checked"] else float("nan")
    return EncounterSet(d, tuple(situations), {**total, "acceptance_share": share, "groups": per_group})


def _target(rng, spec: TargetSpec, d: Description, key: str, stats: dict):
    """A target drawn until its own geometry is accepted (:func:`_draw_target`), at most ``d.max_attempts`` times."""
    for _ in range(d.max_attempts):
        stats["target_draws"] += 1
        drawn = _draw_target(rng, spec, d)
        if drawn is not None:
            return drawn
    raise InputError(key, f"ranges with a target course in relative_course and a start at least set.min_range = "
                     f"{d.min_range:g} L away within set.max_attempts = {d.max_attempts} draws", spec.type)


def _header(s: Situation, d: Description) -> str:
    what = ", ".join(f"{t['name']} {t['type']}" for t in s.targets)
    return f"# {s.id}: {what}; generated by mmg-casadi generate from {d.source}, seed {d.seed}.\n"


def set_files(es: EncounterSet) -> dict[str, str]:
    """The files of a set as ``{relative path: text}``: ``<id>.toml`` (scenario files with a header comment),
    ``maritime/<id>.json`` (maritime-schema traffic situations) and ``generation.json`` (the description with its
    defaults filled in, the draw statistics and every situation's drawn values).

    Parameters
    ----------
    es : EncounterSet
        The generated set.

    Returns
    -------
    dict
        Relative path → text, in writing order.
    """
    files = {}
    for s in es.situations:
        files[f"{s.id}.toml"] = _header(s, es.description) + dump_scenario(s.scenario)
        try:
            files[f"maritime/{s.id}.json"] = dump_traffic_situation(s.scenario, title=s.id)
        except ScenarioError as err:
            raise InputError("own_ship.leg", f"routes that keep every ship within reach of the maritime-schema "
                             f"file's reference ({s.id}: {err})") from None
    record = {"source": es.description.source, "description": es.description.to_dict(), "stats": es.stats,
              "situations": [{"id": s.id, "group": s.group, "attempts": s.attempts, "targets": list(s.targets)}
                             for s in es.situations]}
    files["generation.json"] = json.dumps(record, indent=2) + "\n"
    return files


def write_set(es: EncounterSet, out) -> Path:
    """Write :func:`set_files` into directory ``out`` (created); every file is built before the first is written.

    Parameters
    ----------
    es : EncounterSet
        The generated set.
    out : str or Path
        Output directory.

    Returns
    -------
    Path
        ``out``.
    """
    out = Path(out)
    files = set_files(es)
    for rel, text in files.items():
        write_text(out / rel, text)
    return out


def requested_types(set_dir) -> dict[str, list[str]]:
    """Per situation id, the requested encounter type of each target, from a set's ``generation.json`` ({} if the
    directory has none).

    Parameters
    ----------
    set_dir : str or Path
        A directory written by :func:`write_set`.

    Returns
    -------
    dict
        Situation id → list of encounter types, target by target.
    """
    path = Path(set_dir) / "generation.json"
    if not path.is_file():
        return {}
    record = load_json(path, "generation record")  # size, UTF-8, nesting checked while reading
    try:
        return {s["id"]: [t["type"] for t in s["targets"]] for s in record["situations"]}
    except (KeyError, TypeError) as err:
        raise InputError(str(path), "the generation.json written by `mmg-casadi generate`", str(err)) from None



def override(d: Description, *, situations: int | None = None, seed: int | None = None) -> Description:
    """``d`` with another number of situations or seed (checked as in the file).

    Parameters
    ----------
    d : Description
        The description.
    situations : int, optional
        New ``set.situations``, in [1, :data:`MAX_SITUATIONS`].
    seed : int, optional
        New ``set.seed``, >= 0.

    Returns
    -------
    Description
        A new description; ``d`` is not changed.

    Examples
    --------
    >>> override(standard_description(), situations=3).situations
    3
    """
    kw = {}
    if situations is not None:
        kw["situations"] = _integer(situations, "situations", 1, MAX_SITUATIONS)
    if seed is not None:
        kw["seed"] = _integer(seed, "seed", 0, 2 ** 63 - 1)
    return dataclasses.replace(d, **kw)
