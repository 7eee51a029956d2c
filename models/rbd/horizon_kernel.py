"""The compiled Euler nodes of a range ``t0 <= t < t1`` in one call each (:class:`.euler_horizon.EulerHorizon`).

The node tables are stacked (``tbls[t]``), their integers and parameters concatenated (``ints[ioff[t]:ioff[t+1]]``,
``par[poff[t]:poff[t+1]]``), and the trajectories arrive as address arrays (``xs[t]`` the address of state t).
Each function loops over the range and calls the single-node kernels of :mod:`.euler_node_kernel`; each node's
cost goes into ``costs[t]`` and the functions return their sum, added in node order.  The evaluations release the
GIL (several threads may run disjoint ranges at once, :mod:`.node_threads`).
"""

from __future__ import annotations

import math

from crocopy.costs.stack_kernel import stack_values
from crocopy.kernels import matrix_at, uncounted, vector_at

from .configuration_kernel import state_diff
from .euler_node_kernel import node_calc, node_calc_diff, node_rollout_step
from .node_table import (
    E_ACT_KINDS,
    E_ACT_PARAMS,
    E_ACT_WEIGHTS,
    E_ITEM_COSTS,
    E_ITEM_WEIGHTS,
    E_LB,
    E_R,
    E_STAMP,
    E_UB,
    E_XNEXT,
    N_STACK,
    NQ,
    NV,
    STARTS,
    entry_model,
    ivec,
    vec,
)


@uncounted
def horizon_rollout(tbls, ints, ioff, par, poff, xs, us, xs_try, us_try, dxs, ks, Ks, fs, lbs, ubs, nus, nx, ndx,
                    alpha, gaps, gap_at, t0, t1, costs):
    """:func:`node_rollout_step` over the running nodes ``t0 <= t < t1`` in one call; returns the sum of their costs
    (each into ``costs[t]``).

    Node ``t``'s table is ``tbls[t]``, its integers ``ints[ioff[t]:ioff[t+1]]``, its parameters
    ``par[poff[t]:poff[t+1]]``; the trajectories, gains, gaps and bounds arrive as addresses (``xs[t]`` the
    address of the state ``t``, ...): states of size ``nx``, tangents ``ndx``, controls ``nus[t]``, ``K[t]``
    of shape ``(nus[t], ndx)``.  The gap of node ``t+1`` is kept open (``(α - 1) fs[t+1]``) when ``gaps`` or
    ``t + 1 == gap_at``.
    """
    total = 0.0
    for t in range(t0, t1):
        nu = nus[t]
        cost = node_rollout_step(
            tbls[t], ints[ioff[t]: ioff[t + 1]], par[poff[t]: poff[t + 1]], vector_at(xs[t], nx),
            vector_at(xs_try[t], nx), vector_at(us[t], nu), vector_at(ks[t], nu), matrix_at(Ks[t], nu, ndx), alpha,
            vector_at(lbs[t], nu), vector_at(ubs[t], nu), vector_at(us_try[t], nu), vector_at(dxs[t], ndx),
            vector_at(xs_try[t + 1], nx), vector_at(fs[t + 1], ndx), gaps or t + 1 == gap_at,
        )
        costs[t] = cost
        total += cost
    return total


@uncounted
def horizon_recost(tbls, ints, ioff, par, poff, nodes, costs):
    """The costs of the running ``nodes`` again from their cost stacks as they stand (after the rows of their Python
    residuals were written, :mod:`.python_residuals`), into ``costs[t]`` and the stack value of their stamps (a
    ``calcDiff`` at the same point reuses it); returns the change of their sum."""
    change = 0.0
    for t in nodes:
        tbl, node_ints = tbls[t], ints[ioff[t]: ioff[t + 1]]
        starts = node_ints[node_ints[STARTS]: node_ints[STARTS] + node_ints[N_STACK]]
        value = stack_values(
            vec(tbl, node_ints, E_R), vec(tbl, node_ints, E_LB), vec(tbl, node_ints, E_UB),
            vec(tbl, node_ints, E_ACT_WEIGHTS), starts, ivec(tbl, node_ints, E_ACT_KINDS),
            vec(tbl, node_ints, E_ACT_PARAMS), vec(tbl, node_ints, E_ITEM_COSTS), vec(tbl, node_ints, E_ITEM_WEIGHTS),
        )
        stamp = vec(tbl, node_ints, E_STAMP)
        if stamp.shape[0] and stamp[0] == 1.0:
            stamp[1] = value
        cost = par[poff[t]] * value
        change += cost - costs[t]
        costs[t] = cost
    return change


def _horizon_calc_diff(tbls, ints, ioff, par, poff, xs, us, nus, nx, ndx, gaps, fs, t0, t1, costs):
    """:func:`node_calc_diff` over the running nodes ``t0 <= t < t1`` in one call (tables as in
    :func:`horizon_rollout`); returns the sum of their costs (each into ``costs[t]``).  With ``gaps``, also
    the gaps ``fs[t+1] = xnext_t ⊖ xs[t+1]``."""
    total = 0.0
    for t in range(t0, t1):
        tbl, node_ints = tbls[t], ints[ioff[t]: ioff[t + 1]]
        x = vector_at(xs[t], nx)
        cost = node_calc_diff(tbl, node_ints, par[poff[t]: poff[t + 1]], x, vector_at(us[t], nus[t]))
        costs[t] = cost
        total += cost
        if gaps:
            rb = entry_model(tbl, node_ints)
            x_next = vector_at(xs[t + 1], nx)
            state_diff(rb.jtype, rb.idx_q, rb.idx_v, node_ints[NQ], node_ints[NV], x_next,
                       vec(tbl, node_ints, E_XNEXT), vector_at(fs[t + 1], ndx))
    return total


horizon_calc_diff = uncounted(_horizon_calc_diff, nogil=True)


@uncounted
def calc_diff_all(tbls, ints, ioff, par, poff, xs, us, nus, nx, ndx, gaps, fs, T, costs, ttbl, tints, tpar, no_control,
                  out):
    """:func:`horizon_calc_diff` over every running node (``0 <= t < T``), then the terminal node's
    :func:`node_calc_diff` at ``xs[T]`` (tables ``ttbl, tints, tpar``, the empty control ``no_control``) into
    ``out[0]``; returns the running nodes' total (not finite: the terminal node is not evaluated)."""
    total = horizon_calc_diff(tbls, ints, ioff, par, poff, xs, us, nus, nx, ndx, gaps, fs, 0, T, costs)
    if math.isfinite(total):
        out[0] = node_calc_diff(ttbl, tints, tpar, vector_at(xs[T], nx), no_control)
    return total


def _horizon_calc(tbls, ints, ioff, par, poff, xs, us, nus, nx, t0, t1, costs):
    """:func:`node_calc` over the running nodes ``t0 <= t < t1`` in one call (tables as in :func:`horizon_rollout`,
    ``xs``/``us`` addresses); returns the sum of their costs (each into ``costs[t]``)."""
    total = 0.0
    for t in range(t0, t1):
        cost = node_calc(tbls[t], ints[ioff[t]: ioff[t + 1]], par[poff[t]: poff[t + 1]], vector_at(xs[t], nx),
                         vector_at(us[t], nus[t]))
        costs[t] = cost
        total += cost
    return total


horizon_calc = uncounted(_horizon_calc, nogil=True)


@uncounted
def fold(costs, t0, t1):
    """The sum of ``costs[t0:t1]`` added in node order (as :func:`horizon_calc_diff` adds it)."""
    total = 0.0
    for t in range(t0, t1):
        total += costs[t]
    return total
