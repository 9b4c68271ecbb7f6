"""The notebooks run top to bottom on a fresh kernel (venv's ipykernel), and the stagnation-point helper they use."""

import sys
from pathlib import Path

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
