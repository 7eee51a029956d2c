"""Compiled activation and accumulation steps of :class:`~crocopy.costs.stack.CostStack` (numba).

Twins of the numpy steps in :mod:`crocopy.costs.stack`, same maths (rows ``i``, items ``k``)::

    eᵢ = rᵢ - clip(rᵢ, lbᵢ, ubᵢ),   costₖ = ½ Σ_{i ∈ k} aᵢ eᵢ²,   cost = Σₖ wₖ costₖ
    Arᵢ = aᵢ eᵢ,   Arrᵢ = aᵢ [rᵢ ≤ lbᵢ or rᵢ ≥ ubᵢ]
    Lx = Jxᵀ (w ∘ Ar),   Lxx = Jxᵀ diag(w ∘ Arr) Jx,   Lu, Lxu, Luu likewise with the ``Ju`` rows

One call replaces a dozen small numpy calls, and rows whose weighted curvature is zero (a barrier
row inside its bounds, an inactive item) are left out of the matrix products.  ``available`` is
False when numba cannot be imported; :class:`~crocopy.costs.stack.CostStack` then uses its numpy
steps, which give the same numbers to round-off (tested).
"""

from __future__ import annotations

import numpy as np

try:
    from numba import njit
except ImportError:  # pragma: no cover - exercised only without numba
    njit = None

available = njit is not None


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


if available:
    activation_values = njit(cache=True)(_activation_values)
    activation_derivatives = njit(cache=True)(_activation_derivatives)
    accumulate = njit(cache=True)(_accumulate)
else:  # pragma: no cover - exercised only without numba
    activation_values, activation_derivatives, accumulate = _activation_values, _activation_derivatives, _accumulate
