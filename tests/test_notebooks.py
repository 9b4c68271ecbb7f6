"""The notebooks run top to bottom on a fresh kernel (venv's ipykernel), and the stagnation-point helper they use."""

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from tuning.stagnation import distance_from_obstacle, stagnation_point

NOTEBOOKS = Path(__file__).resolve().parents[1] / "notebooks"
NAMES = ("stagnation_points.ipynb", "pd_gain_design.ipynb", "apf_tuning.ipynb", "identify_from_trials.ipynb")


def test_kernel_is_this_venv():
    from jupyter_client.manager import KernelManager
    km = KernelManager(kernel_name="python3")
    assert km.format_kernel_cmd()[0] == sys.executable


@pytest.mark.parametrize("name", NAMES)
def test_notebook_runs(name):
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    nb = nbformat.read(NOTEBOOKS / name, as_version=4)
    assert all(not c.get("outputs") for c in nb.cells if c.cell_type == "code"), "commit notebooks without outputs"
    client = nbclient.NotebookClient(nb, timeout=300, kernel_name="python3",
                                     resources={"metadata": {"path": str(NOTEBOOKS)}})
    client.execute()  # raises CellExecutionError on the first failing cell
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", []) if o.output_type == "error"]
    assert not errors


def test_inverse_square_stagnation_point_of_paper_example():
    """Obstacle (-10, 0) of radius 0.5 L, goal (10, 0): the paper reads ≈ 5 L off its figure; d0 = 8 L gives 5.4 L."""
    p = stagnation_point("inverse-square", goal=(10, 0), obstacle=(-10, 0), guess=(-15, 0))
    assert abs(p[1]) < 1e-9 and p[0] < -10
    assert 5.0 <= distance_from_obstacle(p, (-10, 0)) <= 5.6


def test_sink_vortex_stagnation_point_matches_closed_form():
    p = stagnation_point("sink-vortex", guess=(-10, -2))
    assert abs(distance_from_obstacle(p) - 20 / (1 + 10 ** 2) ** 0.5) < 1e-9


def test_no_root_raises():
    with pytest.raises(RuntimeError):
        stagnation_point("sink-vortex", guess=(-10, 2))  # Newton runs off to infinity, where every field vanishes


CUP = [(-12, -3), (-9, 0), (-12, 3)]
SCENES = [  # the stagnation-point notebook's scenes: (field, goal, obstacles, targets, kinds found)
    ("inverse-square", (15, 0), CUP, (), ["saddle", "saddle", "stable node", "saddle", "saddle"]),
    ("sink-vortex", (15, 0), CUP, (), ["saddle"] * 3),
    ("modified-vortex", (10, 0), [(-10, 0)], (), []),
    ("modified-vortex", (10, 0), (), [((0, 5), (0, -1))], ["saddle"]),
    ("modified-vortex", (10, 0), (), [((-10, 0), (1.0, 0.0))], ["saddle"]),
    ("modified-vortex", (10, 0), (), [((-10, 3), (0.0, -0.8))], []),
]


@pytest.mark.parametrize("field, goal, obstacles, targets, kinds", SCENES)
def test_stagnation_points_agree_with_a_brute_force_grid_search(field, goal, obstacles, targets, kinds):
    """Multi-start Newton (CasADi rootfinder) and a 300 x 300 sign-change search find the same points, within
    two grid cells; the Jacobian's eigenvalues say saddle / node as the notebook reports."""
    from tuning.stagnation import classify, grid_stagnation_cells, scene_function, stagnation_points
    box = (-30, 20, -20, 20)
    F = scene_function(field, goal, obstacles, targets=targets)
    exclude = [(o, 1.0) for o in obstacles] + [(p, 1.0) for p, _ in targets] + [(goal, 1.0)]
    roots = stagnation_points(F, box, exclude=exclude)
    grid = grid_stagnation_cells(F, box, n=300, exclude=exclude)
    cell = math.hypot(50 / 299, 40 / 299)
    assert len(roots) == len(grid) == len(kinds)
    for q in roots:
        assert min(math.hypot(*(q - g)) for g in grid) < 2 * cell
    for g in grid:
        assert min(math.hypot(*(g - q)) for q in roots) < 2 * cell
    assert [classify(F, q)[1] for q in roots] == kinds
    assert all(float(np.linalg.norm(np.array(F(q)))) < 1e-8 for q in roots)


def test_the_modified_vortex_switch_is_a_sign_change_without_a_zero():
    from tuning.stagnation import grid_stagnation_cells, scene_function
    F = scene_function("modified-vortex", (10, 0), (), targets=[((-10, 3), (0.0, -0.8))])
    jumps = grid_stagnation_cells(F, (-30, 20, -20, 20), n=300, exclude=[((-10, 3), 1.0), ((10, 0), 1.0)],
                                  jumps=True)
    assert len(jumps) == 1
    q = jumps[0]
    near = np.array([[q[0] + dx, q[1] + dy] for dx in np.linspace(-0.2, 0.2, 21) for dy in np.linspace(-0.2, 0.2, 21)])
    speed = np.hypot(*np.array(F.map(len(near))(near.T)))
    assert speed.min() > 0.05 * speed.max()  # the field jumps across zero without vanishing
