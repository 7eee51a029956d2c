"""The trial point of SolverSQP/SolverCSQP over a range of compiled Euler nodes, in one call
(:class:`.euler_horizon.EulerHorizon` ``.trial``; :meth:`crocopy.solvers.compiled_nodes.CompiledNodes.trial`).

On the straight line of the QP step ``(δx, δu)`` at step length ``α``, for the running nodes ``t0 <= t < t1`` ::

    x̂_t = x_t ⊕ α δx_t,   û_t = u_t + α δu_t,   (cost_t, xnext_t) = node_t(x̂_t, û_t),   f̂_{t+1} = xnext_t ⊖ x̂_{t+1}

(``f̂_0 = x0 ⊖ x̂_0`` too when ``t0 = 0``).  Tables as in :mod:`.horizon_kernel` (``tbls[t]``, ``ints[ioff[t]:
ioff[t+1]]``, ``par[poff[t]:poff[t+1]]``); the trajectories ``xs, us, xs_try, us_try`` arrive as addresses (states of
size ``nx``, controls ``nus[t]``), the steps ``dx (T+1, n)``, ``du (T+1, m)`` and the trial gaps ``fs (T+1, n)`` as
the solver's padded stacks (tangents of size ``ndx``).  ``x̂_{t1}`` is read, not written: the caller integrates the
states outside the range first.  Each node's cost goes into ``costs[t]``; the functions return their sum, added in
node order (NaN where a node's acceleration is not finite: the caller evaluates it again on its Python path).
"""

from __future__ import annotations

import math

import numpy as np

from crocopy.kernels import compiled, uncounted, vector_at

from .configuration_kernel import state_diff, state_integrate
from .euler_node_kernel import node_calc, node_integrate
from .horizon_kernel import horizon_calc
from .node_table import E_XNEXT, NQ, NV, entry_model, vec


def _points(tbls, ints, ioff, xs, us, xs_try, us_try, nus, nx, ndx, dx, du, alpha, step, t0, t1):
    """``x̂_t = x_t ⊕ α δx_t`` and ``û_t = u_t + α δu_t`` for ``t0 <= t < t1`` (``step (ndx,)``: scratch)."""
    for t in range(t0, t1):
        node_ints = ints[ioff[t]: ioff[t + 1]]
        rb = entry_model(tbls[t], node_ints)
        for i in range(ndx):
            step[i] = alpha * dx[t, i]
        state_integrate(rb.jtype, rb.idx_q, rb.idx_v, node_ints[NQ], node_ints[NV], vector_at(xs[t], nx), step,
                        vector_at(xs_try[t], nx))
        u, u_try = vector_at(us[t], nus[t]), vector_at(us_try[t], nus[t])
        for i in range(nus[t]):
            u_try[i] = u[i] + alpha * du[t, i]


horizon_points = compiled(_points, nogil=True)


def _gaps(tbls, ints, ioff, x0, xs_try, nx, fs, t0, t1):
    """``f̂_{t+1} = xnext_t ⊖ x̂_{t+1}`` for ``t0 <= t < t1`` (node ``t``'s ``xnext`` as it stands), and
    ``f̂_0 = x0 ⊖ x̂_0`` when ``t0 = 0``."""
    for t in range(t0, t1):
        tbl, node_ints = tbls[t], ints[ioff[t]: ioff[t + 1]]
        rb = entry_model(tbl, node_ints)
        nq, nv = node_ints[NQ], node_ints[NV]
        if t == 0:
            state_diff(rb.jtype, rb.idx_q, rb.idx_v, nq, nv, vector_at(xs_try[0], nx), x0, fs[0])
        state_diff(rb.jtype, rb.idx_q, rb.idx_v, nq, nv, vector_at(xs_try[t + 1], nx), vec(tbl, node_ints, E_XNEXT),
                   fs[t + 1])


horizon_gaps = compiled(_gaps, nogil=True)


def _trial(tbls, ints, ioff, par, poff, x0, xs, us, xs_try, us_try, nus, nx, ndx, dx, du, alpha, fs, step, t0, t1,
           costs):
    """The whole trial of the range (module docstring) in one call; returns the sum of the nodes' costs."""
    horizon_points(tbls, ints, ioff, xs, us, xs_try, us_try, nus, nx, ndx, dx, du, alpha, step, t0, t1)
    total = horizon_calc(tbls, ints, ioff, par, poff, xs_try, us_try, nus, nx, t0, t1, costs)
    horizon_gaps(tbls, ints, ioff, x0, xs_try, nx, fs, t0, t1)
    return total


horizon_trial = compiled(_trial, nogil=True)


@uncounted
def trial_all(tbls, ints, ioff, par, poff, x0, xs, us, xs_try, us_try, nus, nx, ndx, dx, du, alpha, fs, step, T, costs,
              ttbl, tints, tpar, no_control, out):
    """``x̂_T = x_T ⊕ α δx_T`` (the terminal node's :func:`.euler_node_kernel.node_integrate`), :func:`horizon_trial`
    over every running node (``0 <= t < T``), then the terminal node at ``x̂_T`` into ``out[0]``; returns the running
    nodes' total (not finite: the terminal node is not evaluated)."""
    for i in range(ndx):
        step[i] = alpha * dx[T, i]
    node_integrate(ttbl, tints, vector_at(xs[T], nx), step[:ndx], vector_at(xs_try[T], nx))
    total = horizon_trial(tbls, ints, ioff, par, poff, x0, xs, us, xs_try, us_try, nus, nx, ndx, dx, du, alpha, fs,
                          step, 0, T, costs)
    if math.isfinite(total):
        out[0] = node_calc(ttbl, tints, tpar, vector_at(xs_try[T], nx), no_control)
    return total


def trial(horizon, addresses: tuple, x0: np.ndarray, dx: np.ndarray, du: np.ndarray, alpha: float, fs: np.ndarray,
          step: np.ndarray, trajectories: tuple, t0: int, t1: int) -> float:
    """``EulerHorizon.trial``: the trial point of the nodes ``t0 <= t < t1`` (module docstring); returns their total
    cost, each node's in ``horizon.costs[t]``.

    ``addresses``: of ``xs, us, xs_try, us_try``; ``dx``, ``du``, ``fs``: the solver's stacks; ``step``: scratch of at
    least ``ndx`` entries; ``trajectories``: the lists ``(xs_try, us_try, fs)`` (views of the same arrays) for the
    Python paths.  One compiled call on one thread without Python residuals in the range (for a horizon whose
    ``fused_trial`` is true: the Euler nodes'); otherwise the states and
    controls, then :meth:`~.euler_horizon.EulerHorizon.calc` (which runs those residuals and the threads), then the
    gaps.  A node whose acceleration is not finite is evaluated again on its Python path, its gap from there."""
    xs, us, xs_at, us_at = addresses
    xs_try, us_try, fs_list = trajectories
    tables = horizon.tbls, horizon.ints, horizon.ioff
    nus, nx, ndx = horizon.nus, horizon.nx, horizon.ndx
    if horizon.fused_trial and horizon.threads is None and not any(t0 <= t < t1 for t, _ in horizon.python):
        total = horizon_trial(*tables, horizon.par, horizon.poff, x0, xs, us, xs_at, us_at, nus, nx, ndx, dx, du,
                              alpha, fs, step, t0, t1, horizon.costs)
        return total if math.isfinite(total) else horizon._python_path(xs_try, us_try, fs_list, t0, t1, False)
    horizon_points(*tables, xs, us, xs_at, us_at, nus, nx, ndx, dx, du, alpha, step, t0, t1)
    total = horizon.calc(xs_try, us_try, xs_at, us_at, t0, t1)
    horizon_gaps(*tables, x0, xs_at, nx, fs, t0, t1)
    return total
