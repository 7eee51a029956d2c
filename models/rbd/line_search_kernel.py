"""The DDP family's line search in one compiled call, for a feasible iterate whose running nodes are one range of
compiled Euler nodes (:mod:`.horizon_kernel`) and whose terminal node is a compiled Euler node too.

For each step length ``α`` of ``alphas`` in turn: the trial rollout of every running node
(:func:`.horizon_kernel.horizon_rollout`, no gap kept open), the terminal node at the last trial state
(:func:`.euler_node_kernel.node_calc`), the trial cost ``cost_try`` (added as the Python rollout adds it: the range's
total, then the terminal cost), ``dV = cost - cost_try`` and ``dVexp = α (d₀ + ½ α d₁)``, and the solvers'
acceptance test of a feasible iterate: ``dVexp ≥ 0`` and (``|d₀| < th_grad`` or ``dV > th_accept dVexp``), or, with
``negative`` (FDDP), ``dVexp < 0`` and (``|d₀| < th_grad`` or ``dV > th_negative dVexp``).  The numbers are those of
the trials run one by one.

:func:`line_search_gaps` is the search from an infeasible iterate of FDDP and Box-FDDP: the gaps kept open by
``(1 - α)`` (``x̂₀ = x0 ⊕ ((α - 1) f₀)`` by node 0's state integration, then every node's next state; Box-FDDP only when
``α ≠ 1``), and ``d`` of the trial step, ``dv = Σ_t (Vxx f)_tᵀ (x̂_t ⊖ x_t)`` (the running nodes' sum as
:func:`crocopy.solvers.riccati_kernel.gap_step_term` adds it, then the terminal node's term, its difference by the
terminal node's state), ``d₀ = dg + dv``, ``d₁ = dq - 2 dv``: what ``SolverFDDP.expectedImprovement`` gives after the
trial's ``tryStep`` on compiled nodes; then the solvers' acceptance test of an infeasible iterate (``dVexp < 0`` passes
when ``dV > th_negative dVexp``, or for FDDP also when ``|d₀| < th_grad``).
"""

from __future__ import annotations

import math

from crocopy.kernels import uncounted, vector_at
from crocopy.solvers.horizon import VXX_F
from crocopy.solvers.riccati_kernel import gap_step_term, step_term

from .euler_node_kernel import node_calc, node_diff, node_integrate
from .horizon_kernel import horizon_rollout

ACCEPTED = 0
"""Status: the trial of ``alphas[i]`` passed the test (its values are in ``out``)."""
REJECTED = 1
"""Status: every trial failed the test (``i`` the last; its values are in ``out``)."""
NONFINITE = 2
"""Status: the trial of ``alphas[i]`` was not finite (a node's cost, the last state or the total): the caller runs
it again on its own path, which finds where and why."""


@uncounted
def line_search(tbls, ints, ioff, par, poff, xs, us, xs_try, us_try, dxs, ks, Ks, fs, lbs, ubs, nus, nx, ndx, T,
                costs, ttbl, tints, tpar, no_control, alphas, cost, d0, d1, th_grad, th_accept, th_negative, negative,
                out):
    """The trials of ``alphas`` until one is accepted; returns ``(i, status)``.

    The running nodes' arguments are :func:`.horizon_kernel.horizon_rollout`'s (over ``0 <= t < T``), the terminal
    node's ``ttbl, tints, tpar`` with the empty control ``no_control``; ``out (4,)`` receives the last finite trial's
    ``cost_try``, terminal cost, ``dV`` and ``dVexp``.
    """
    last = alphas.shape[0] - 1
    for i in range(alphas.shape[0]):
        alpha = alphas[i]
        cost_try, terminal = _trial(tbls, ints, ioff, par, poff, xs, us, xs_try, us_try, dxs, ks, Ks, fs, lbs, ubs, nus,
                                    nx, ndx, T, costs, ttbl, tints, tpar, no_control, alpha, False)
        if not math.isfinite(cost_try):
            return i, NONFINITE
        dV = cost - cost_try
        dVexp = alpha * (d0 + 0.5 * alpha * d1)
        out[0], out[1], out[2], out[3] = cost_try, terminal, dV, dVexp
        if dVexp >= 0:
            if abs(d0) < th_grad or dV > th_accept * dVexp:
                return i, ACCEPTED
        elif negative and (abs(d0) < th_grad or dV > th_negative * dVexp):
            return i, ACCEPTED
    return last, REJECTED


@uncounted
def _trial(tbls, ints, ioff, par, poff, xs, us, xs_try, us_try, dxs, ks, Ks, fs, lbs, ubs, nus, nx, ndx, T, costs, ttbl,
           tints, tpar, no_control, alpha, gaps):
    """The trial of step ``alpha`` (the running nodes' rollout, every gap kept open if ``gaps``, then the terminal node
    at the last state); returns ``(cost_try, terminal cost)``, ``cost_try`` NaN where the trial is not finite (a cost,
    the total or the last state)."""
    total = horizon_rollout(tbls, ints, ioff, par, poff, xs, us, xs_try, us_try, dxs, ks, Ks, fs, lbs, ubs, nus, nx,
                            ndx, alpha, gaps, -1, 0, T, costs)
    if not math.isfinite(total):
        return math.nan, math.nan
    x = vector_at(xs_try[T], nx)
    terminal = node_calc(ttbl, tints, tpar, x, no_control)
    cost_try = 0.0
    cost_try += total
    cost_try += terminal
    if not math.isfinite(cost_try) or not _finite(x):
        return math.nan, terminal
    return cost_try, terminal


@uncounted
def _finite(x):
    for i in range(x.shape[0]):
        if not math.isfinite(x[i]):
            return False
    return True


@uncounted
def line_search_gaps(tbls, ints, ioff, par, poff, xs, us, xs_try, us_try, dxs, ks, Ks, fs, lbs, ubs, nus, nx, ndx, T,
                     costs, ttbl, tints, tpar, no_control, x0, step, dx_T, saddr, sdims, alphas, cost, dg, dq,
                     th_grad, th_accept, th_negative, every, grad_negative, out):
    """The trials of ``alphas`` from an infeasible iterate until one is accepted (module docstring); returns
    ``(i, status)``.

    The arguments of :func:`line_search` (no ``d``: ``dg``, ``dq``, the trial-independent parts of FDDP's ``d``), the
    initial state ``x0``, scratch ``step (ndx,)`` and ``dx_T (ndx,)``, the solver's horizon buffer ``saddr``,
    ``sdims`` (``Vxx f`` in its column :data:`~crocopy.solvers.horizon.VXX_F`); ``every``: the gaps are kept open at
    every step length (FDDP; else only where ``α ≠ 1``, Box-FDDP); ``grad_negative``: ``|d₀| < th_grad`` also passes a
    negative ``dVexp`` (FDDP).  ``out (6,)`` receives the last finite trial's ``cost_try``, terminal cost, ``dV``,
    ``dVexp``, ``d₀`` and ``d₁``.
    """
    last = alphas.shape[0] - 1
    f0 = vector_at(fs[0], ndx)
    tbl0, ints0 = tbls[0], ints[ioff[0]: ioff[1]]
    x_first = vector_at(xs_try[0], nx)
    for i in range(alphas.shape[0]):
        alpha = alphas[i]
        gaps = every or alpha != 1.0
        if gaps:
            for j in range(ndx):
                step[j] = (alpha - 1.0) * f0[j]
            node_integrate(tbl0, ints0, x0, step, x_first)
        else:
            for j in range(nx):
                x_first[j] = x0[j]
        cost_try, terminal = _trial(tbls, ints, ioff, par, poff, xs, us, xs_try, us_try, dxs, ks, Ks, fs, lbs, ubs, nus,
                                    nx, ndx, T, costs, ttbl, tints, tpar, no_control, alpha, gaps)
        if not math.isfinite(cost_try):
            return i, NONFINITE
        dV = cost - cost_try
        dv = gap_step_term(saddr, sdims, dxs)  # the running nodes' (the terminal node's dx address is 0)
        node_diff(ttbl, tints, vector_at(xs[T], nx), vector_at(xs_try[T], nx), dx_T)
        dv += step_term(vector_at(saddr[T, VXX_F], ndx), dx_T)
        d0 = dg + dv
        d1 = dq - 2.0 * dv
        dVexp = alpha * (d0 + 0.5 * alpha * d1)
        out[0], out[1], out[2], out[3], out[4], out[5] = cost_try, terminal, dV, dVexp, d0, d1
        if dVexp >= 0:
            if abs(d0) < th_grad or dV > th_accept * dVexp:
                return i, ACCEPTED
        elif (grad_negative and abs(d0) < th_grad) or dV > th_negative * dVexp:
            return i, ACCEPTED
    return last, REJECTED
