"""Linear heading-step metrics over a grid of gains (K_p, K_d), and where the paper's K_p = 3.5, K_d = 4 sit.

:func:`grid_step_metrics` steps every loop of the grid at once with the exact zero-order-hold discretisation
(batched matrix exponentials); :func:`paper_gains_map` adds the analysis of the paper's gains
(:func:`~tuning.pd.design.analyse_gains`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from mmg_casadi.vessel.library import DEFAULT as DEFAULT_VESSEL

from ..linear import YawModel, yaw_subsystem
from .analysis import SETTLING
from .design import PAPER_GAINS, PdDesign, analyse_gains


@dataclass(frozen=True)
class GainMap:
    """The paper's gains analysed on the linear model, and linear step metrics over a (K_p, K_d) grid.

    ``overshoot`` (percent), ``settling_time`` and ``dominant_zeta`` are ``(len(kd_grid), len(kp_grid))``
    arrays, NaN where the loop is unstable or does not settle within the horizon.

    Parameters
    ----------
    paper : PdDesign
        The paper's gains K_p = 3.5, K_d = 4 analysed (:func:`~tuning.pd.design.analyse_gains`).
    kp_grid : ndarray
        Grid of K_p values.
    kd_grid : ndarray
        Grid of K_d values.
    overshoot : ndarray
        Linear step overshoot (percent).
    settling_time : ndarray
        2 % settling time of the linear step (L/U_des).
    dominant_zeta : ndarray
        Damping ratio of the dominant closed-loop pole or pair, capped at 1.
    """

    paper: PdDesign
    kp_grid: np.ndarray = field(repr=False)
    kd_grid: np.ndarray = field(repr=False)
    overshoot: np.ndarray = field(repr=False)
    settling_time: np.ndarray = field(repr=False)
    dominant_zeta: np.ndarray = field(repr=False)

    def to_dict(self) -> dict:
        return {"paper": self.paper.to_dict(), "kp_grid": self.kp_grid.tolist(), "kd_grid": self.kd_grid.tolist(),
                "overshoot": _nan_to_none(self.overshoot), "settling_time": _nan_to_none(self.settling_time),
                "dominant_zeta": _nan_to_none(self.dominant_zeta)}


def _nan_to_none(a) -> list:
    return [[None if not np.isfinite(v) else float(v) for v in row] for row in np.asarray(a)]


def _expm_batch(M: np.ndarray, order: int = 18) -> np.ndarray:
    """Matrix exponentials of a stack of small matrices: Taylor series with a common scaling and squaring.

    Examples
    --------
    >>> from scipy.linalg import expm
    >>> M = np.array([[[0.0, 1.0], [-4.0, -0.4]], [[-1.0, 0.0], [0.0, 3.0]]])
    >>> bool(np.allclose(_expm_batch(M), expm(M), rtol=1e-12, atol=1e-12))
    True
    """
    norm = float(np.max(np.sum(np.abs(M), axis=-1)))
    s = max(0, int(math.ceil(math.log2(norm))) + 1) if norm > 0 else 0
    X = M / 2.0**s
    E = np.broadcast_to(np.eye(M.shape[-1]), M.shape).copy()
    term = E.copy()
    for k in range(1, order + 1):
        term = term @ X / k
        E += term
    for _ in range(s):
        E = E @ E
    return E


def grid_step_metrics(model: YawModel, kp_grid, kd_grid, t_end: float = 150.0, dt: float = 0.1):
    """Overshoot (%), 2 % settling time and dominant damping of the linear unit heading step over a gain grid.

    All loops are stepped together with their exact zero-order-hold discretisation (batched ``expm``).

    Parameters
    ----------
    model : YawModel
        Linear yaw subsystem (:func:`~tuning.linear.yaw_subsystem`).
    kp_grid : array_like
        K_p values (columns of the result).
    kd_grid : array_like
        K_d values (rows of the result).
    t_end : float
        Horizon of the step (L/U_des).
    dt : float
        Discretisation step (L/U_des).

    Returns
    -------
    overshoot : numpy.ndarray (len(kd_grid), len(kp_grid))
        Overshoot (%), NaN where the loop is unstable or does not settle.
    settling_time : numpy.ndarray (len(kd_grid), len(kp_grid))
        2 % settling time (L/U_des), NaN likewise.
    dominant_zeta : numpy.ndarray (len(kd_grid), len(kp_grid))
        Damping ratio of the dominant pole(s), at most 1; NaN where unstable.
    """
    KP, KD = np.meshgrid(np.asarray(kp_grid, float), np.asarray(kd_grid, float))
    kp, kd = KP.ravel(), KD.ravel()
    G = kp.size
    Kr = np.zeros((G, 1, 4))
    Kr[:, 0, 1], Kr[:, 0, 2] = kd, kp
    Acl = model.A[None] - model.B[None] @ Kr
    M = np.zeros((G, 5, 5))
    M[:, :4, :4] = Acl
    M[:, :4, 4] = model.B[:, 0][None] * kp[:, None]
    E = _expm_batch(M * dt)
    Ad, bd = E[:, :4, :4], E[:, :4, 4]
    n = int(round(t_end / dt))
    x = np.zeros((G, 4))
    psi = np.empty((G, n + 1))
    psi[:, 0] = 0.0
    for k in range(n):
        x = np.einsum("gij,gj->gi", Ad, x) + bd
        psi[:, k + 1] = x[:, 2]
    t = np.arange(n + 1) * dt
    eig = np.linalg.eigvals(Acl)
    lead = eig[np.arange(G), np.argmax(eig.real, axis=1)]
    stable = np.all(eig.real < 0, axis=1)
    outside = np.abs(psi - 1.0) > SETTLING
    last = n - np.argmax(outside[:, ::-1], axis=1)
    settled = ~outside[:, -1] & stable
    ts = np.where(settled, t[np.minimum(last, n)], np.nan)
    os_ = np.where(settled, np.maximum(psi.max(axis=1) - 1.0, 0.0) * 100.0, np.nan)
    zeta = np.where(stable, np.minimum(-lead.real / np.abs(lead), 1.0), np.nan)
    shape = KP.shape
    return os_.reshape(shape), ts.reshape(shape), zeta.reshape(shape)


def paper_gains_map(speed: float = 1.0, *, side: str = "port", kp_grid=None, kd_grid=None,
                    vessel: str = DEFAULT_VESSEL) -> GainMap:
    """Where the paper's K_p = 3.5, K_d = 4 sit on the linear model at ``speed``, and a (K_p, K_d) grid map.

    Parameters
    ----------
    speed : float
        Fraction of the hull's design speed, in [0.2, 1.2].
    side : {"port", "starboard", "mean"}
        Side of the linearisation.
    kp_grid : array_like, optional
        K_p values of the map; 40 points over [0.1, 6] by default.
    kd_grid : array_like, optional
        K_d values of the map; 41 points over [0, 8] by default.
    vessel : str or pathlib.Path
        The hull: a name of :data:`~mmg_casadi.vessel.library.VESSELS` or a vessel .toml file (default the KCS).

    Returns
    -------
    GainMap
        The paper's gains analysed (:func:`~tuning.pd.design.analyse_gains`), the grids and the step metrics over
        them.

    Examples
    --------
    >>> g = paper_gains_map(1.0, kp_grid=[1.0, 3.5], kd_grid=[2.0, 4.0])
    >>> g.paper.loop.stable, round(g.paper.loop.dominant_zeta, 2), round(float(g.overshoot[1, 1]), 1)
    (True, 0.32, 10.9)
    """
    model = yaw_subsystem(speed, side, vessel=vessel)
    paper = analyse_gains(*PAPER_GAINS, model)
    kp_grid = np.linspace(0.1, 6.0, 40) if kp_grid is None else np.asarray(kp_grid, float)
    kd_grid = np.linspace(0.0, 8.0, 41) if kd_grid is None else np.asarray(kd_grid, float)
    os_, ts, zeta = grid_step_metrics(model, kp_grid, kd_grid)
    return GainMap(paper, kp_grid, kd_grid, os_, ts, zeta)
