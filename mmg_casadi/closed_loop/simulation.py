"""Compiled rollouts of the closed loop: one scenario with its full history, or a batch keeping final states.

The closed-loop step is compiled once per :class:`~mmg_casadi.closed_loop.layout.Layout` (native code, cached on disk)
and rolled out with ``mapaccum`` in chunks of steps; a rollout stops after the chunk in which every ship has
finished (reached its goal or diverged) or the horizon ``t_max`` (a step parameter) is reached.
"""

from __future__ import annotations

import csv
import time
from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from mmg_casadi.io import atomic_open, atomic_path, csv_cell
from mmg_casadi.compiled import compile_function, library_is_trusted, library_path, load_library
from mmg_casadi.closed_loop.fleet import build_fleet_step, candidate_radius, neighbour_lists
from mmg_casadi.closed_loop.layout import Layout
from mmg_casadi.errors import InputError
from mmg_casadi.closed_loop.state import ship_rows
from mmg_casadi.closed_loop.step import AUX, build_closed_loop_step, build_guidance
from mmg_casadi.guidance import methods
from mmg_casadi.guidance.methods import forget_on_unregister


def rollout_functions(layout: Layout) -> list[ca.Function]:
    """The closed-loop step and guidance Functions that rollouts of ``layout`` compile into one library: the
    sparse ones (:func:`~mmg_casadi.closed_loop.step.build_closed_loop_step`) for an exact layout, else the dense.

    Parameters
    ----------
    layout : Layout
        Closed-loop layout (ships, obstacles, walls, method) of the Functions.

    Returns
    -------
    list of casadi.Function
        ``[fleet step]`` for a fleet layout, else ``[closed-loop step, guidance]`` (sparse for an exact layout).
    """
    if layout.neighbours:
        return [build_fleet_step(layout)]
    sparse = layout.smooth is None
    return [build_closed_loop_step(layout, sparse=sparse), build_guidance(layout, sparse=sparse)]


_LIBRARIES: dict[Layout, tuple[ca.Function, ...]] = {}
"""Compiled Functions loaded by this process, by layout (the most recent :data:`MAX_LOADED`)."""
MAX_LOADED = 64
"""Layouts whose compiled Functions this process keeps loaded."""


def _keep(layout: Layout, compiled) -> tuple[ca.Function, ...]:
    _LIBRARIES[layout] = tuple(compiled)
    while len(_LIBRARIES) > MAX_LOADED:
        del _LIBRARIES[next(iter(_LIBRARIES))]
    return _LIBRARIES[layout]


def describe(layout: Layout) -> str:
    """What a rollout of ``layout`` compiles, in words (the notice of :data:`mmg_casadi.compiled.NOTICES`).

    Parameters
    ----------
    layout : Layout
        Closed-loop layout.

    Returns
    -------
    str
        For example ``"closed loop for 3 ships (modified-vortex)"``.
    """
    n = layout.n_ships
    kind = "fleet step" if layout.neighbours else "closed loop"
    return f"{kind} for {n} ship{'s' if n != 1 else ''} ({', '.join(dict.fromkeys(layout.methods))})"


def _library(layout: Layout) -> tuple[ca.Function, ...]:
    if layout in _LIBRARIES:
        return _LIBRARIES[layout]
    step, *also = rollout_functions(layout)
    compiled = compile_function(step, also=also, label=describe(layout))
    return _keep(layout, compiled if also else [compiled])


_library.cache_clear = _LIBRARIES.clear  # as an lru_cache's: forgets the loaded libraries (unregister, tests)


def load_if_cached(layout: Layout) -> bool:
    """Load the compiled library of ``layout`` if the disk cache holds it (trusted), and say whether it did.

    The Functions are built and their C source generated once for both the test and the loading (a study's
    start tests every layout it needs before compiling the missing ones,
    :func:`~mmg_casadi.montecarlo.batching.prepare_layouts`).

    Parameters
    ----------
    layout : Layout
        Closed-loop layout.

    Returns
    -------
    bool
        True if the library is loaded (now or before), False if it must be compiled.
    """
    if layout in _LIBRARIES:
        return True
    step, *also = rollout_functions(layout)
    so, _src = library_path(step, also=also)
    if not library_is_trusted(so):
        return False
    _keep(layout, load_library(so, [f.name() for f in (step, *also)]))
    return True


def compiled_step(layout: Layout) -> ca.Function:
    """Natively compiled closed-loop step for ``layout`` (memoised in-process, cached on disk).

    Parameters
    ----------
    layout : Layout
        Closed-loop layout (ships, obstacles, walls, method) of the Function.

    Returns
    -------
    casadi.Function
        The step ``(x, p) -> (x_next, aux)`` loaded from the compiled library.
    """
    return _library(layout)[0]


def compiled_guidance(layout: Layout) -> ca.Function:
    """Natively compiled guidance-only Function for ``layout`` (for timing guidance calls; the same library as
    :func:`compiled_step`).

    Parameters
    ----------
    layout : Layout
        Closed-loop layout (ships, obstacles, walls, method) of the Function (not a fleet layout).

    Returns
    -------
    casadi.Function
        ``guidance_<key>(x, p) -> delta_c (1 x N)`` (rad) loaded from the compiled library.
    """
    _check_unrolled(layout, "compiled_guidance")
    return _library(layout)[1]


def _check_unrolled(layout: Layout, what: str) -> None:
    if layout.neighbours:
        raise InputError(what, "a layout of the unrolled step (a fleet layout is rolled out by simulate only)",
                         f"{layout.n_ships} ships with {layout.neighbours} neighbour slots")


FLEET_CHUNK = 4
"""Steps per compiled call of a fleet rollout: the neighbour lists are renewed between calls, and the candidate
radius grows with the chunk (:func:`~mmg_casadi.closed_loop.fleet.candidate_radius`)."""


@lru_cache(maxsize=64)
def _chunk(layout: Layout, chunk: int, batch: int) -> ca.Function:
    step = compiled_step(layout)
    if batch > 1:
        step = step.map(batch)
    return step.mapaccum(chunk)


@lru_cache(maxsize=64)
def _scenario_chunk(layout: Layout, chunk: int, every: int) -> ca.Function:
    """``chunk`` steps of one scenario returning its final state and, every ``every`` steps, the time and the
    :data:`HISTORY_STATE` rows of every ship (``(1 + 4 N, chunk // every)``); ``every = 0``: the final state only.

    A batch maps this over its scenarios (:func:`_chunk_final`, :func:`_chunk_history`): one scenario's ``chunk``
    steps after the other's, so the work memory holds one scenario's steps, not the batch's (the steps and their
    arithmetic are those of ``compiled_step(layout).map(batch).mapaccum(chunk)``, the results the same to the bit).
    """
    F = compiled_step(layout).mapaccum(chunk)
    x = ca.MX.sym("x", layout.nx)
    p = ca.MX.sym("p", layout.np)
    X, _ = F(x, p)
    outputs = [X[:, -1]]
    if every:
        rows = [0] + [layout.row(name, i) for i in range(layout.n_ships) for name in HISTORY_STATE]
        outputs.append(X[rows, list(range(every - 1, chunk, every))])
    return ca.Function(f"chunk_one_{layout.key()}_{chunk}_{every}", [x, p], outputs)


def _chunk_final(layout: Layout, chunk: int, batch: int) -> ca.Function:
    """``chunk`` steps of a batch returning only the final states (no history copied out of compiled code)."""
    f = _scenario_chunk(layout, chunk, 0)
    return f.map(batch) if batch > 1 else f


class _Bound:
    """A dense Function called through CasADi's buffer interface: its inputs and outputs are numpy arrays bound
    once, so a call copies the inputs in and the outputs out without converting to and from ``DM``."""

    def __init__(self, f: ca.Function):
        self.f = f
        self.buf, self.trigger = f.buffer()
        self.args = [np.zeros(f.nnz_in(i)) for i in range(f.n_in())]
        self.res = [np.zeros(f.nnz_out(i)) for i in range(f.n_out())]
        self.shapes = [f.size_out(i) for i in range(f.n_out())]
        for i, a in enumerate(self.args):
            self.buf.set_arg(i, memoryview(a))
        for i, r in enumerate(self.res):
            self.buf.set_res(i, memoryview(r))

    def __call__(self, *inputs) -> list[np.ndarray]:
        for a, x in zip(self.args, inputs):
            a[:] = np.asarray(x, float).ravel(order="F")
        self.trigger()
        return [r.reshape(shape, order="F").copy() for r, shape in zip(self.res, self.shapes)]


@lru_cache(maxsize=256)
def _bound(kind: str, layout: Layout, chunk: int, batch: int, every: int = 1) -> _Bound:
    f = _chunk_final(layout, chunk, batch) if kind == "final" else _chunk_history(layout, chunk, batch, every)
    return _Bound(f)


HISTORY_STATE: tuple[str, ...] = ("x", "y", "psi", "status")
"""Ship state variables kept by :func:`simulate_batch_history`."""


def _chunk_history(layout: Layout, chunk: int, batch: int, every: int) -> ca.Function:
    """``chunk`` steps of a batch returning the final states and, every ``every`` steps, the time and the
    :data:`HISTORY_STATE` rows of every ship (``(1 + 4 N, batch * (chunk // every))``, scenario-major blocks)."""
    f = _scenario_chunk(layout, chunk, every)
    return f.map(batch) if batch > 1 else f


def _finished(layout: Layout, x: np.ndarray, t_max) -> np.ndarray:
    """Per column of scenario states: every ship has stopped sailing, or that column's horizon is reached."""
    x = np.atleast_2d(x.T).T
    status = x[layout.rows("status"), :]
    return np.all(status != 0, axis=0) | (x[0] >= np.asarray(t_max) - 1e-9)


def sailing_mask(status) -> np.ndarray:
    """``(K, N)`` True while a ship sails (status 0), and at the sample at which it stopped.

    Parameters
    ----------
    status : array (K, N)
        Status history (0 sailing, 1 reached, 2 diverged).

    Returns
    -------
    numpy.ndarray of bool (K, N)
        True where the ship sails, and at the first sample of each ship that stopped.

    Examples
    --------
    >>> sailing_mask(np.array([[0, 0], [0, 1], [1, 1]])).astype(int).tolist()
    [[1, 1], [1, 1], [1, 0]]
    """
    status = np.asarray(status)
    mask = status == 0
    first_stop = np.argmax(~mask, axis=0)
    for i, k in enumerate(first_stop):
        if not mask[:, i].all():
            mask[k, i] = True
    return mask


@dataclass
class Trajectory:
    """History of one closed-loop rollout.

    Parameters
    ----------
    layout : Layout
        Shape of the closed loop.
    t : ndarray (T+1,)
        Times of the stored states (non-dimensional).
    states : ndarray (T+1, N, ns)
        Ship states, columns named by :attr:`~mmg_casadi.closed_loop.layout.Layout.ship_state`.
    aux : ndarray (T, N, 4)
        Commanded rudder, desired heading, cross-track error and reactive flag used over each step.
    neighbour_overflows : int, default 0
        Fleet step only: how many times a ship had more candidate neighbours than slots and kept the nearest
        (:func:`~mmg_casadi.closed_loop.fleet.neighbour_lists`); 0 means every step was exact.
    """

    layout: Layout
    t: np.ndarray
    states: np.ndarray
    aux: np.ndarray
    neighbour_overflows: int = 0

    def state(self, name: str, ship: int | None = None) -> np.ndarray:
        """History of one state variable, ``(T+1, N)`` or ``(T+1,)`` for one ship.

        Parameters
        ----------
        name : str
            A name of :attr:`~mmg_casadi.closed_loop.layout.Layout.ship_state`.
        ship : int, optional
            Ship index; all ships if omitted.

        Returns
        -------
        numpy.ndarray
            Values at the times :attr:`t`, in the units of the state (L, rad, U_des, L/U...).
        """
        col = self.states[:, :, self.layout.column(name)]
        return col if ship is None else col[:, ship]

    def auxiliary(self, name: str, ship: int | None = None) -> np.ndarray:
        """History of one auxiliary signal, ``(T, N)`` or ``(T,)`` for one ship.

        Parameters
        ----------
        name : str
            ``delta_c``, ``psi_d``, ``y_e`` or ``reactive``.
        ship : int, optional
            Ship index; all ships if omitted.

        Returns
        -------
        numpy.ndarray
            Values over each step: ``delta_c``, ``psi_d`` (rad), ``y_e`` (L) or ``reactive`` (1/0).
        """
        col = self.aux[:, :, AUX.index(name)]
        return col if ship is None else col[:, ship]

    @property
    def final(self) -> np.ndarray:
        """Final ship states ``(N, ns)``."""
        return self.states[-1]

    def sailing_mask(self) -> np.ndarray:
        """``(T+1, N)`` True while a ship is still sailing (:func:`sailing_mask` of its status history).

        Returns
        -------
        numpy.ndarray of bool (T+1, N)
            The mask, True also at the sample at which a ship stopped.
        """
        return sailing_mask(self.state("status"))

    def to_npz(self, path) -> None:
        """Save times, states and auxiliary signals (with their names) as a compressed ``.npz``.

        Parameters
        ----------
        path : str or Path
            Destination file.
        """
        with atomic_path(path) as tmp:  # the suffix is kept: ".npz" is not added a second time
            np.savez_compressed(tmp, t=self.t, states=self.states, aux=self.aux,
                                state_names=np.array(self.layout.ship_state), aux_names=np.array(AUX))

    def to_csv(self, path, names=None) -> None:
        """Long-format CSV: one row per (time, ship) with the MMG state and the auxiliary signals.

        Parameters
        ----------
        path : str or Path
            Destination file.
        names : list of str, optional
            Ship names (default ``ship0``, ``ship1``, ...).
        """
        names = names or [f"ship{i}" for i in range(self.layout.n_ships)]
        cols = ["u", "v", "r", "x", "y", "psi", "delta", "status"]
        aux = np.concatenate([self.aux, self.aux[-1:]], axis=0) if len(self.aux) else np.zeros(
            (len(self.t), self.layout.n_ships, len(AUX)))
        cells = [csv_cell(n) for n in names]  # quoted by the csv module; never read as a spreadsheet formula
        with atomic_open(path, "w", encoding="utf-8", newline="") as fh:
            w = csv.writer(fh, lineterminator="\n")
            w.writerow(["t", "ship"] + cols + list(AUX))
            for k, tk in enumerate(self.t):
                for i in range(self.layout.n_ships):
                    vals = [self.states[k, i, self.layout.column(c)] for c in cols] + list(aux[k, i])
                    w.writerow([f"{tk:.4f}", cells[i], *(f"{v:.6g}" for v in vals)])


def simulate(layout: Layout, x0: np.ndarray, p: np.ndarray, *, chunk: int = 200, commands=None) -> Trajectory:
    """Roll out one scenario until every ship has finished or ``t_max`` (in ``p``) is reached.

    Parameters
    ----------
    layout : Layout
        Shape of the closed loop.
    x0 : ndarray (nx,)
        Initial scenario state (:func:`~mmg_casadi.closed_loop.state.initial_state`).
    p : ndarray (np,)
        Parameter vector (:func:`~mmg_casadi.closed_loop.layout.pack_params`).
    chunk : int
        Steps per compiled ``mapaccum`` call.
    commands : array_like, optional
        Orders of the commanded ships (``Layout.commanded``),
        one row per guidance step: ``(K, C)`` headings (rad) or, with ``Layout.command_rpm``, ``(K, C, 2)``
        headings and propeller speeds (rev/min). Each step writes its row into the ships' ``command_heading`` /
        ``command_rpm`` state rows and calls the same compiled step as without commands (which carries the rows
        on: sample ``k + 1`` holds the orders of step ``k``), so the rollout equals stepping
        :mod:`mmg_casadi.gym`'s environment with those actions to the bit; it ends after ``K`` steps (or earlier,
        as without commands). Without ``commands`` a commanded ship holds the orders of ``x0``.

    Returns
    -------
    Trajectory
        The history, up to the sample at which the last ship finished or ``t_max`` was reached.
    """
    if commands is not None:
        return _simulate_commands(layout, x0, p, commands)
    fleet = layout.neighbours > 0
    if fleet:
        chunk = FLEET_CHUNK
        radius = candidate_radius(_look_radius(layout, p), float(p[layout.param_index("dt")]), chunk)
    F = _chunk(layout, chunk, 1)
    t_max = float(p[layout.param_index("t_max")])
    xs, auxs = [np.asarray(x0, float)[:, None]], []
    x = np.asarray(x0, float)
    overflow = 0
    while not _finished(layout, x, t_max)[0]:
        if fleet:
            nbr, over = neighbour_lists(layout, x, p, radius)
            overflow += over
            Xc, Ac = F(x, p, nbr)
        else:
            Xc, Ac = F(x, p)
        Xc = np.array(Xc)
        # mapaccum stacks the (NAUX, N) output of each step horizontally: step-major blocks of N columns
        Ac = np.array(Ac).reshape(len(AUX), chunk, layout.n_ships)
        xs.append(Xc)
        auxs.append(np.transpose(Ac, (1, 2, 0)))
        x = Xc[:, -1]
    X = np.concatenate(xs, axis=1)
    A = np.concatenate(auxs, axis=0) if auxs else np.zeros((0, layout.n_ships, len(AUX)))
    # drop the frozen tail after the horizon / after the last ship finished
    t = X[0]
    stop = len(t) - 1
    fin = _finished(layout, X, t_max)
    if fin.any():
        stop = int(np.argmax(fin))
    X, A = X[:, :stop + 1], A[:stop]
    states = ship_rows(layout, X)
    return Trajectory(layout, X[0].copy(), states, A, overflow)


def _look_radius(layout: Layout, p) -> float:
    """The farthest a ship's method sees its neighbours (L): R_safe, or R_safe plus a lookout, or a method's own
    sensing range (:class:`~mmg_casadi.guidance.contract.Method`), the largest over the layout's methods."""
    r_safe = float(p[layout.param_index("r_safe")])
    ranges = [r_safe]
    named = None
    for name in dict.fromkeys(layout.methods):
        spec = methods.get(name)
        if spec.lookout or spec.sensing:
            named = named or layout.split_params(ca.DM(np.asarray(p, float)))
            ranges.append(r_safe + float(named[spec.lookout]) if spec.lookout else float(named[spec.sensing]))
    return max(ranges)


def command_rows(layout: Layout) -> list[list[int]]:
    """State rows of the commanded ships' orders: per commanded ship ``[command_heading]`` or, with
    ``command_rpm``, ``[command_heading, command_rpm]``.

    Parameters
    ----------
    layout : Layout
        A layout with commanded ships.

    Returns
    -------
    list of list of int
        Row indices of the scenario state, one list per commanded ship.
    """
    names = ("command_heading", "command_rpm")[:1 + int(layout.command_rpm)]
    return [[layout.row(k, i) for k in names] for i in layout.commanded]


def stepper(layout: Layout, batch: int = 1):
    """The compiled closed-loop step of ``layout`` (:func:`compiled_step`) as a function of numpy arrays, mapped over
    ``batch`` scenario columns: ``(x (nx, batch), p (np, batch)) -> (x_next (nx, batch), aux (NAUX, N batch))``.

    Parameters
    ----------
    layout : Layout
        An unrolled layout.
    batch : int, default 1
        Columns stepped by one call (CasADi's ``map`` of the compiled step: each column runs the same compiled
        code as a single step).

    Returns
    -------
    callable
        The step, bound to numpy buffers (no conversion to ``DM`` per call).
    """
    _check_unrolled(layout, "stepper")
    return _stepper(layout, int(batch))


@lru_cache(maxsize=32)
def _stepper(layout: Layout, batch: int) -> _Bound:
    f = compiled_step(layout)
    return _Bound(f if batch == 1 else f.map(batch))


def _simulate_commands(layout: Layout, x0, p, commands) -> Trajectory:
    """:func:`simulate` with per-step orders of the commanded ships, one compiled step per order."""
    rows = command_rows(layout)
    if not rows:
        raise InputError("commands", "nothing for a layout without commanded ships (Layout.commanded)",
                         np.shape(commands))
    cmd = np.asarray(commands, float)
    want = (len(rows),) if not layout.command_rpm else (len(rows), 2)
    if cmd.ndim == 1 and want == (1,):  # one ship's headings
        cmd = cmd[:, None]
    if cmd.ndim != 1 + len(want) or cmd.shape[1:] != want or not np.all(np.isfinite(cmd)):
        raise InputError("commands", f"finite orders of shape (steps, {', '.join(map(str, want))})", cmd.shape)
    step = stepper(layout)
    t_max = float(p[layout.param_index("t_max")])
    x = np.asarray(x0, float).copy()
    p = np.asarray(p, float)
    xs, auxs = [x.copy()], []
    for k in range(cmd.shape[0]):
        if _finished(layout, x, t_max)[0]:
            break
        for j, r in enumerate(rows):
            x[r] = cmd[k, j]
        x, aux = step(x, p)
        x = x.ravel()
        xs.append(x.copy())
        auxs.append(aux.reshape(len(AUX), layout.n_ships).T)
    X = np.column_stack(xs)
    A = np.stack(auxs) if auxs else np.zeros((0, layout.n_ships, len(AUX)))
    return Trajectory(layout, X[0].copy(), ship_rows(layout, X), A, 0)


DEFAULT_WIDTH = 32
"""Scenarios stepped side by side by :func:`simulate_batch` (columns of one compiled ``map``)."""


def simulate_batch(layout: Layout, X0: np.ndarray, P: np.ndarray, *, chunk: int = 100,
                   width: int | None = DEFAULT_WIDTH) -> tuple[np.ndarray, float]:
    """Roll out ``M`` scenarios of one layout (columns of ``X0`` (nx, M) and ``P`` (np, M)) to their ends.

    At most ``width`` scenarios are stepped side by side, ``chunk`` steps per compiled call; after every call the
    scenarios that finished leave the batch and waiting ones take their columns (when none wait, the batch
    shrinks), so no compiled work is spent on finished scenarios beyond the chunk in which they finished.
    Every column is computed independently, so the final states do not depend on ``width`` or ``chunk``.

    Parameters
    ----------
    layout : Layout
        Shape of the closed loop shared by all scenarios.
    X0 : ndarray (nx, M)
        Initial scenario states.
    P : ndarray (np, M)
        Parameter vectors (each column its own horizon ``t_max``).
    chunk : int
        Steps per compiled call.
    width : int, optional
        Scenarios stepped together (``None``: all ``M``).

    Returns
    -------
    tuple
        Final scenario states ``(nx, M)`` and the wall time spent in compiled code (s).
    """
    def call(x, p, active):
        return _bound("final", layout, chunk, len(active))(x, p)[0]

    return _stream(layout, X0, P, width, call)


def _bucket(n: int, width: int) -> int:
    """Columns of the compiled call for ``n`` running scenarios: the next power of two, at most ``width`` (so a
    draining batch reuses a few compiled widths instead of building one per count)."""
    return min(width, 1 << (n - 1).bit_length())


def _stream(layout: Layout, X0, P, width, call) -> tuple[np.ndarray, float]:
    """Step the columns of ``X0`` / ``P`` at most ``width`` at a time with ``call(x, p, active) -> x_next``
    (``active``: the original column indices of ``x``, -1 for padding); a column that finished leaves the batch
    and a waiting one takes its place. Returns the final states and the time spent in ``call``."""
    _check_unrolled(layout, "simulate_batch")
    X0 = np.asarray(X0, float)
    P = np.asarray(P, float)
    M = X0.shape[1]
    width = M if width is None else max(1, min(int(width), M))
    t_row = layout.param_index("t_max")
    out = X0.copy()
    active = [j for j in range(M) if not _finished(layout, X0[:, j:j + 1], P[t_row, j])[0]]
    pending = active[width:]
    active = active[:width]
    x, p = X0[:, active], P[:, active]
    busy = 0.0
    while active:
        t0 = time.perf_counter()
        n = len(active)
        b = _bucket(n, width)
        if b > n:  # pad to a width already built, with columns past their horizon (held: they cost nothing)
            pad_x, pad_p = np.repeat(x[:, :1], b - n, axis=1), np.repeat(p[:, :1], b - n, axis=1)
            pad_x[0] = pad_p[t_row]
            x = call(np.hstack([x, pad_x]), np.hstack([p, pad_p]), active + [-1] * (b - n))[:, :n]
        else:
            x = call(x, p, active)
        busy += time.perf_counter() - t0
        done = _finished(layout, x, p[t_row])
        if not done.any():
            continue
        out[:, [active[k] for k in np.flatnonzero(done)]] = x[:, done]
        keep = np.flatnonzero(~done)
        active = [active[k] for k in keep]
        x, p = x[:, keep], p[:, keep]
        n_new = min(len(pending), width - len(active))
        if n_new:
            new, pending = pending[:n_new], pending[n_new:]
            active += new
            x = np.hstack([x, X0[:, new]])
            p = np.hstack([p, P[:, new]])
    return out, busy


@dataclass
class BatchHistory:
    """Decimated history of a batch rollout (:func:`simulate_batch_history`).

    Parameters
    ----------
    t : list of ndarray (K_m,)
        Per scenario, the time of each kept sample (the initial state first).
    states : list of ndarray (K_m, N, 4)
        Per scenario, ``x``, ``y``, ``psi`` and ``status`` (:data:`HISTORY_STATE`) of every ship.
    """

    t: list
    states: list

    def column(self, m: int) -> tuple[np.ndarray, np.ndarray]:
        """Times ``(K,)`` and ship states ``(K, N, 4)`` of scenario ``m``, up to its last advancing sample.

        Parameters
        ----------
        m : int
            Column (scenario) index.

        Returns
        -------
        t : numpy.ndarray (K,)
            Sample times (L/U).
        states : numpy.ndarray (K, N, 4)
            Per sample and ship: x, y (L), heading (rad) and status.
        """
        t = self.t[m]
        last = int(np.argmax(t)) + 1  # the clock stops at the horizon; later samples repeat the final state
        return t[:last], self.states[m][:last]


def simulate_batch_history(layout: Layout, X0: np.ndarray, P: np.ndarray, *, chunk: int = 100, every: int = 2,
                           width: int | None = DEFAULT_WIDTH) -> tuple[np.ndarray, float, BatchHistory]:
    """:func:`simulate_batch` that also keeps the time, position, heading and status of every ship every
    ``every`` guidance steps (from the compiled ``mapaccum`` outputs; ``chunk`` must be a multiple of ``every``).

    Returns the final scenario states ``(nx, M)``, the wall time spent in compiled code (s) and the
    :class:`BatchHistory` (the initial state is its first sample). Finished scenarios leave the batch as in
    :func:`simulate_batch`.

    Parameters
    ----------
    layout : Layout
        Shape of the closed loop.
    X0, P : ndarray (nx, M), (np, M)
        Initial states and parameter vectors, one column per scenario.
    chunk : int
        Steps per compiled call.
    every : int
        Keep every ``every``-th step.
    width : int, optional
        Scenarios stepped together (``None``: all ``M``).

    Returns
    -------
    X : numpy.ndarray (nx, M)
        Final scenario states, one column per scenario.
    busy : float
        Wall time spent in compiled code (s).
    history : BatchHistory
        Times and ship states every ``every`` steps, the initial state first.
    """
    if isinstance(every, bool) or not isinstance(every, int) or every < 1 or chunk % every:
        raise ValueError(f"every: expected an integer >= 1 dividing chunk={chunk}, got {every!r}")
    _check_unrolled(layout, "simulate_batch_history")
    X0 = np.asarray(X0, float)
    M, N = X0.shape[1], layout.n_ships
    rows = [0] + [layout.row(name, i) for i in range(N) for name in HISTORY_STATE]
    hist: list[list[np.ndarray]] = [[X0[rows, j][None, :]] for j in range(M)]

    def call(x, p, active):
        xf, H = _bound("history", layout, chunk, len(active), every)(x, p)
        H = H.reshape(len(rows), len(active), chunk // every)  # scenario-major blocks of chunk // every columns
        for k, j in enumerate(active):
            if j >= 0:
                hist[j].append(H[:, k, :].T)
        return np.array(xf)

    out, busy = _stream(layout, X0, P, width, call)
    t, states = [], []
    for j in range(M):
        Hj = np.concatenate(hist[j], axis=0)  # (K_j, rows)
        t.append(Hj[:, 0])
        states.append(Hj[:, 1:].reshape(len(Hj), N, len(HISTORY_STATE)))
    return out, busy, BatchHistory(t, states)


forget_on_unregister(_library.cache_clear, _chunk.cache_clear, _scenario_chunk.cache_clear, _bound.cache_clear,
                     _stepper.cache_clear)
