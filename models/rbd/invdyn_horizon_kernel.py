"""The compiled inverse-dynamics nodes of a range ``t0 <= t < t1`` in one call each
(:class:`.invdyn_horizon.InvDynHorizon`).

The same loops as :mod:`.horizon_kernel` over the kernels of :mod:`.invdyn_node_kernel`: the node tables stacked
(``tbls[t]``), their integers, parameters and inverse-dynamics items concatenated (``ints[ioff[t]:ioff[t+1]]``,
``par[poff[t]:poff[t+1]]``, ``iints[joff[t]:joff[t+1]]``), the trajectories as address arrays (``xs[t]`` the address
of state t).  Each node's cost goes into ``costs[t]`` and the functions return their sum, added in node order.  The
evaluations release the GIL (several threads may run disjoint ranges at once, :mod:`.node_threads`).
"""

from __future__ import annotations

from crocopy.kernels import matrix_at, uncounted, vector_at

from .configuration_kernel import state_diff
from .invdyn_node_kernel import invdyn_calc, invdyn_calc_diff, invdyn_rollout_step
from .node_table import E_XNEXT, NQ, NV, entry_model, vec


@uncounted
def invdyn_horizon_rollout(tbls, ints, ioff, par, poff, iints, joff, xs, us, xs_try, us_try, dxs, ks, Ks, fs, lbs,
                           ubs, nus, nx, ndx, alpha, gaps, gap_at, t0, t1, costs):
    """:func:`.invdyn_node_kernel.invdyn_rollout_step` over the running nodes ``t0 <= t < t1`` in one call (arguments
    as :func:`.horizon_kernel.horizon_rollout`'s, and the items ``iints``/``joff``); returns the sum of their costs."""
    total = 0.0
    for t in range(t0, t1):
        nu = nus[t]
        cost = invdyn_rollout_step(
            tbls[t], ints[ioff[t]: ioff[t + 1]], par[poff[t]: poff[t + 1]], iints[joff[t]: joff[t + 1]],
            vector_at(xs[t], nx), vector_at(xs_try[t], nx), vector_at(us[t], nu), vector_at(ks[t], nu),
            matrix_at(Ks[t], nu, ndx), alpha, vector_at(lbs[t], nu), vector_at(ubs[t], nu), vector_at(us_try[t], nu),
            vector_at(dxs[t], ndx), vector_at(xs_try[t + 1], nx), vector_at(fs[t + 1], ndx), gaps or t + 1 == gap_at,
        )
        costs[t] = cost
        total += cost
    return total


def _calc_diff(tbls, ints, ioff, par, poff, iints, joff, xs, us, nus, nx, ndx, gaps, fs, t0, t1, costs):
    """:func:`.invdyn_node_kernel.invdyn_calc_diff` over the running nodes ``t0 <= t < t1`` in one call; returns the
    sum of their costs.  With ``gaps``, also the gaps ``fs[t+1] = xnext_t ⊖ xs[t+1]``."""
    total = 0.0
    for t in range(t0, t1):
        tbl, node_ints = tbls[t], ints[ioff[t]: ioff[t + 1]]
        cost = invdyn_calc_diff(tbl, node_ints, par[poff[t]: poff[t + 1]], iints[joff[t]: joff[t + 1]],
                                vector_at(xs[t], nx), vector_at(us[t], nus[t]))
        costs[t] = cost
        total += cost
        if gaps:
            rb = entry_model(tbl, node_ints)
            state_diff(rb.jtype, rb.idx_q, rb.idx_v, node_ints[NQ], node_ints[NV], vector_at(xs[t + 1], nx),
                       vec(tbl, node_ints, E_XNEXT), vector_at(fs[t + 1], ndx))
    return total


invdyn_horizon_calc_diff = uncounted(_calc_diff, nogil=True)


def _calc(tbls, ints, ioff, par, poff, iints, joff, xs, us, nus, nx, t0, t1, costs):
    """:func:`.invdyn_node_kernel.invdyn_calc` over the running nodes ``t0 <= t < t1`` in one call; returns the sum of
    their costs."""
    total = 0.0
    for t in range(t0, t1):
        cost = invdyn_calc(tbls[t], ints[ioff[t]: ioff[t + 1]], par[poff[t]: poff[t + 1]],
                           iints[joff[t]: joff[t + 1]], vector_at(xs[t], nx), vector_at(us[t], nus[t]))
        costs[t] = cost
        total += cost
    return total


invdyn_horizon_calc = uncounted(_calc, nogil=True)
