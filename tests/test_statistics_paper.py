"""The paper's qualitative Monte Carlo results at 1000 runs per cell (slow: `make test-all`)."""

import pytest

from mmg_casadi.montecarlo import run_study

pytestmark = pytest.mark.slow


def test_modified_vortex_beats_inverse_square_in_every_environment(tmp_path):
    summary = run_study(tmp_path, runs=1000, envs=(1, 2, 3, 4, 5), methods=("modified-vortex", "inverse-square"),
                        progress=False)
    rate = {(r["environment"], r["method"]): r["success_rate"] for r in summary.rows}
    for env in range(1, 6):
        assert rate[(env, "modified-vortex")] > rate[(env, "inverse-square")]
    assert rate[(1, "modified-vortex")] >= 0.99 and rate[(2, "modified-vortex")] >= 0.99
    # success falls with congestion
    assert rate[(5, "modified-vortex")] < rate[(1, "modified-vortex")]
    assert rate[(5, "inverse-square")] < rate[(1, "inverse-square")]
