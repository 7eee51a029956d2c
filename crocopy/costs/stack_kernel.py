"""Activation and accumulation steps of :class:`~crocopy.costs.stack.CostStack`: numba kernels and numpy twins.

Both compute (rows ``i``, items ``k``)::

    eᵢ = rᵢ - clip(rᵢ, lbᵢ, ubᵢ),   costₖ = ½ Σ_{i ∈ k} aᵢ eᵢ²,   cost = Σₖ wₖ costₖ
    Arᵢ = aᵢ eᵢ,   Arrᵢ = aᵢ [rᵢ ≤ lbᵢ or rᵢ ≥ ubᵢ]
    Lx = Jxᵀ (w ∘ Ar),   Lxx = Jxᵀ diag(w ∘ Arr) Jx,   Lu, Lxu, Luu likewise with the ``Ju`` rows

:func:`derivatives_and_sums` runs the last two in one call (the stack's ``calcDiff`` when every
activation is fused).  One call replaces a dozen small numpy calls, and rows whose weighted curvature is zero (a barrier
row inside its bounds, an inactive item) are left out of the matrix products.  Each kernel has a
numpy twin (``*_numpy``, same arguments) giving the same numbers to round-off (tested);
:mod:`crocopy.kernels` chooses.
"""

from __future__ import annotations

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


def accumulate_numpy(weights, Ar, Arr, Jx, Ju, u_start, with_u, Jc, Hx, Juc, Hu, Lx, Lu, Lxx, Lxu, Luu) -> None:
    """Numpy twin of :func:`accumulate` (uses ``Hx``/``Hu`` as scratch; ``Jc``/``Juc`` unused)."""
    wArr = weights * Arr
    np.dot(Jx.T, weights * Ar, out=Lx)
    np.multiply(wArr[:, None], Jx, out=Hx)
    np.dot(Jx.T, Hx, out=Lxx)
    if with_u:
        np.dot(Ju.T, (weights * Ar)[u_start:], out=Lu)
        np.multiply(wArr[u_start:, None], Ju, out=Hu)
        np.dot(Jx[u_start:].T, Hu, out=Lxu)
        np.dot(Ju.T, Hu, out=Luu)


def derivatives_and_sums_numpy(r, lb, ub, act_w, weights, Ar, Arr, Jx, Ju, u_start, with_u, Jc, Hx, Juc, Hu,
                               Lx, Lu, Lxx, Lxu, Luu) -> None:
    """Numpy twin of :func:`derivatives_and_sums`."""
    activation_derivatives_numpy(r, lb, ub, act_w, Ar, Arr)
    accumulate_numpy(weights, Ar, Arr, Jx, Ju, u_start, with_u, Jc, Hx, Juc, Hu, Lx, Lu, Lxx, Lxu, Luu)


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


def _accumulate(weights, Ar, Arr, Jx, Ju, u_start, with_u, Jc, Hx, Juc, Hu, Lx, Lu, Lxx, Lxu, Luu):
    """Weighted Gauss-Newton sums; ``Jc``/``Hx``/``Juc``/``Hu`` are scratch of the shapes of ``Jx``/``Ju``."""
    nr, ndx = Jx.shape
    nu = Ju.shape[1]
    if nu == 0:
        with_u = False
    Lx[:] = 0.0
    if with_u:
        Lu[:] = 0.0
    k = 0
    ku = 0
    for i in range(nr):
        g = weights[i] * Ar[i]
        h = weights[i] * Arr[i]
        u_row = with_u and i >= u_start
        if g != 0.0:
            for j in range(ndx):
                Lx[j] += g * Jx[i, j]
            if u_row:
                for j in range(nu):
                    Lu[j] += g * Ju[i - u_start, j]
        if h != 0.0:
            for j in range(ndx):
                Jc[k, j] = Jx[i, j]
                Hx[k, j] = h * Jx[i, j]
            k += 1
            if u_row:
                for j in range(nu):
                    Juc[ku, j] = Ju[i - u_start, j]
                    Hu[ku, j] = h * Ju[i - u_start, j]
                ku += 1
    if k > 0:
        np.dot(Jc[:k].T, Hx[:k], Lxx)
    else:
        Lxx[:, :] = 0.0
    if with_u:
        if ku > 0:
            np.dot(Jc[k - ku : k].T, Hu[:ku], Lxu)
            np.dot(Juc[:ku].T, Hu[:ku], Luu)
        else:
            Lxu[:, :] = 0.0
            Luu[:, :] = 0.0


activation_values = compiled(_activation_values)
activation_derivatives = compiled(_activation_derivatives)
accumulate = compiled(_accumulate)


def _derivatives_and_sums(r, lb, ub, act_w, weights, Ar, Arr, Jx, Ju, u_start, with_u, Jc, Hx, Juc, Hu,
                          Lx, Lu, Lxx, Lxu, Luu):
    """:func:`activation_derivatives` then :func:`accumulate`, one call from Python."""
    activation_derivatives(r, lb, ub, act_w, Ar, Arr)
    accumulate(weights, Ar, Arr, Jx, Ju, u_start, with_u, Jc, Hx, Juc, Hu, Lx, Lu, Lxx, Lxu, Luu)


derivatives_and_sums = compiled(_derivatives_and_sums)
