"""Recorded AIS tracks as a scenario: the target ships retrace their recorded routes, the own ship sails hers with a
collision-avoidance method.

Input: a CSV file of AIS position reports with the columns ``mmsi``, ``time`` (seconds, or an ISO 8601 date and
time; a time without zone is read as UTC), ``lat``, ``lon`` (degrees, WGS-84); other columns are ignored. One ship
(``own``, an MMSI) is the own ship.

Replay (ours): the scenario begins at ``t0``, the own ship's first report or a chosen ``start`` time within her
recording, and her recording ends it. Positions go to the plane of
:class:`~mmg_casadi.scenarios.geodesy.LocalPlane` about the own ship's position at ``t0``, in ship lengths of
``unit_m`` metres (the KCS's 230 m by default), times to L/U with the design speed Froude-scaled to ``unit_m``.
The own ship starts from her recorded state at ``t0`` (position, course of her track, speed): her track from
``t0`` (linearly interpolated) is resampled every ``step_s`` seconds; the resampled points are her waypoints and
the speed of each leg is its length over ``step_s``, as a fraction of the design speed (clipped to
:data:`~mmg_casadi.scenarios.scenario.SPEED_RANGE`, the clipped legs counted); she sails them with ``method``.

The target ships (``targets``):

* ``"track"`` (exact replay): each target is a replayed ship (:mod:`mmg_casadi.scenarios.tracks`) whose track is
  its reports from the last one at or before ``t0`` to the first one after the horizon, in L and L/U; the closed
  loop interpolates it in time, so the target is where the recording has it at every step.
* ``"route"`` (approximate): a target gets waypoints and leg speeds like the own ship, with the method ``"none"``;
  it follows its recorded route by waypoint tracking, so its timing follows the recording only as far as the
  ship's dynamics allow.

Ships without a report at or before ``t0`` (they appear later) or with one report only are left out and listed,
as are replayed targets with a jump faster than :data:`~mmg_casadi.scenarios.tracks.MAX_TRACK_SPEED` between two
reports.
"""

from __future__ import annotations

import csv
import datetime
import json
import math
from pathlib import Path

import numpy as np

from mmg_casadi.errors import InputError
from mmg_casadi.guidance import methods as registry
from mmg_casadi.scenarios.geodesy import LocalPlane
from mmg_casadi.scenarios.scenario import SPEED_RANGE, Scenario, scenario_from_dict
from mmg_casadi.scenarios.tracks import MAX_TRACK_POINTS, MAX_TRACK_SPEED
from mmg_casadi.vessel.ship import load_kcs

COLUMNS = ("mmsi", "time", "lat", "lon")
"""Required columns of an AIS CSV file."""
MAX_LEGS = 10_000
"""Largest number of resampled legs of one ship (duration / step)."""
HORIZON_FACTOR = 1.5
TARGETS = ("route", "track")
"""How the targets follow their recordings (:func:`ais_scenario`)."""
"""The horizon is this many times the recording's duration (room for the own ship's detours; ours)."""
REPLAY_METHOD = "colregs-vortex"
"""The own ship's method unless one is chosen. A replayed route has a waypoint every ``step_s`` (60 s: 1.9 L at
14 kn), and the paper's fields put their sink at the next waypoint: within a few L its pull, ``abs(Λ) / (2π r)``
(about 4 U at 4 L), dwarfs the vortex (a few tenths of U), the paper's near-goal failure, so the modified vortex cannot
give way (in the shipped sample it passes the target at 0.74 L; with the own ship's last waypoint alone, 5.57 L).
colregs-vortex caps the goal's pull while it avoids (``cv_d_att_floor``) and counts waypoints passed abeam as
passed, so it sails such routes as they are (4.18 L in the sample)."""


def _time(text: str, field: str) -> float:
    """Seconds from a number or an ISO 8601 date-time (UTC without a zone)."""
    try:
        value = float(text)
    except ValueError:
        try:
            dt = datetime.datetime.fromisoformat(text.strip())
        except ValueError:
            raise InputError(field, "seconds or an ISO 8601 date and time", text) from None
        if dt.tzinfo is None:
            dt = dt.replace(tzinfo=datetime.timezone.utc)
        return dt.timestamp()
    if not math.isfinite(value):
        raise InputError(field, "seconds or an ISO 8601 date and time", text)
    return value


def parse_time(text: str, field: str) -> float:
    """Seconds from a number or an ISO 8601 date and time (UTC without a zone), as the ``time`` column is read.

    Parameters
    ----------
    text : str
        The time.
    field : str
        Name of the input, for the error.

    Returns
    -------
    float
        Seconds (since the epoch for a date and time).

    Examples
    --------
    >>> parse_time("2024-05-01T12:00:30", "--start") - parse_time("2024-05-01T12:00:00", "--start")
    30.0
    """
    return _time(text, field)


def _json_rows(path: Path) -> list[dict]:
    """The reports of a JSON file (a list of objects, or an object whose ``reports`` is one) as CSV-like rows of
    strings (a number as JSON writes it)."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError, RecursionError) as err:
        raise InputError(str(path), "an existing, readable JSON file of AIS reports (UTF-8)", str(err)) from None
    reports = data.get("reports") if isinstance(data, dict) else data
    if not isinstance(reports, list) or not all(isinstance(r, dict) for r in reports):
        raise InputError(str(path), "a JSON list of report objects (or an object whose 'reports' is one)")
    return [{k: v if isinstance(v, str) else json.dumps(v) for k, v in r.items()} for r in reports]


def load_ais_csv(path) -> dict[str, np.ndarray]:
    """AIS reports per MMSI from a CSV file: ``{mmsi: array (K, 3) of time [s], lat, lon [deg]}``, time-sorted.

    A file ending in ``.json`` is read as a list of report objects with the same keys as the CSV columns
    (``[{"mmsi": 999000001, "time": "2026-05-04T10:00:00", "lat": 57.9, "lon": 10.2}, ...]``, or an object whose
    ``reports`` is that list).

    Parameters
    ----------
    path : str or Path
        The CSV (or JSON) file (module docstring).

    Returns
    -------
    dict
        MMSI (as written) → reports; duplicate times keep the last report.

    Raises
    ------
    InputError
        A missing file, a missing column, or a bad value (``<file> row <n>.<column>``).
    """
    path = Path(path)
    is_json = path.suffix.lower() == ".json"
    if is_json:
        rows = _json_rows(path)
    else:
        try:
            with path.open(newline="", encoding="utf-8") as f:
                rows = list(csv.DictReader(f))
        except (OSError, UnicodeDecodeError, csv.Error) as err:
            raise InputError(str(path), "an existing, readable CSV file of AIS reports (UTF-8)", str(err)) from None
    if not rows:
        raise InputError(str(path), f"a file with the columns ({', '.join(COLUMNS)}) and at least one report")
    missing = [c for c in COLUMNS if c not in rows[0]]
    if missing:
        raise InputError(str(path), f"the columns {', '.join(COLUMNS)} (missing: {', '.join(missing)})")
    ships: dict[str, dict[float, tuple[float, float]]] = {}
    for n, r in enumerate(rows, start=1 if is_json else 2):
        key = f"{path.name} {'report' if is_json else 'row'} {n}"
        mmsi = (r.get("mmsi") or "").strip()
        if not mmsi:
            raise InputError(f"{key}.mmsi", "a ship identifier (MMSI)", r.get("mmsi"))
        t = _time(r.get("time") or "", f"{key}.time")
        pos = []
        for col, bound in (("lat", 90.0), ("lon", 180.0)):
            try:
                v = float(r.get(col))
            except (TypeError, ValueError):
                raise InputError(f"{key}.{col}", f"degrees in [-{bound:g}, {bound:g}]", r.get(col)) from None
            if not -bound <= v <= bound:
                raise InputError(f"{key}.{col}", f"degrees in [-{bound:g}, {bound:g}]", r.get(col))
            pos.append(v)
        ships.setdefault(mmsi, {})[t] = (pos[0], pos[1])
    return {m: np.array([[t, *p] for t, p in sorted(reports.items())]) for m, reports in ships.items()}


def _resample(track: np.ndarray, t0: float, t1: float, step: float) -> np.ndarray:
    """Times ``t0, t0 + step, ...`` up to the track's end (at most ``t1``; the end itself included)."""
    end = min(float(track[-1, 0]), t1)
    times = np.arange(t0, end, step)
    return np.append(times, end) if end - times[-1] > 1e-9 else times


def ais_scenario(tracks: dict, own: str, *, step_s: float = 60.0, method: str = REPLAY_METHOD,
                 unit_m: float | None = None, targets: str = "route",
                 start: float | None = None) -> tuple[Scenario, dict]:
    """The replay scenario of AIS ``tracks`` with ship ``own`` as the own ship (module docstring).

    Parameters
    ----------
    tracks : dict
        :func:`load_ais_csv`'s result.
    own : str
        MMSI of the own ship.
    step_s : float, optional
        Resampling step of the routes [s], > 0.
    method : str, optional
        The own ship's method (default :data:`REPLAY_METHOD`).
    unit_m : float, optional
        Metres per ship length (default: the KCS's 230 m).
    targets : {"route", "track"}, optional
        The targets retrace their recorded routes by waypoint tracking (``"route"``) or replay their tracks
        exactly (``"track"``), see the module docstring.
    start : float, optional
        Time [s, as in the file] at which the own ship starts from her recorded state (default: her first report);
        within her recording.

    Returns
    -------
    (Scenario, dict)
        The scenario (own ship first, targets named by MMSI) and a report: ``t0`` [s], ``duration`` [s],
        ``ships`` (MMSIs kept), ``left_out`` ({MMSI: reason}), ``clipped_legs`` (legs whose speed was clipped),
        ``targets``.

    Examples
    --------
    >>> t = np.array([0.0, 600.0])
    >>> tracks = {"1": np.column_stack([t, [58.0, 58.05], [10.0, 10.0]]),
    ...           "2": np.column_stack([t, [58.05, 58.0], [10.001, 10.001]])}
    >>> sc, rep = ais_scenario(tracks, "1", step_s=300.0)
    >>> [s.name for s in sc.ships], len(sc.ships[0].waypoints), round(sc.ships[1].heading_deg)
    (['1', '2'], 2, 180)
    """
    if own not in tracks:
        raise InputError("own", f"an MMSI of the file (one of: {', '.join(sorted(tracks)[:10])}"
                         f"{', ...' if len(tracks) > 10 else ''})", own)
    if not (isinstance(step_s, (int, float)) and math.isfinite(step_s) and step_s > 0):
        raise InputError("step", "a number of seconds > 0", step_s)
    registry.get(method, "method")
    kcs = load_kcs()
    unit = kcs.L if unit_m is None else float(unit_m)
    u_des = kcs.U_design * math.sqrt(unit / kcs.L)  # m/s, Froude-scaled
    own_track = tracks[own]
    if len(own_track) < 2:
        raise InputError("own", "a ship with at least two reports", own)
    if targets not in TARGETS:
        raise InputError("targets", f"one of: {', '.join(TARGETS)}", targets)
    t0, t1 = float(own_track[0, 0]), float(own_track[-1, 0])
    if start is not None:
        if not (isinstance(start, (int, float)) and math.isfinite(start) and t0 <= start < t1):
            raise InputError("start", f"a time within the own ship's recording, [{t0:g}, {t1:g}) s", start)
        t0 = float(start)
    horizon_s = HORIZON_FACTOR * (t1 - t0)
    if (t1 - t0) / step_s > MAX_LEGS:
        raise InputError("step", f"a step of at least {(t1 - t0) / MAX_LEGS:.6g} s (at most {MAX_LEGS} legs over the "
                         f"own ship's {t1 - t0:g} s)", step_s)
    plane = LocalPlane(*(float(np.interp(t0, own_track[:, 0], own_track[:, k])) for k in (1, 2)))
    lo, hi = SPEED_RANGE
    ships, left_out, clipped = [], {}, 0
    for mmsi in [own] + sorted(m for m in tracks if m != own):
        tr = tracks[mmsi]
        if len(tr) < 2:
            left_out[mmsi] = "one report only"
            continue
        if tr[0, 0] > t0 or tr[-1, 0] <= t0:
            left_out[mmsi] = "no report at or before the own ship's first one" if tr[0, 0] > t0 else \
                "its reports end before the own ship's first one"
            continue
        if mmsi != own and targets == "track":
            entry = _replayed(mmsi, tr, t0, t0 + horizon_s, plane, unit, u_des)
            if isinstance(entry, str):
                left_out[mmsi] = entry
            else:
                ships.append(entry)
            continue
        times = _resample(tr, t0, t1, float(step_s))
        if len(times) < 2:
            left_out[mmsi] = "no report after the own ship's first one"
            continue
        lat = np.interp(times, tr[:, 0], tr[:, 1])
        lon = np.interp(times, tr[:, 0], tr[:, 2])
        pts = np.array([plane.to_plane(a, b, field=f"{mmsi} position") for a, b in zip(lat, lon)]) / unit
        legs = np.hypot(*np.diff(pts, axis=0).T)
        speeds = legs * unit / np.diff(times) / u_des
        clipped += int(np.sum((speeds < lo) | (speeds > hi)))
        speeds = np.clip(speeds, lo, hi)
        moving = legs > 1e-9
        if not moving.any():
            left_out[mmsi] = "it does not move"
            continue
        first = int(np.argmax(moving))
        d = pts[first + 1] - pts[first]
        keep = moving  # zero-length legs (a ship lying still) add no waypoint
        ships.append({"name": mmsi, "start": [round(float(v), 6) + 0.0 for v in pts[0]],
                      "heading": round(math.degrees(math.atan2(d[1], d[0])), 6) + 0.0,
                      "speed": round(float(speeds[first]), 6),
                      "waypoints": [[round(float(v), 6) + 0.0 for v in p] for p in pts[1:][keep]],
                      "speeds": [round(float(v), 6) for v in speeds[keep]]})
        if mmsi != own:
            ships[-1]["method"] = "none"
    if not ships or ships[0]["name"] != own:
        raise InputError("own", "a ship that moves during its recording", own)
    duration = t1 - t0
    t_max = max(HORIZON_FACTOR * duration * u_des / unit, 1.0)
    sc = scenario_from_dict({"settings": {"method": method, "t_max": round(t_max, 3)}, "ships": ships},
                            source="ais replay")
    return sc, {"t0": t0, "duration": duration, "ships": [s["name"] for s in ships], "left_out": left_out,
                "clipped_legs": clipped, "targets": targets}


def _replayed(mmsi: str, tr: np.ndarray, t0: float, t_end: float, plane: LocalPlane, unit: float,
              u_des: float) -> dict | str:
    """The scenario table of a replayed target (its reports from the last at or before ``t0`` to the first at or
    after ``t_end``, in L and L/U), or the reason it is left out."""
    first = int(np.searchsorted(tr[:, 0], t0, side="right")) - 1
    last = min(int(np.searchsorted(tr[:, 0], t_end, side="left")), len(tr) - 1)
    part = tr[first:last + 1]
    if len(part) > MAX_TRACK_POINTS:
        return f"more than {MAX_TRACK_POINTS} reports over the horizon"
    pts = np.array([plane.to_plane(a, b, field=f"{mmsi} position") for a, b in part[:, 1:3]]) / unit
    t = (part[:, 0] - t0) * u_des / unit
    speed = np.hypot(*np.diff(pts, axis=0).T) / np.diff(t)
    if np.any(speed > MAX_TRACK_SPEED):
        return f"a jump faster than {MAX_TRACK_SPEED:g} U between two reports (a bad record)"
    return {"name": mmsi, "track": {"t": [round(float(v), 9) + 0.0 for v in t],
                                    "x": [round(float(v), 9) + 0.0 for v in pts[:, 0]],
                                    "y": [round(float(v), 9) + 0.0 for v in pts[:, 1]]}}
