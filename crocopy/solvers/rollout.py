"""The rollout of the DDP family: a trial trajectory from the solver's gains, written in place.

``û_t = clamp(u_t - α k_t - K_t (x̂_t ⊖ x_t), lb_t, ub_t)`` and ``x̂_{t+1} = f(x̂_t, û_t)``, the gaps kept open by
``(1 - α)`` where the solver asks (FDDP).  :func:`trial_rollout` is ``SolverDDP._trial_rollout``;
:func:`horizon_addresses` prepares the compiled calls that run each range of compiled nodes
(:mod:`.compiled_nodes`).
"""

from __future__ import annotations

from itertools import islice, repeat
from operator import attrgetter, is_, is_not
from sys import getrefcount

import numpy as np

from .. import kernels
from . import riccati_kernel
from .base import ForwardPassError


def sole_holder_count() -> int:
    """``getrefcount`` of an array that one list holds, read into a local name, as :func:`trial_rollout` reads it
    (3 on CPython 3.11-3.13: the list, the name, the argument; less where the interpreter borrows references)."""
    held = [np.empty(1)]
    a = held[0]
    return getrefcount(a)


SOLE = sole_holder_count()
"""The reference count of an array only a trajectory list holds, read as the rollout reads it."""


def sole_holder_count_mapped() -> int:
    """``getrefcount`` of an array that one list holds, read through ``map`` over ``islice`` of the list, as
    :func:`_fit` reads it."""
    held = [None, np.empty(1)]
    return list(map(getrefcount, islice(held, 1, None)))[0]


SOLE_MAPPED = sole_holder_count_mapped()
"""The reference count of an array only a trajectory list holds, read as :func:`_fit` reads it."""

_base = attrgetter("base")


def _fit(arrays: list, start: int, stop: int, sizes: list[int], check_holders: bool) -> bool:
    """Whether the entries ``start:stop`` of ``arrays`` can all be written in place (C-level checks, no Python
    loop): none is None, each has its size in ``sizes`` and owns its memory, and (``check_holders``) only the
    list holds it (:data:`SOLE_MAPPED`)."""
    if any(map(is_, islice(arrays, start, stop), repeat(None))):
        return False
    if list(map(len, islice(arrays, start, stop))) != sizes:
        return False
    if any(map(is_not, map(_base, islice(arrays, start, stop)), repeat(None))):
        return False
    return not check_holders or not any(map(int.__ne__, map(getrefcount, islice(arrays, start, stop)),
                                             repeat(SOLE_MAPPED)))


def trial_rollout(solver, steplength: float, gaps: bool = False, bounds: tuple[list, list] | None = None,
                  last_gap: bool = False) -> None:
    """The DDP family's rollout into ``xs_try``/``us_try``/``cost_try``; raises ForwardPassError on NaN.

    ``û_t = clamp(u_t - α k_t - K_t (x̂_t ⊖ x_t), lb_t, ub_t)`` (one compiled call,
    :func:`~crocopy.solvers.riccati_kernel.feedback_control`) with ``bounds = (lbs, ubs)`` (no
    ``bounds``, or ``None`` entries: no clamp) and ``x̂_{t+1} = f(x̂_t, û_t)``.  ``gaps`` keeps every
    gap open by ``(1 - α)``: ``x̂₀ = x0 ⊕ ((α-1) f₀)``, ``x̂_{t+1} = f(x̂_t, û_t) ⊕ ((α-1) f_{t+1})``
    (FDDP); ``last_gap`` keeps only the last one (Crocoddyl 3.2's Box-DDP from an infeasible
    iterate).  Stores ``x̂_t ⊖ x_t`` in ``_dx_try`` (the solver's arrays, rewritten by every rollout).

    No per-node allocation: an entry of ``xs_try``/``us_try`` is written in place when the list is
    the only holder of that array (its ``getrefcount`` is :data:`SOLE`, measured at import on the same
    pattern), else replaced by a new array, so that a state or control a user
    kept from ``xs``/``us`` (swapped with ``xs_try``/``us_try`` when a trial is accepted) never
    changes under them.

    Inside ``solve``, a compiled node (:mod:`.compiled_nodes`) does its whole step (``dx``, the
    control, the node, the next state) in one call, and each range of compiled nodes with a horizon is one
    call (:attr:`~.compiled_nodes.CompiledNodes.segments`, :func:`horizon_addresses`).
    """
    problem = solver.problem
    xs, xs_try, us_try, fs, dx_try = solver.xs, solver.xs_try, solver.us_try, solver.fs, solver._dx_try
    models = problem.runningModels
    x0 = problem.x0
    x = xs_try[0]
    if getrefcount(x) != SOLE or x.base is not None or x.shape != x0.shape:
        x = xs_try[0] = np.empty_like(x0)
    if gaps:
        (models[0] if models else problem.terminalModel).state._integrate_into(x0, (steplength - 1.0) * fs[0], x)
    else:
        x[:] = x0
    lbs, ubs = (None, None) if bounds is None else bounds
    us, k, K, unbounded = solver.us, solver.k, solver.K, solver._unbounded
    feedback = riccati_kernel.feedback_control if kernels.active else riccati_kernel.feedback_control_numpy
    gap_at = problem.T if last_gap else -1
    nodes = solver._nodes
    calcs, steps = (None, None) if nodes is None else (nodes.calcs, nodes.steps)
    segments = {} if nodes is None or nodes.horizon is None else nodes.segments
    addresses = None if not segments else horizon_addresses(solver, lbs, ubs)
    datas = problem.runningDatas
    cost = 0.0
    t = 0
    T = problem.T
    while t < T:
        if t in segments:
            end = segments[t]
            cost += nodes.horizon.rollout(addresses, steplength, gaps, gap_at, t, end)
            for d, c in zip(islice(datas, t, end), nodes.horizon.costs[t:end].tolist()):
                d.cost = c
            t = end
            x = xs_try[t]
            continue
        m, d = models[t], datas[t]
        state = m.state
        if m.nu:
            dx = dx_try[t]
            if dx is None or dx.shape[0] != state.ndx:
                dx = dx_try[t] = np.empty(state.ndx)
            u = us_try[t]
            if getrefcount(u) != SOLE or u.base is not None or u.shape[0] != m.nu:
                u = us_try[t] = np.empty(m.nu)
            lb = None if lbs is None else lbs[t]
            if lb is None:
                lb, ub = unbounded[m.nu]
            else:
                ub = ubs[t]
            step = None if steps is None else steps[t]
            if step is not None:
                x_next = xs_try[t + 1]
                if getrefcount(x_next) != SOLE or x_next.base is not None or x_next.shape[0] != state.nx:
                    x_next = xs_try[t + 1] = np.empty(state.nx)
                d.cost = c = step(xs[t], x, us[t], k[t], K[t], steplength, lb, ub, u, dx, x_next, fs[t + 1],
                                  gaps or t + 1 == gap_at)
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
        t += 1
        xnext = d.xnext
        x = xs_try[t]
        if getrefcount(x) != SOLE or x.base is not None or x.shape != xnext.shape:
            x = xs_try[t] = np.empty_like(xnext)
        if gaps or t == gap_at:
            state._integrate_into(xnext, (steplength - 1.0) * fs[t], x)
        else:
            x[:] = xnext
    if calcs is None:
        problem.terminalModel.calc(problem.terminalData, x)
    else:
        calcs[-1](x, None)
    cost += problem.terminalData.cost
    if not np.isfinite(cost) or not np.isfinite(x).all():
        raise ForwardPassError("the rollout produced a non-finite state or cost")
    solver.cost_try = cost


def horizon_addresses(solver, lbs: list | None, ubs: list | None) -> tuple:
    """The addresses of the rollout's arrays for ``solver._nodes.horizon``, after the entries the horizon writes
    (``us_try``, ``_dx_try`` and ``xs_try`` of its nodes, and each range's first state) are made fit, as in the
    node loop: an array is reused when the solver's list is its only holder (``getrefcount`` equal to
    :data:`SOLE`); when they all fit (:func:`_fit`, the usual case) no Python loop runs over the nodes.  The node
    loop then replaces none of them, so the addresses stay valid for the whole rollout."""
    problem = solver.problem
    xs_try, us_try, dx_try = solver.xs_try, solver.us_try, solver._dx_try
    nodes = solver._nodes
    for t0, t1 in nodes.segments.items():
        first = max(t0, 1)  # xs_try[0] was made fit by the caller, which holds it
        if not (_fit(us_try, t0, t1, nodes.nu[t0:t1], True) and _fit(dx_try, t0, t1, nodes.ndx[t0:t1], False)
                and _fit(xs_try, first, t1 + 1, nodes.nx[first - 1:t1], True)):
            _make_fit(problem, xs_try, us_try, dx_try, t0, t1)
    lb_list, ub_list = nodes.bounds(lbs, ubs, solver._unbounded)
    return nodes.horizon.addresses(solver.xs, solver.us, xs_try, us_try, dx_try, solver.k, solver.K, solver.fs,
                                   lb_list, ub_list)


def _make_fit(problem, xs_try: list, us_try: list, dx_try: list, t0: int, t1: int) -> None:
    """The node loop of :func:`horizon_addresses`' checks for the nodes ``t0 <= t < t1``: replace each entry that
    cannot be written in place (and the range's first state, ``t0 > 0``)."""
    if t0 > 0:
        x = xs_try[t0]
        if getrefcount(x) != SOLE or x.base is not None or x.shape[0] != problem.runningModels[t0].state.nx:
            xs_try[t0] = np.empty(problem.runningModels[t0].state.nx)
    for t in range(t0, t1):
        m = problem.runningModels[t]
        state, nu = m.state, m.nu
        dx = dx_try[t]
        if dx is None or dx.shape[0] != state.ndx:
            dx_try[t] = np.empty(state.ndx)
        u = us_try[t]
        if getrefcount(u) != SOLE or u.base is not None or u.shape[0] != nu:
            us_try[t] = np.empty(nu)
        x = xs_try[t + 1]
        if getrefcount(x) != SOLE or x.base is not None or x.shape[0] != state.nx:
            xs_try[t + 1] = np.empty(state.nx)
