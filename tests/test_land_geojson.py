"""Land from GeoJSON (issue 24): a scenario's ``[chart]`` table and the maritime-schema import's same-stem file,
projected like the import; bad input refused with one line naming the field, exit 2, nothing written."""

import json
import shutil
from importlib.resources import files

import numpy as np
import pytest

from mmg_casadi.cli import main
from mmg_casadi.errors import ScenarioError
from mmg_casadi.scenarios.geodesy import LocalPlane
from mmg_casadi.scenarios.interchange import scenario_header
from mmg_casadi.scenarios.maritime_schema import load_traffic_situation
from mmg_casadi.scenarios.run import run_scenario
from mmg_casadi.scenarios.scenario import load_scenario

ORIGIN = (58.61, 10.59)
PLANE = LocalPlane(*ORIGIN)
SQUARE_L = [(20.0, -5.0), (30.0, -5.0), (30.0, 5.0), (20.0, 5.0)]  # as tests/test_land.py's, in L
SCENARIO = """
[settings]
method = "none"
t_max = 60.0

[[ships]]
name = "own"
start = [0.0, 0.0]
heading = 0.0
speed = 1.0
waypoints = [[50.0, 0.0]]
"""


def _lonlat(points_l, plane=PLANE, unit=230.0):
    ring = [list(reversed(plane.to_geodetic(x * unit, y * unit))) for x, y in points_l]
    return ring + [ring[0]]


def _collection(*geometries):
    return {"type": "FeatureCollection",
            "features": [{"type": "Feature", "properties": {}, "geometry": g} for g in geometries]}


def _write(tmp_path, chart: str, geojson) -> object:
    (tmp_path / "coast.geojson").write_text(json.dumps(geojson))
    path = tmp_path / "s.toml"
    path.write_text(SCENARIO + "\n[chart]\n" + chart)
    return path


def test_a_ship_sailing_into_geojson_land_grounds(tmp_path):
    path = _write(tmp_path, f'land_file = "coast.geojson"\norigin = [{ORIGIN[0]}, {ORIGIN[1]}]\n',
                  _collection({"type": "Polygon", "coordinates": [_lonlat(SQUARE_L)]}))
    sc = load_scenario(path)
    (land,) = sc.land
    assert np.allclose(land.points, SQUARE_L, atol=1e-6)
    own = run_scenario(sc).metrics["ships"][0]
    assert own["collision_kind"] == "land" and own["collision_time"] == pytest.approx(20.0)


def test_multipolygons_follow_inline_land_and_the_converted_header_gives_the_origin(tmp_path):
    island = [(60.0, 10.0), (62.0, 10.0), (62.0, 12.0)]
    multi = {"type": "MultiPolygon", "coordinates": [[_lonlat(SQUARE_L)], [_lonlat(island)]]}
    (tmp_path / "coast.geojson").write_text(json.dumps(multi))
    path = tmp_path / "s.toml"
    path.write_text(scenario_header(PLANE, 230.0) + SCENARIO
                    + "\n[[land]]\npoints = [[-10.0, 10.0], [-5.0, 10.0], [-5.0, 15.0]]\n"
                    + '\n[chart]\nland_file = "coast.geojson"\n')
    sc = load_scenario(path)
    assert [len(p.points) for p in sc.land] == [3, 4, 3]
    assert np.allclose(sc.land[2].points, island, atol=1e-6)


@pytest.mark.parametrize("chart, geojson, field", [
    ('land_file = "missing.geojson"\norigin = [58.61, 10.59]\n', {}, "chart.land_file"),
    ('land_file = "coast.geojson"\n', {"type": "Polygon", "coordinates": []}, "chart.origin"),
    ('land_file = "coast.geojson"\norigin = [95.0, 10.59]\n', {}, "chart.origin[0]"),
    ('land_file = "coast.geojson"\norigin = [58.61, 10.59]\nscale = 2\n', {}, "chart.scale"),
    ('land_file = "coast.geojson"\norigin = [58.61, 10.59]\n',
     _collection({"type": "LineString", "coordinates": [[10.59, 58.61], [10.6, 58.62]]}),
     "coast.geojson.features[0].geometry.type"),
    ('land_file = "coast.geojson"\norigin = [58.61, 10.59]\n',
     {"type": "Polygon", "coordinates": [[[10.59, 58.61], [10.6, 58.61], [10.59, 58.61]]]},
     "coast.geojson.coordinates[0]"),
    ('land_file = "coast.geojson"\norigin = [58.61, 10.59]\n',
     {"type": "Polygon", "coordinates": [[[10.59, 58.61], [200.0, 58.61], [10.6, 58.62], [10.59, 58.61]]]},
     "coast.geojson.coordinates[0][1][0]"),
    ('land_file = "coast.geojson"\norigin = [58.61, 10.59]\n',  # the own ship would start on land
     {"type": "Polygon", "coordinates": [_lonlat([(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)])]},
     "ships[0].start"),
])
def test_bad_charts_name_the_field(tmp_path, chart, geojson, field):
    with pytest.raises(ScenarioError) as err:
        load_scenario(_write(tmp_path, chart, geojson))
    assert err.value.field == field


def test_cli_refuses_a_bad_chart_with_one_line_exit_2_nothing_written(tmp_path, capsys):
    path = _write(tmp_path, 'land_file = "coast.geojson"\norigin = [58.61, 10.59]\n',
                  _collection({"type": "Point", "coordinates": [10.6, 58.6]}))
    out = tmp_path / "out"
    assert main(["simulate", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "geometry.type" in err[0] and "Polygon, MultiPolygon" in err[0]
    assert not out.exists()


def test_convert_reads_the_geojson_next_to_the_situation(tmp_path):
    src = tmp_path / "situation.json"
    shutil.copy(files("mmg_casadi") / "data" / "traffic_situation.json", src)
    plain = load_traffic_situation(src)[0]
    assert plain.land == ()
    island = [(10.0, 20.0), (14.0, 20.0), (14.0, 24.0), (10.0, 24.0)]  # east of every route, in KCS lengths
    (tmp_path / "situation.geojson").write_text(json.dumps(_collection({"type": "Polygon",
                                                                        "coordinates": [_lonlat(island)]})))
    sc, plane, unit = load_traffic_situation(src)
    assert (plane.lat, plane.lon, unit) == (*ORIGIN, 230.0)
    assert np.allclose(sc.land[0].points, island, atol=1e-6) and sc.ships == plain.ships
    toml = tmp_path / "converted.toml"
    assert main(["convert", str(src), "--out", str(toml)]) == 0
    assert load_scenario(toml).land == sc.land
