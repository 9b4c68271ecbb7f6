"""Converting files between maritime-schema JSON traffic situations and scenario TOML files.

JSON → TOML reads the situation with :func:`~mmg_casadi.scenarios.maritime_schema.load_traffic_situation` and
writes the scenario after a comment recording the plane's reference and the length unit
(:func:`~mmg_casadi.scenarios.geodesy.scenario_header`); TOML → JSON reads that comment back
(:func:`~mmg_casadi.scenarios.geodesy.read_header`) and writes the situation
with :func:`~mmg_casadi.scenarios.maritime_export.dump_traffic_situation`. :func:`convert_file` is the
``mmg-casadi convert`` command.

What the situation holds comes back: positions (the plane's map and its inverse agree to nanometres, see
:mod:`mmg_casadi.scenarios.geodesy`), courses, speeds, and each ship's static data, kept in the scenario file as
``length_m``, ``beam_m`` and a ``[ships.metadata]`` table (:class:`~mmg_casadi.scenarios.scenario.ShipSpec`).
"""

from __future__ import annotations

import json
import math
import tomllib
from pathlib import Path

from mmg_casadi.errors import ScenarioError
from mmg_casadi.guidance.methods import DEFAULT as DEFAULT_METHOD
from mmg_casadi.io import write_text
from mmg_casadi.scenarios.geodesy import LocalPlane, read_header, scenario_header
from mmg_casadi.scenarios.maritime_export import DEFAULT_REFERENCE, dump_traffic_situation
from mmg_casadi.scenarios.maritime_schema import hull_choices, load_traffic_situation
from mmg_casadi.scenarios.scenario import dump_scenario, load_scenario, scenario_from_dict



def json_to_toml_text(path, **kw) -> str:
    """Scenario-file TOML text (with its reference header) of a maritime-schema JSON file.

    Parameters
    ----------
    path : str or os.PathLike
        The maritime-schema JSON file.
    **kw
        Keyword arguments of :func:`~mmg_casadi.scenarios.maritime_schema.traffic_situation_to_scenario`:
        ``method``, ``target_method``, ``length_scale``, ``extend_past``.

    Returns
    -------
    str
        The :func:`scenario_header` comment followed by the scenario (:func:`~mmg_casadi.scenarios.scenario.dump_scenario`).
    """
    sc, plane, unit = load_traffic_situation(path, **kw)
    return scenario_header(plane, unit) + dump_scenario(sc)


def toml_to_json_text(path, *, reference=None) -> str:
    """maritime-schema JSON text of a scenario TOML file, about ``reference`` = (lat, lon), else the reference
    recorded in the file's header, else :data:`~mmg_casadi.scenarios.maritime_export.DEFAULT_REFERENCE`.

    Parameters
    ----------
    path : str or os.PathLike
        The scenario TOML file (UTF-8); its name without suffix becomes the situation's ``title``.
    reference : (float, float), optional
        Latitude and longitude [deg] of the scenario's origin. If None, the file's :func:`scenario_header`
        supplies the reference and the length unit; without a header the reference is
        :data:`~mmg_casadi.scenarios.maritime_export.DEFAULT_REFERENCE` and the unit the KCS length (230 m). A
        given ``reference`` always uses the KCS length, even if the file has a header.

    Returns
    -------
    str
        The JSON text (:func:`~mmg_casadi.scenarios.maritime_export.dump_traffic_situation`).
    """
    sc = load_scenario(path)
    header = read_header(Path(path).read_text(encoding="utf-8"))
    unit = None
    if reference is None and header is not None:
        reference, unit = header[:2], header[2]
    return dump_traffic_situation(sc, reference=reference or DEFAULT_REFERENCE, unit_m=unit,
                                  title=Path(path).stem)


def parse_reference(text):
    """``"LAT,LON"`` [deg] as a (lat, lon) tuple (None stays None).

    Parameters
    ----------
    text : str or None
        Two numbers separated by one comma (spaces allowed), latitude in [-90, 90] and longitude in
        [-180, 180] degrees, as given to ``--reference``; anything else raises a
        :class:`~mmg_casadi.errors.ScenarioError`.

    Returns
    -------
    (float, float) or None
        ``(lat, lon)``, or None if ``text`` is None.

    Examples
    --------
    >>> parse_reference("58.5, 10.25")
    (58.5, 10.25)
    >>> parse_reference("north")
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.ScenarioError: --reference: expected LAT,LON in degrees (lat in [-90, 90], lon in [-180, 180]), got 'north'
    """
    if text is None:
        return None
    allowed = "LAT,LON in degrees (lat in [-90, 90], lon in [-180, 180])"
    parts = str(text).split(",")
    try:
        lat, lon = (float(v) for v in parts)
    except ValueError:
        raise ScenarioError("--reference", allowed, text) from None
    if not (math.isfinite(lat) and math.isfinite(lon) and -90 <= lat <= 90 and -180 <= lon <= 180):
        raise ScenarioError("--reference", allowed, text)
    return lat, lon


def convert_file(src, out, *, method: str = DEFAULT_METHOD, target_method: str = "none",
                 length_scale: str = "kcs", reference=None) -> dict:
    """Convert ``src`` (``.json`` traffic situation or ``.toml`` scenario) into ``out`` (the other format).

    The output is written only if the conversion succeeds (a temporary file, then a rename). ``reference``
    (``"LAT,LON"`` or a tuple) applies to TOML → JSON; the other keywords to JSON → TOML.

    Parameters
    ----------
    src : str or os.PathLike
        The input file: a ``.json`` traffic situation or a ``.toml`` scenario (suffix case-insensitive).
    out : str or os.PathLike
        The output file, with the other suffix (``.toml`` for a JSON input, ``.json`` for a TOML one); its
        directory is created if needed.
    method : str, optional
        Collision-avoidance method of the own ship (JSON → TOML), one of :data:`~mmg_casadi.guidance.methods.METHODS`.
    target_method : str, optional
        Method of the target ships (JSON → TOML); ``"none"``: they do not avoid anyone.
    length_scale : str, optional
        ``"kcs"`` or ``"own-ship"`` (JSON → TOML), see
        :func:`~mmg_casadi.scenarios.maritime_schema.traffic_situation_to_scenario`.
    reference : str or (float, float), optional
        Latitude and longitude [deg] of the scenario's origin (TOML → JSON), ``"LAT,LON"``
        (:func:`parse_reference`) or a tuple; None: the file's header, else
        :data:`~mmg_casadi.scenarios.maritime_export.DEFAULT_REFERENCE`.

    Returns
    -------
    dict
        ``{"out": str(out), "ships": number of ships, "hulls": lines}``: for a JSON input, the hull each ship of
        known length sails and why (:func:`~mmg_casadi.scenarios.maritime_schema.hull_choices`), else empty.
    """
    src, out = Path(src), Path(out)
    kinds = {".json": ".toml", ".toml": ".json"}
    if src.suffix.lower() not in kinds:
        raise ScenarioError("file", "a .json traffic situation or a .toml scenario file", str(src))
    if out.suffix.lower() != kinds[src.suffix.lower()]:
        raise ScenarioError("--out", f"a {kinds[src.suffix.lower()]} file (converting {src.suffix})", str(out))
    if isinstance(reference, str):
        reference = parse_reference(reference)
    if src.suffix.lower() == ".json":
        text = json_to_toml_text(src, method=method, target_method=target_method, length_scale=length_scale)
        sc = scenario_from_dict(tomllib.loads(text))
        n, hulls = len(sc.ships), hull_choices(sc)
    else:
        text = toml_to_json_text(src, reference=reference)
        n, hulls = 1 + len(json.loads(text)["targetShips"]), []
    write_text(out, text)
    return {"out": str(out), "ships": n, "hulls": hulls}
