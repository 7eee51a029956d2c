"""Activation and accumulation steps of :class:`~crocopy.costs.stack.CostStack`: numba kernels and numpy twins.

Both compute (rows ``i``, items ``k``)::

    eᵢ = rᵢ - clip(rᵢ, lbᵢ, ubᵢ),   costₖ = ½ Σ_{i ∈ k} aᵢ eᵢ²,   cost = Σₖ wₖ costₖ
    Arᵢ = aᵢ eᵢ,   Arrᵢ = aᵢ [rᵢ ≤ lbᵢ or rᵢ ≥ ubᵢ]
    Lx = Jxᵀ (w ∘ Ar),   Lxx = Jxᵀ diag(w ∘ Arr) Jx,   Lu, Lxu, Luu likewise with the ``Ju`` rows

:func:`derivatives_and_sums` runs the last two in one call (the stack's ``calcDiff`` when every
activation is fused).  One call replaces a dozen small numpy calls; rows whose weighted curvature is zero (a barrier
row inside its bounds, an inactive item) are left out of the matrix products, and the compiled products skip the
zero entries of each Jacobian row.  Each kernel has a
numpy twin (``*_numpy``, same arguments) giving the same numbers to round-off (tested);
:mod:`crocopy.kernels` chooses.

Compiled nodes also evaluate, item by item, the diagonal activations of another form (an item's ``kinds[k]`` not
:data:`BARRIER`, its parameter ``params[k]``; ``n = Σ rᵢ²`` over the item's rows, Crocoddyl's diagonal ``Arr``):

* :data:`SMOOTH1` (``ε``): ``a = Σ √(ε + rᵢ²)``, ``Arᵢ = rᵢ/sᵢ``, ``Arrᵢ = ε/sᵢ³`` with ``sᵢ = √(ε + rᵢ²)``;
* :data:`FLAT_EXP` (``α``): ``a = 1 - e``, ``e = exp(-n/α)``, ``Ar = c r``, ``Arrᵢ = c - (2/α) c rᵢ²``, ``c = (2/α) e``;
* :data:`FLAT_LOG` (``α``): ``a = log(1 + n/α)``, ``Ar = c r``, ``Arrᵢ = c - c² rᵢ²``, ``c = 2/(α + n)``;

and the dense activations, whose Hessian ``Arr = d I + c r rᵀ`` is a diagonal and a rank-one term (the diagonal ``d``
goes into the rows' ``Arr`` and the sums; then :func:`rank_one_sums` adds ``w c (Jᵀ r)(Jᵀ r)ᵀ`` over the item's
rows, ``J = [Jx Ju]``):

* :data:`SMOOTH2` (``ε``): ``a = √(ε + n)``, ``Ar = r/a``, ``d = 1/a``, ``c = -1/a³``;
* :data:`NORM_BARRIER` (``α``, Gauss-Newton) and :data:`NORM_BARRIER_TRUE` (``α``, true Hessian): with ``ρ = √n``,
  inside the ball (``0 < ρ < α``) ``a = ½ (ρ - α)²``, ``Ar = (1 - α/ρ) r``, ``d = 0`` and ``c = 1/ρ²`` (Gauss-Newton),
  or ``d = 1 - α/ρ`` and ``c = α/ρ³`` (true Hessian); zero elsewhere;
* :data:`FLAT_EXP_TRUE` and :data:`FLAT_LOG_TRUE` (``α``): the quadratic-flat activations with their full Hessian,
  ``d`` the coefficient ``c`` of their ``Ar = c r`` above and ``c = -(2/α) c``, ``-c²`` respectively

(:func:`stack_values`, :func:`stack_derivatives_and_sums`: the barrier-family pass, then those items'; the same
numbers as the activations' own ``calc``/``calcDiff`` to round-off, tested through the nodes).
"""

from __future__ import annotations

import math

import numpy as np

from ..kernels import compiled


def _excess(r, lb, ub):
    return r - np.maximum(np.minimum(r, ub), lb)


def activation_values_numpy(r, lb, ub, act_w, starts, item_costs, item_weights) -> float:
    """Numpy twin of :func:`activation_values`."""
    with np.errstate(over="ignore", invalid="ignore"):
        rows = _excess(r, lb, ub)
        rows *= rows
        rows *= act_w
    np.add.reduceat(rows, starts, out=item_costs)
    item_costs *= 0.5
    return float(item_weights @ item_costs)


def activation_derivatives_numpy(r, lb, ub, act_w, Ar, Arr) -> None:
    """Numpy twin of :func:`activation_derivatives`."""
    np.multiply(act_w, _excess(r, lb, ub), out=Ar)
    np.multiply((r <= lb) | (r >= ub), act_w, out=Arr)


def accumulate_numpy(weights, Ar, Arr, Jx, Ju, u_start, with_u, Lx, Lu, Lxx, Lxu, Luu, cols) -> None:
    """Numpy twin of :func:`accumulate` (``cols`` unused)."""
    wArr = weights * Arr
    np.dot(Jx.T, weights * Ar, out=Lx)
    np.dot(Jx.T, wArr[:, None] * Jx, out=Lxx)
    if with_u:
        np.dot(Ju.T, (weights * Ar)[u_start:], out=Lu)
        Hu = wArr[u_start:, None] * Ju
        np.dot(Jx[u_start:].T, Hu, out=Lxu)
        np.dot(Ju.T, Hu, out=Luu)


def derivatives_and_sums_numpy(r, lb, ub, act_w, weights, Ar, Arr, Jx, Ju, u_start, with_u, Lx, Lu, Lxx, Lxu,
                               Luu, cols) -> None:
    """Numpy twin of :func:`derivatives_and_sums`."""
    activation_derivatives_numpy(r, lb, ub, act_w, Ar, Arr)
    accumulate_numpy(weights, Ar, Arr, Jx, Ju, u_start, with_u, Lx, Lu, Lxx, Lxu, Luu, cols)


def _activation_values(r, lb, ub, act_w, starts, item_costs, item_weights):
    """``costₖ`` of every item into ``item_costs``; returns ``Σₖ wₖ costₖ``."""
    nr, n = r.shape[0], starts.shape[0]
    total = 0.0
    for k in range(n):
        stop = starts[k + 1] if k + 1 < n else nr
        acc = 0.0
        for i in range(starts[k], stop):
            ri = r[i]
            c = ri if ri <= ub[i] else ub[i]
            c = c if c >= lb[i] else lb[i]
            e = ri - c
            acc += act_w[i] * e * e
        item_costs[k] = 0.5 * acc
        total += item_weights[k] * item_costs[k]
    return total


def _activation_derivatives(r, lb, ub, act_w, Ar, Arr):
    """``Ar`` and ``Arr`` of every row."""
    for i in range(r.shape[0]):
        ri = r[i]
        c = ri if ri <= ub[i] else ub[i]
        c = c if c >= lb[i] else lb[i]
        Ar[i] = act_w[i] * (ri - c)
        Arr[i] = act_w[i] if (ri <= lb[i] or ri >= ub[i]) else 0.0


def _accumulate(weights, Ar, Arr, Jx, Ju, u_start, with_u, Lx, Lu, Lxx, Lxu, Luu, cols):
    """Weighted Gauss-Newton sums, one rank-one update per row whose weighted curvature ``h = w Arr`` is not zero, each
    over the nonzero entries of its Jacobian row only (listed once per row: a state or control residual's row has one
    or a few, so the products cost the square of the rows' nonzeros, not ``nr ndx²``); the upper triangles of ``Lxx``
    and ``Luu``, then their mirror (exactly symmetric).  A zero entry is left out of a sum it would add ``±0`` to.
    ``cols (≥ ndx + nu,)`` int64: scratch for a row's nonzero columns (the stack's ``cols``; nothing is allocated)."""
    nr, ndx = Jx.shape
    nu = Ju.shape[1]
    if nu == 0:
        with_u = False
    Lx[:] = 0.0
    Lxx[:, :] = 0.0
    if with_u:
        Lu[:] = 0.0
        Lxu[:, :] = 0.0
        Luu[:, :] = 0.0
    ucols = cols[ndx:]
    for i in range(nr):
        g = weights[i] * Ar[i]
        h = weights[i] * Arr[i]
        if g == 0.0 and h == 0.0:
            continue
        u_row = with_u and i >= u_start
        n = 0
        for j in range(ndx):
            if Jx[i, j] != 0.0:
                cols[n] = j
                n += 1
        m = 0
        if u_row:
            iu = i - u_start
            for j in range(nu):
                if Ju[iu, j] != 0.0:
                    ucols[m] = j
                    m += 1
        if g != 0.0:
            for p in range(n):
                j = cols[p]
                Lx[j] += g * Jx[i, j]
            for p in range(m):
                j = ucols[p]
                Lu[j] += g * Ju[i - u_start, j]
        if h == 0.0:
            continue
        for p in range(n):
            a = cols[p]
            s = h * Jx[i, a]
            if s != 0.0:
                for q in range(p, n):
                    b = cols[q]
                    Lxx[a, b] += s * Jx[i, b]
                for q in range(m):
                    b = ucols[q]
                    Lxu[a, b] += s * Ju[i - u_start, b]
        for p in range(m):
            a = ucols[p]
            s = h * Ju[i - u_start, a]
            if s != 0.0:
                for q in range(p, m):
                    b = ucols[q]
                    Luu[a, b] += s * Ju[i - u_start, b]
    for a in range(ndx):
        for b in range(a):
            Lxx[a, b] = Lxx[b, a]
    if with_u:
        for a in range(nu):
            for b in range(a):
                Luu[a, b] = Luu[b, a]


activation_values = compiled(_activation_values)
activation_derivatives = compiled(_activation_derivatives)
accumulate = compiled(_accumulate)


def _derivatives_and_sums(r, lb, ub, act_w, weights, Ar, Arr, Jx, Ju, u_start, with_u, Lx, Lu, Lxx, Lxu, Luu, cols):
    """:func:`activation_derivatives` then :func:`accumulate`, one call from Python."""
    activation_derivatives(r, lb, ub, act_w, Ar, Arr)
    accumulate(weights, Ar, Arr, Jx, Ju, u_start, with_u, Lx, Lu, Lxx, Lxu, Luu, cols)


derivatives_and_sums = compiled(_derivatives_and_sums)


BARRIER, SMOOTH1, FLAT_EXP, FLAT_LOG, SMOOTH2, NORM_BARRIER, NORM_BARRIER_TRUE, FLAT_EXP_TRUE, FLAT_LOG_TRUE = range(9)
"""Activation kinds of a stack item: the barrier family (every row by the fused formula), then the item forms
(:meth:`crocopy.activations.base.ActivationModelAbstract.item_form`); from :data:`SMOOTH2` on, dense ones."""
ITEM_KINDS = {"smooth1": SMOOTH1, "flat_exp": FLAT_EXP, "flat_log": FLAT_LOG, "smooth2": SMOOTH2,
              "norm_barrier": NORM_BARRIER, "norm_barrier_true": NORM_BARRIER_TRUE, "flat_exp_true": FLAT_EXP_TRUE,
              "flat_log_true": FLAT_LOG_TRUE}
"""The kind of each item form's name."""
DENSE = (SMOOTH2, NORM_BARRIER, NORM_BARRIER_TRUE, FLAT_EXP_TRUE, FLAT_LOG_TRUE)
"""The kinds whose Hessian is dense (diagonal plus rank one, :func:`rank_one_sums`)."""


def _dense_terms(kind, p, n2):
    """``(a, s, d, c)`` of a dense item whose rows have ``Σ rᵢ² = n2``: its value, ``Ar = s r`` and ``Arr = d I +
    c r rᵀ`` (module docstring)."""
    if kind == SMOOTH2:
        a = math.sqrt(p + n2)
        return a, 1.0 / a, 1.0 / a, -1.0 / (a * a * a)
    if kind == FLAT_EXP_TRUE:
        e = math.exp(-n2 / p)
        c = 2.0 / p * e
        return 1.0 - e, c, c, -(2.0 / p * c)
    if kind == FLAT_LOG_TRUE:
        c = 2.0 / (p + n2)
        return math.log1p(n2 / p), c, c, -(c * c)
    rho = math.sqrt(n2)
    if rho >= p or rho == 0.0:
        return 0.0, 0.0, 0.0, 0.0
    s = (rho - p) / rho
    if kind == NORM_BARRIER:
        return 0.5 * (rho - p) ** 2, s, 0.0, 1.0 / n2
    return 0.5 * (rho - p) ** 2, s, s, p / (n2 * rho)


def _item_activations(r, starts, kinds, params, item_costs, item_weights, Ar, Arr, derivatives):
    """The cost (and, if ``derivatives``, the rows of ``Ar``, ``Arr``) of every item whose kind is not
    :data:`BARRIER`; returns ``Σₖ wₖ costₖ`` over every item, in item order."""
    nr, n = r.shape[0], starts.shape[0]
    total = 0.0
    for k in range(n):
        kind = kinds[k]
        if kind != BARRIER:
            stop = starts[k + 1] if k + 1 < n else nr
            p = params[k]
            if kind == SMOOTH1:
                acc = 0.0
                for i in range(starts[k], stop):
                    ri = r[i]
                    si = math.sqrt(p + ri * ri)
                    acc += si
                    if derivatives:
                        Ar[i] = ri / si
                        Arr[i] = p / (si * si * si)
                item_costs[k] = acc
            else:
                n2 = 0.0
                for i in range(starts[k], stop):
                    n2 += r[i] * r[i]
                if kind >= SMOOTH2:
                    a, s, d, _ = dense_terms(kind, p, n2)
                    item_costs[k] = a
                    if derivatives:
                        for i in range(starts[k], stop):
                            Ar[i] = s * r[i]
                            Arr[i] = d
                    total += item_weights[k] * item_costs[k]
                    continue
                if kind == FLAT_EXP:
                    e = math.exp(-n2 / p)
                    item_costs[k] = 1.0 - e
                    c = 2.0 / p * e
                    curvature = 2.0 / p * c
                else:
                    item_costs[k] = math.log1p(n2 / p)
                    c = 2.0 / (p + n2)
                    curvature = c * c
                if derivatives:
                    for i in range(starts[k], stop):
                        Ar[i] = r[i] * c
                        Arr[i] = c - curvature * (r[i] * r[i])
        total += item_weights[k] * item_costs[k]
    return total


def _rank_one_sums(r, starts, kinds, params, item_weights, Jx, Ju, u_start, with_u, Lxx, Lxu, Luu, grad):
    """``w c g gᵀ`` of every dense item (module docstring; ``g = Σᵢ rᵢ [Jx Ju]ᵢ`` over its rows, the ``Ju`` rows from
    ``u_start`` on, into the scratch ``grad (≥ ndx + nu,)``) added to the upper triangles of ``Lxx`` and ``Luu`` and to
    ``Lxu``, then their mirror (after :func:`accumulate`, which leaves them exactly symmetric); nothing when no item is
    dense."""
    nr, n, ndx = r.shape[0], starts.shape[0], Jx.shape[1]
    nu = Ju.shape[1] if with_u else 0
    touched = False
    for k in range(n):
        kind = kinds[k]
        if kind < SMOOTH2 or item_weights[k] == 0.0:
            continue
        start = starts[k]
        stop = starts[k + 1] if k + 1 < n else nr
        n2 = 0.0
        for i in range(start, stop):
            n2 += r[i] * r[i]
        c = item_weights[k] * dense_terms(kind, params[k], n2)[3]
        if c == 0.0:
            continue
        touched = True
        for a in range(ndx + nu):
            grad[a] = 0.0
        for i in range(start, stop):
            ri = r[i]
            for a in range(ndx):
                grad[a] += ri * Jx[i, a]
            if i >= u_start:
                for a in range(nu):
                    grad[ndx + a] += ri * Ju[i - u_start, a]
        for a in range(ndx + nu):
            ga = grad[a]
            if ga == 0.0:
                continue
            s = c * ga
            for b in range(a, ndx + nu):
                if b < ndx:
                    Lxx[a, b] += s * grad[b]
                elif a < ndx:
                    Lxu[a, b - ndx] += s * grad[b]
                else:
                    Luu[a - ndx, b - ndx] += s * grad[b]
    if touched:
        for a in range(ndx):
            for b in range(a):
                Lxx[a, b] = Lxx[b, a]
        for a in range(nu):
            for b in range(a):
                Luu[a, b] = Luu[b, a]


def _any_item(kinds):
    for k in range(kinds.shape[0]):
        if kinds[k] != BARRIER:
            return True
    return False


def _stack_values(r, lb, ub, act_w, starts, kinds, params, item_costs, item_weights):
    """:func:`activation_values`, then the items of another kind (:func:`_item_activations`); returns
    ``Σₖ wₖ costₖ`` (the barrier pass's own total when every item is of the barrier family)."""
    total = activation_values(r, lb, ub, act_w, starts, item_costs, item_weights)
    if not any_item(kinds):
        return total
    return item_activations(r, starts, kinds, params, item_costs, item_weights, r, r, False)


def _stack_derivatives_and_sums(r, lb, ub, act_w, weights, Ar, Arr, Jx, Ju, u_start, with_u, Lx, Lu, Lxx, Lxu, Luu,
                                cols, grad, starts, kinds, params, item_costs, item_weights):
    """:func:`derivatives_and_sums` with the items of another kind's ``Ar``, ``Arr`` (and costs) written between the
    barrier pass and the sums."""
    if not any_item(kinds):
        derivatives_and_sums(r, lb, ub, act_w, weights, Ar, Arr, Jx, Ju, u_start, with_u, Lx, Lu, Lxx, Lxu, Luu, cols)
        return
    activation_derivatives(r, lb, ub, act_w, Ar, Arr)
    item_activations(r, starts, kinds, params, item_costs, item_weights, Ar, Arr, True)
    accumulate(weights, Ar, Arr, Jx, Ju, u_start, with_u, Lx, Lu, Lxx, Lxu, Luu, cols)
    rank_one_sums(r, starts, kinds, params, item_weights, Jx, Ju, u_start, with_u, Lxx, Lxu, Luu, grad)


dense_terms = compiled(_dense_terms)
rank_one_sums = compiled(_rank_one_sums)
item_activations = compiled(_item_activations)
any_item = compiled(_any_item)
stack_values = compiled(_stack_values)
stack_derivatives_and_sums = compiled(_stack_derivatives_and_sums)
