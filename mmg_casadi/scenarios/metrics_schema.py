"""JSON Schema of the ``metrics.json`` of a scenario run (:mod:`mmg_casadi.scenarios.run`).

:func:`metrics_schema` builds the schema (JSON Schema draft 2020-12) from the code's own tuples: the methods, the
ship statuses, the parameters and their types, the COLREG rules, roles, encounter types and scoring profiles. The
package ships it as ``mmg_casadi/data/metrics.schema.json`` (:func:`load_metrics_schema`; the tests check that the
file equals :func:`metrics_schema` and validate real outputs against it). After a change of the format or of one of
those tuples, rewrite the file with::

    python -m mmg_casadi.scenarios.metrics_schema

Every object of the format lists its keys as required and allows no other key, except the open-ended term
dictionaries: the terms behind a rule's verdict and the quantities of the legacy scorer (scalars, ``null`` or
lists of them).
Non-finite numbers are written as ``null`` (:func:`mmg_casadi.io.json_safe`), so every number may be ``null``
where the code can produce an infinity or NaN.
"""

from __future__ import annotations

import json
import sys
from importlib import resources

from mmg_casadi.io import write_text

SCHEMA_ID = "https://mmg-casadi.invalid/schemas/metrics.schema.json"
"""``$id`` of the schema (a name, not a download address: the schema ships in the package and with the docs)."""

SCHEMA_FILE = "metrics.schema.json"
"""File name of the packaged schema in ``mmg_casadi/data/``."""

ENCOUNTER_QUANTITIES = ("t_baseline", "t_baseline_other", "beta_deg", "alpha_deg", "beta_onset_deg",
                        "alpha_onset_deg", "speed", "speed_other", "t_late", "t_apparent", "t_must",
                        "speed_max_before", "own_clearance")
"""Numeric keys of an applicable encounter's ``quantities`` (:class:`~mmg_casadi.colregs.scorer.Encounter`), besides
the flag ``head_on_in_doubt``; a non-applicable one has ``min_range`` alone."""

_NUM = {"type": ["number", "null"]}
_POINT = {"oneOf": [{"type": "null"}, {"type": "array", "items": {"type": "number"}, "minItems": 2, "maxItems": 2}]}
_SCALAR = {"type": ["number", "string", "boolean", "null"]}
_TERM = {"anyOf": [_SCALAR, {"type": "array", "items": _SCALAR}]}


def _obj(properties: dict, *, extra=False, description: str | None = None) -> dict:
    """An object with exactly ``properties`` (all required); ``extra``: the schema of further keys, or False."""
    out = {"type": "object", "properties": properties, "required": list(properties),
           "additionalProperties": extra}
    if description:
        out = {"description": description, **out}
    return out


def _with_optional(obj: dict, properties: dict) -> dict:
    """``obj`` (an :func:`_obj`) that also allows ``properties`` without requiring them."""
    return {**obj, "properties": {**obj["properties"], **properties}}


def _enum(values, *, null=False) -> dict:
    return {"enum": [*values, None] if null else list(values)}


def _param_schema(p) -> dict:
    if p.kind == "choice":
        return {"enum": list(p.choices)}
    if p.kind == "text":
        return {"type": "string"}
    return {"type": {"float": "number", "int": "integer", "bool": "boolean"}[p.kind]}


def metrics_schema() -> dict:
    """The JSON Schema of a scenario run's ``metrics.json``, from the code's tuples (module docstring).

    Returns
    -------
    dict
        The schema, JSON-ready.

    Examples
    --------
    >>> s = metrics_schema()
    >>> s["required"]
    ['method', 'collision', 't_end', 'params', 'ships', 'pairs', 'route_warnings']
    >>> s["$defs"]["ship"]["properties"]["status"]["enum"]
    ['reached', 'diverged', 'stalled', 'timeout', 'grounded', 'collided']
    """
    from mmg_casadi.closed_loop.outcome import OUTCOMES
    from mmg_casadi.colregs.classify import ENCOUNTERS
    from mmg_casadi.colregs.profiles import SCORING_PROFILES
    from mmg_casadi.colregs.roles import ENCOUNTER_OF_ROLE, ROLES
    from mmg_casadi.colregs.score import RULES as LEGACY_RULES
    from mmg_casadi.colregs.verdict import RULES
    from mmg_casadi.guidance.hazards import KINDS
    from mmg_casadi.closed_loop.replay import REPLAY
    from mmg_casadi.guidance.methods import METHODS, ON_DEMAND, on_demand_method
    from mmg_casadi.params import PARAMETERS

    # the on-demand methods (registered the first time a run names them) and their parameters are optional: a run
    # that uses one records them, the others do not (mmg_casadi.guidance.methods.ON_DEMAND)
    on_demand = {name: on_demand_method(name) for name in ON_DEMAND}
    optional = {p.name: p for m in on_demand.values() for p in m.params}
    method_names = list(dict.fromkeys([*(n for n in METHODS if n not in on_demand), *on_demand]))

    ship = _obj({
        "name": {"type": "string"},
        "method": _enum([*method_names, REPLAY]),
        "status": _enum(OUTCOMES),
        "reached_goal": {"type": "boolean"},
        "time_to_goal": _NUM,
        "ce": _NUM,
        "mcte": _NUM,
        "collided": {"type": "boolean"},
        "collision_time": _NUM,
        "collision_with": {"type": ["string", "null"]},
        "collision_kind": _enum(["ship", *KINDS], null=True),
        "collision_position": _POINT,
        "min_distance": _NUM,
        "stalled_at": _POINT,
        "reactive_time": {"type": "number"},
        "rule9": {"oneOf": [{"type": "null"}, _obj({
            "verdict": {"type": "boolean"}, "score": {"type": "number", "minimum": 0, "maximum": 1},
            "channel_time": {"type": "number"}, "starboard_time": {"type": "number"},
            "share": {"type": "number", "minimum": 0, "maximum": 1}, "mean_offset": {"type": "number"},
            "min_width": {"type": "number"}},
            description="COLREG Rule 9(a) in a narrow channel (mmg_casadi.colregs.narrow_channel.rule9)")]},
        "route": _obj({"planned": {"type": "boolean"}, "waypoints": {"type": "array", "minItems": 1, "items": _POINT}},
                      description="The route sailed: the waypoints, planned around the land or as given "
                                  "(mmg_casadi.scenarios.routes)"),
        "min_speed": _NUM,
        "reduced_speed_time": {"type": "number"},
        "delay": _NUM,
    }, description="One ship's outcome (the closed loop's judgement) and its speed metrics.")
    route_warning = _obj({
        "ship": {"type": "string"}, "index": {"type": "integer", "minimum": 0},
        "leg": {"type": "integer", "minimum": 0}, "from": _POINT, "to": _POINT,
        "land": {"type": "string", "pattern": "^land[0-9]+$"}, "crosses": {"type": "boolean"},
        "distance": {"type": "number", "minimum": 0}, "clearance": {"type": "number", "minimum": 0},
        "where": _POINT,
    }, description="A route leg across land or within the grounding clearance of it "
                   "(mmg_casadi.scenarios.routes.check_routes).")
    ship["properties"]["tallies"] = {
        "description": "Counts over the run of a method with tallies (Method.tallies, e.g. nmpc's solves and "
                       "fallbacks); only for a ship whose method has them.",
        "type": "object", "additionalProperties": {"type": "number"}}

    moment = _obj({"t": _NUM, "range": _NUM})
    rule = _obj({"verdict": {"type": "boolean"}, "score": {"type": "number", "minimum": 0, "maximum": 1}},
                extra=_TERM)
    encounter_types = sorted(set(ENCOUNTER_OF_ROLE.values()))
    encounter = _obj({
        "own": {"type": "string"},
        "other": {"type": "string"},
        "profile": _enum(SCORING_PROFILES),
        "applicable": {"type": "boolean"},
        "unfinished": {"type": "boolean"},
        "excuse_changed": {"type": "boolean"},
        "encounter": _enum(encounter_types, null=True),
        "role": _enum(ROLES, null=True),
        "onset": {"oneOf": [{"type": "null"}, _obj({"t": _NUM, "range": _NUM, "cpa": _NUM, "tcpa": _NUM})]},
        "release": {"oneOf": [{"type": "null"}, moment]},
        "closest": {"oneOf": [{"type": "null"}, moment]},
        "score": {"type": ["number", "null"], "minimum": 0, "maximum": 1},
        "compliant": {"type": ["boolean", "null"]},
        "conflicting_duties": {"type": "boolean"},
        "conflicts_with": {"type": "array", "items": {"type": "string"}},
        "rules": _obj({r: {"oneOf": [{"type": "null"}, rule]} for r in RULES}),
        "quantities": {"oneOf": [_obj({"min_range": _NUM}),
                                 _obj({**{q: _NUM for q in ENCOUNTER_QUANTITIES},
                                       "head_on_in_doubt": {"type": "boolean"}})]},
    }, description="One encounter of the encounter scorer (mmg_casadi.colregs.scorer.Encounter.to_dict).")
    encounter["allOf"] = [
        {"if": {"properties": {"applicable": {"const": True}}},
         "then": {"properties": {"encounter": {"type": "string"}, "role": {"type": "string"},
                                 "onset": {"type": "object"}, "release": {"type": "object"},
                                 "closest": {"type": "object"}}}},
        {"if": {"properties": {"applicable": {"const": False}}},
         "then": {"properties": {"unfinished": {"const": False}, "encounter": {"type": "null"},
                                 "role": {"type": "null"}, "score": {"type": "null"},
                                 "compliant": {"type": "null"}, "rules": {"additionalProperties": {"type": "null"}},
                                 "quantities": {"required": ["min_range"]}}}},
    ]

    legacy_rule = _obj({"verdict": {"type": ["boolean", "null"]}}, extra=_TERM)
    legacy_side = _obj({"encounter": _enum(ENCOUNTERS), "compliant_all": {"type": ["boolean", "null"]},
                        "quantities": {"type": "object", "additionalProperties": _TERM},
                        **{r: legacy_rule for r in LEGACY_RULES}})
    legacy = _obj({"profile": {"type": "string"}, "a": legacy_side, "b": legacy_side},
                  description="The legacy scorer (mmg_casadi.colregs.score.PairScore.to_dict).")

    common = {"a": {"type": "string"}, "b": {"type": "string"}, "min_distance": _NUM, "t_min": _NUM}
    ship_pair = _obj({
        **common,
        "encounter": _enum(ENCOUNTERS), "compliant": {"type": ["boolean", "null"]},
        "encounter_b": _enum(ENCOUNTERS), "compliant_b": {"type": ["boolean", "null"]},
        "t_enter": _NUM,
        "rules": {"oneOf": [{"type": "null"}, legacy]},
        "encounters": _obj({side: {"type": "array", "items": {"$ref": "#/$defs/encounter"}} for side in "ab"}),
    }, description="A pair of ships.")
    obstacle_pair = _obj({
        **common, "b": {"type": "string", "pattern": "^obstacle[0-9]+$"},
        "encounter": _enum(["static", "none"]), "compliant": {"type": "null"},
        "encounter_b": {"type": "null"}, "compliant_b": {"type": "null"}, "t_enter": {"type": "null"},
    }, description="A ship and a static obstacle.")

    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "$id": SCHEMA_ID,
        "title": "metrics.json of a scenario run (mmg-casadi)",
        "description": "Written by `mmg-casadi simulate`, the studies of single scenarios and "
                       "ScenarioResult.save; distances in ship lengths L, times in L/U (mmg_casadi.scenarios.run).",
        **_obj({
            "method": _enum(method_names),
            "collision": {"type": "boolean"},
            "t_end": {"type": "number"},
            "params": _with_optional(
                _obj({name: _param_schema(p) for name, p in PARAMETERS.items() if name not in optional},
                     description="Every parameter of the table, resolved (mmg_casadi.params.PARAMETERS); the "
                                 "parameters of an on-demand method only in a run that uses it."),
                {name: _param_schema(p) for name, p in optional.items()}),
            "ships": {"type": "array", "minItems": 1, "items": {"$ref": "#/$defs/ship"}},
            "pairs": {"type": "array", "items": {"oneOf": [{"$ref": "#/$defs/ship_pair"},
                                                           {"$ref": "#/$defs/obstacle_pair"}]}},
            "route_warnings": {"type": "array", "items": {"$ref": "#/$defs/route_warning"}},
        }),
        "$defs": {"ship": ship, "ship_pair": ship_pair, "obstacle_pair": obstacle_pair, "encounter": encounter,
                  "route_warning": route_warning},
    }


def schema_text() -> str:
    """:func:`metrics_schema` as the text of the packaged file (indented JSON, one trailing newline).

    Returns
    -------
    str
        The JSON text.

    Examples
    --------
    >>> schema_text().startswith('{')
    True
    """
    return json.dumps(metrics_schema(), indent=2, ensure_ascii=False) + "\n"


def load_metrics_schema() -> dict:
    """The schema shipped in ``mmg_casadi/data/metrics.schema.json``.

    Returns
    -------
    dict
        The parsed JSON Schema.

    Examples
    --------
    >>> load_metrics_schema()["title"]
    'metrics.json of a scenario run (mmg-casadi)'
    """
    return json.loads(resources.files("mmg_casadi").joinpath("data", SCHEMA_FILE).read_text(encoding="utf-8"))


if __name__ == "__main__":
    target = resources.files("mmg_casadi").joinpath("data", SCHEMA_FILE)
    with resources.as_file(target) as path:
        write_text(path, schema_text())
    print(f"wrote {path}", file=sys.stderr)
