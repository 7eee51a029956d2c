"""The rollout of the DDP family: a trial trajectory from the solver's gains, written in place.

``û_t = clamp(u_t - α k_t - K_t (x̂_t ⊖ x_t), lb_t, ub_t)`` and ``x̂_{t+1} = f(x̂_t, û_t)``, the gaps kept open by
``(1 - α)`` where the solver asks (FDDP).  :func:`trial_rollout` is ``SolverDDP._trial_rollout``;
:func:`horizon_addresses` prepares the compiled calls that run each range of compiled nodes
(:mod:`.compiled_nodes`).  A trial likely to diverge (its step length diverged last time, or the trial before it
did) runs its ranges in growing steps (:func:`segment_rollout`), so that the work stops near the divergence; the
numbers are those of one call.
"""

from __future__ import annotations

import math
from itertools import islice

import numpy as np

from .. import kernels
from . import riccati_kernel
from .base import ForwardPassError
from .trajectories import addresses


def trial_rollout(solver, steplength: float, gaps: bool = False, bounds: tuple[list, list] | None = None,
                  last_gap: bool = False) -> None:
    """The DDP family's rollout into ``xs_try``/``us_try``/``cost_try``; raises ForwardPassError on NaN.

    ``û_t = clamp(u_t - α k_t - K_t (x̂_t ⊖ x_t), lb_t, ub_t)`` (one compiled call,
    :func:`~crocopy.solvers.riccati_kernel.feedback_control`) with ``bounds = (lbs, ubs)`` (no
    ``bounds``, or ``None`` entries: no clamp) and ``x̂_{t+1} = f(x̂_t, û_t)``.  ``gaps`` keeps every
    gap open by ``(1 - α)``: ``x̂₀ = x0 ⊕ ((α-1) f₀)``, ``x̂_{t+1} = f(x̂_t, û_t) ⊕ ((α-1) f_{t+1})``
    (FDDP); ``last_gap`` keeps only the last one (Crocoddyl 3.2's Box-DDP from an infeasible
    iterate).  Stores ``x̂_t ⊖ x_t`` in ``_dx_try`` (the solver's arrays, rewritten by every rollout).

    No allocation: ``xs_try``, ``us_try`` and ``_dx_try`` are the solver's own arrays
    (:mod:`.trajectories`), written in place.

    Inside ``solve``, a compiled node (:mod:`.compiled_nodes`) does its whole step (``dx``, the
    control, the node, the next state) in one call, and each range of compiled nodes with a horizon is one
    call (:attr:`~.compiled_nodes.CompiledNodes.segments`, :func:`horizon_addresses`).
    """
    problem = solver.problem
    xs, xs_try, us_try, fs, dx_try = solver.xs, solver.xs_try, solver.us_try, solver.fs, solver._dx_try
    models = problem.runningModels
    x0 = problem.x0
    x = xs_try[0]
    nodes = solver._nodes
    if gaps:  # by node 0's compiled integration where it is compiled, as the compiled line search
        step = (steplength - 1.0) * fs[0]
        if nodes is None or nodes.horizon is None or not nodes.horizon.first_state(x0, step, x):
            (models[0] if models else problem.terminalModel).state._integrate_into(x0, step, x)
    else:
        x[:] = x0
    lbs, ubs = (None, None) if bounds is None else bounds
    us, k, K, unbounded = solver.us, solver.k, solver.K, solver._unbounded
    feedback = riccati_kernel.feedback_control if kernels.active else riccati_kernel.feedback_control_numpy
    gap_at = problem.T if last_gap else -1
    calcs, steps = (None, None) if nodes is None else (nodes.calcs, nodes.steps)
    segments = {} if nodes is None or nodes.horizon is None else nodes.segments
    addresses = None if not segments else horizon_addresses(solver, nodes, lbs, ubs)
    datas = problem.runningDatas
    cost = 0.0
    t = 0
    T = problem.T
    by_node = -1  # a node the compiled step left non-finite: evaluated again without it (its Python path, which
    # takes least squares where a contact set is singular); if that diverges too, the trial stops there
    chunked = steplength in solver._diverged_steps or solver._last_trial_diverged  # likely to diverge
    diverged = False
    ends = None  # after a diverged step: the end of the compiled range of every node inside one
    while t < T:
        start = t in segments
        if ends is None and diverged and segments and not nodes.horizon.python:
            ends = {s: end for t0, end in segments.items() for s in range(t0, end)}
        if (start or ends is not None and t in ends) and t != by_node:
            end, horizon = ends[t] if ends is not None else segments[t], nodes.horizon
            c, bad = segment_rollout(horizon, addresses, xs_try, us_try, steplength, gaps, gap_at, t, end, chunked)
            if bad is not None:
                end = by_node = bad
                chunked = diverged = True
            if start:
                cost += c
            else:  # within a range, after a diverged step: its node steps' costs added one by one, as they were
                for c in horizon.costs[t:end].tolist():
                    cost += c
            for d, c in zip(islice(datas, t, end), horizon.costs[t:end].tolist()):
                d.cost = c
            t = end
            x = xs_try[t]
            continue
        m, d = models[t], datas[t]
        state = m.state
        if m.nu:
            dx = dx_try[t]
            u = us_try[t]
            lb = None if lbs is None else lbs[t]
            if lb is None:
                lb, ub = unbounded[m.nu]
            else:
                ub = ubs[t]
            step = None if steps is None or t == by_node else steps[t]
            if step is not None:
                x_next = xs_try[t + 1]
                d.cost = c = step(xs[t], x, us[t], k[t], K[t], steplength, lb, ub, u, dx, x_next, fs[t + 1],
                                  gaps or t + 1 == gap_at)
                if not math.isfinite(c):
                    by_node = t
                    chunked = diverged = True
                    continue
                cost += c
                x = x_next
                t += 1
                continue
            state._diff_into(xs[t], x, dx)
            feedback(us[t], k[t], K[t], dx, steplength, lb, ub, u)
        else:
            u = us_try[t]
        if calcs is None:
            m._raw_calc(d, x, u)
        else:
            calcs[t](x, u)
        cost += d.cost
        xnext = d.xnext
        if t == by_node and not np.isfinite(xnext).all():  # the Python path diverges too: the trial fails here
            xs_try[t + 1][:] = xnext  # where the search of the reason finds it (a horizon call may not have reached it)
            _note_divergence(solver, steplength, True)
            raise ForwardPassError("the rollout produced a non-finite state or cost")
        t += 1
        x = xs_try[t]
        if gaps or t == gap_at:
            state._integrate_into(xnext, (steplength - 1.0) * fs[t], x)
        else:
            x[:] = xnext
    if calcs is None:
        problem.terminalModel.calc(problem.terminalData, x)
    else:
        calcs[-1](x, None)
    cost += problem.terminalData.cost
    _note_divergence(solver, steplength, diverged)
    if not math.isfinite(cost) or not np.isfinite(x).all():
        raise ForwardPassError("the rollout produced a non-finite state or cost")
    solver.cost_try = cost


CHUNK = 8
"""Nodes in the first compiled call of a range run in steps (:func:`segment_rollout`); each next call doubles."""


def segment_rollout(horizon, addresses: tuple, xs_try: list, us_try: list, steplength: float, gaps: bool,
                    gap_at: int, t0: int, t1: int, chunked: bool) -> tuple[float, int | None]:
    """The compiled rollout of the nodes ``t0 <= t < t1``: ``(total, None)``, or ``(total before node t, t)`` where
    node ``t`` is the first whose cost is not finite (its compiled step diverged: the caller evaluates it again).

    One call covers the range; ``chunked`` (a trial likely to diverge) runs it in calls of :data:`CHUNK`, then twice
    as many nodes each, so that a divergence stops the work near where it arose (a call runs to its end).  The total
    is the same either way: the nodes' costs added in node order from the range's first (``horizon.fold``), as one call
    adds them.  A horizon with Python residuals (whose costs a call corrects after its nodes) runs in one call.
    """
    if not chunked or horizon.python:
        c = horizon.rollout(addresses, xs_try, us_try, steplength, gaps, gap_at, t0, t1)
        if math.isfinite(c):
            return c, None
        bad = _first_nonfinite(horizon.costs, t0, t1)
        return (c, None) if bad is None else (horizon.fold(t0, bad), bad)
    a, size = t0, CHUNK
    while a < t1:
        b = min(a + size, t1)
        if not math.isfinite(horizon.rollout(addresses, xs_try, us_try, steplength, gaps, gap_at, a, b)):
            bad = _first_nonfinite(horizon.costs, a, b)
            if bad is not None:
                return horizon.fold(t0, bad), bad
        a, size = b, 2 * size
    return horizon.fold(t0, t1), None


def _first_nonfinite(costs: np.ndarray, t0: int, t1: int) -> int | None:
    return next((s for s in range(t0, t1) if not math.isfinite(costs[s])), None)


def _note_divergence(solver, steplength: float, diverged: bool) -> None:
    """Remember whether a compiled step diverged in this trial (its next trial, and the next one with this step
    length, then run their compiled ranges in steps, :func:`segment_rollout`)."""
    solver._last_trial_diverged = diverged
    if diverged:
        solver._diverged_steps.add(steplength)
    else:
        solver._diverged_steps.discard(steplength)


def horizon_addresses(solver, nodes, lbs: list | None, ubs: list | None) -> tuple:
    """The addresses of the rollout's arrays for ``nodes.horizon``: the solver's trajectories and the control
    bounds, read again only after the solver made new ones (:class:`~.trajectories.TrajectoryAddresses`; the
    bounds: ``solver._bound_addresses``, reset where the solver allocates or reads its bounds)."""
    a = solver._addresses()
    bound = solver._bound_addresses
    if bound is None:
        lb_list, ub_list = nodes.bounds(lbs, ubs, solver._unbounded)
        bound = solver._bound_addresses = (addresses(lb_list), addresses(ub_list))
    return (a.xs, a.us, a.xs_try, a.us_try, a.dx_try, a.k, a.K, a.fs, *bound)
