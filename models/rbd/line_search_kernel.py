"""The DDP family's line search in one compiled call, for a feasible iterate whose running nodes are one range of
compiled Euler nodes (:mod:`.horizon_kernel`) and whose terminal node is a compiled Euler node too.

For each step length ``α`` of ``alphas`` in turn: the trial rollout of every running node
(:func:`.horizon_kernel.horizon_rollout`, no gap kept open), the terminal node at the last trial state
(:func:`.euler_node_kernel.node_calc`), the trial cost ``cost_try`` (added as the Python rollout adds it: the range's
total, then the terminal cost), ``dV = cost - cost_try`` and ``dVexp = α (d₀ + ½ α d₁)``, and the solvers'
acceptance test of a feasible iterate: ``dVexp ≥ 0`` and (``|d₀| < th_grad`` or ``dV > th_accept dVexp``), or, with
``negative`` (FDDP), ``dVexp < 0`` and (``|d₀| < th_grad`` or ``dV > th_negative dVexp``).  The numbers are those of
the trials run one by one.
"""

from __future__ import annotations

import math

from crocopy.kernels import uncounted, vector_at

from .euler_node_kernel import node_calc
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
        total = horizon_rollout(tbls, ints, ioff, par, poff, xs, us, xs_try, us_try, dxs, ks, Ks, fs, lbs, ubs, nus,
                                nx, ndx, alpha, False, -1, 0, T, costs)
        if not math.isfinite(total):
            return i, NONFINITE
        x = vector_at(xs_try[T], nx)
        terminal = node_calc(ttbl, tints, tpar, x, no_control)
        cost_try = 0.0
        cost_try += total
        cost_try += terminal
        if not math.isfinite(cost_try) or not _finite(x):
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
def _finite(x):
    for i in range(x.shape[0]):
        if not math.isfinite(x[i]):
            return False
    return True
