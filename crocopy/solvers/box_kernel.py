"""Compiled Box-DDP backward pass (numba), twin of the numpy path of :mod:`~crocopy.solvers.box_ddp` and
:mod:`crocopy.solvers.box_qp`.

:func:`box_pass` runs the whole recursion in one call on the arrays of :mod:`.horizon`: the Riccati step of
:mod:`.riccati_kernel` at unbounded nodes (or on an infeasible iterate), and at a bounded node t with next
value function ``(V'x, V'xx)`` (Crocoddyl's signs) it computes the Q terms (as :mod:`.riccati_kernel`), solves
the box QP ``min ½ δuᵀ Quu δu + Quᵀ δu, lb ≤ δu ≤ ub`` by the same projected-Newton iteration as
:class:`crocopy.solvers.box_qp.BoxQP` (warm start ``warm * k``, i.e. ``-k``, or ``+k`` in Crocoddyl-compatible
mode; no extra regularisation; signed Armijo ratio ``th_acc`` over ``2^-n``; stop on ``‖g_f‖∞ ≤ th_grad``
after the step), sets ``k = -δu``, ``Quu_inv`` (free block inverse, zero-padded), ``K = Quu_inv Qux``, zeroes
the ``Qu`` entries of clamped controls unless ``general``, and updates the value function (general gradient
update when ``general`` and a control is clamped). The first node whose free block is not positive definite
stops the pass (its index is returned). Its numpy twin is
:meth:`~crocopy.solvers.box_ddp.BoxSolverMixin.computeGains` with :class:`~crocopy.solvers.box_qp.BoxQP`
between the Q terms and value function of :class:`~crocopy.solvers.ddp.SolverDDP`; :mod:`crocopy.kernels`
chooses.
"""

from __future__ import annotations

import numpy as np

from ..kernels import compiled
from .horizon import QUU_INV
from .riccati_kernel import (
    SMALL,
    cholesky_lower,
    finish_value_function,
    matrix_at,
    mul,
    node_arrays,
    node_riccati,
    q_arrays,
    q_terms,
    scratch,
    value_loops,
)


def _chol_inverse(H, idx, nf, out):
    """Inverse of ``H[idx, idx]`` (first ``nf`` entries of ``idx``) into ``out[:nf, :nf]``; False if not PD."""
    L = np.zeros((nf, nf))
    if not cholesky_lower(H, idx, nf, L):
        return False
    for c in range(nf):
        col = np.zeros(nf)
        col[c] = 1.0
        for i in range(nf):
            s = col[i]
            for p in range(i):
                s -= L[i, p] * col[p]
            col[i] = s / L[i, i]
        for i in range(nf - 1, -1, -1):
            s = col[i]
            for p in range(i + 1, nf):
                s -= L[p, i] * col[p]
            col[i] = s / L[i, i]
        for i in range(nf):
            out[i, c] = col[i]
    return True


def _free_set(x, g, lb, ub, free):
    n = x.size
    changed = False
    for j in range(n):
        f = not ((x[j] <= lb[j] and g[j] > 0.0) or (x[j] >= ub[j] and g[j] < 0.0))
        if f != free[j]:
            changed = True
        free[j] = f
    return changed


def _gradient(H, q, x, g):
    """``g = q + H x`` in loops."""
    for i in range(x.size):
        acc = 0.0
        for j in range(x.size):
            acc += H[i, j] * x[j]
        g[i] = q[i] + acc


def _box_qp(H, q, lb, ub, x, th_grad, th_acc, maxiter, free, Hinv):
    """Projected Newton in place on ``x`` (``reg = 0``); returns (ok, nfact, nf) with ``Hinv[:nf,:nf]`` for ``free``.

    ``th_acc`` is the signed Armijo ratio: ``+th_acceptStep`` (paper) or ``-th_acceptStep`` (Crocoddyl).
    """
    n = x.size
    idx = np.empty(n, dtype=np.int64)
    for j in range(n):
        x[j] = min(max(x[j], lb[j]), ub[j])
    dx = np.empty(n)
    xa = np.empty(n)
    g = np.empty(n)
    nf = -1
    nfact = 0
    for _ in range(maxiter):
        _gradient(H, q, x, g)
        changed = _free_set(x, g, lb, ub, free) or nf < 0
        if changed:
            nf = 0
            for j in range(n):
                if free[j]:
                    idx[nf] = j
                    nf += 1
        if nf == 0:
            break
        if changed:
            nfact += 1
            if not _chol_inverse(H, idx, nf, Hinv):
                return False, nfact, nf
        gmax = 0.0
        dx[:] = 0.0
        for a in range(nf):
            gmax = max(gmax, abs(g[idx[a]]))
            s = 0.0
            for b in range(nf):
                s += Hinv[a, b] * g[idx[b]]
            dx[idx[a]] = -s
        fold = 0.0
        for j in range(n):
            fold += x[j] * (g[j] + q[j])
        fold *= 0.5
        accepted = False
        alpha = 1.0
        for _i in range(10):
            for j in range(n):
                xa[j] = min(max(x[j] + alpha * dx[j], lb[j]), ub[j])
            fnew, decrease = 0.0, 0.0
            for i in range(n):
                acc = 0.0
                for j in range(n):
                    acc += H[i, j] * xa[j]
                fnew += 0.5 * xa[i] * acc + q[i] * xa[i]
                decrease += g[i] * (x[i] - xa[i])
            if fold - fnew >= th_acc * decrease:
                accepted = True
                break
            alpha *= 0.5
        if not accepted:
            break
        x[:] = xa
        if gmax <= th_grad:
            break
    if nf < 0:  # maxiter = 0
        _gradient(H, q, x, g)
        _free_set(x, g, lb, ub, free)
        nf = 0
        for j in range(n):
            if free[j]:
                idx[nf] = j
                nf += 1
        if nf > 0:
            nfact += 1
            if not _chol_inverse(H, idx, nf, Hinv):
                return False, nfact, nf
    return True, nfact, nf


def _box_gains_value(preg, fs, gaps, u, lb, ub, th_grad, th_acc, warm, maxiter, general, Qxx, Qxu, Quu, Qx, Qu, K,
                     k, Quu_inv, Vxx, Vx):
    """A bounded node after its Q terms: the box QP, the gains and the value function; ``(ok, nfact, clamped)``."""
    nu = Quu.shape[0]
    x = warm * k
    free = np.empty(nu, dtype=np.bool_)
    Hinv = np.zeros((nu, nu))
    ok, nfact, nf = _box_qp(Quu, Qu, lb - u, ub - u, x, th_grad, th_acc, maxiter, free, Hinv)
    if not ok:
        return False, nfact, False
    k[:] = -x
    Quu_inv[:, :] = 0.0
    a = 0
    fidx = np.empty(nf, dtype=np.int64)
    for j in range(nu):
        if free[j]:
            fidx[a] = j
            a += 1
    for a in range(nf):
        for b in range(nf):
            Quu_inv[fidx[a], fidx[b]] = Hinv[a, b]
    small = Qxx.shape[0] <= SMALL
    if small:
        mul(Quu_inv, Qxu.T, K, False)
    else:
        K[:, :] = Quu_inv @ Qxu.T
    clamped = nf < nu
    if clamped and not general:
        for j in range(nu):
            if not free[j]:
                Qu[j] = 0.0
    if small:
        value_loops(Qxx, Qxu, Qx, Qu, K, Vxx, Vx)
    else:
        Vxx[:, :] = Qxx - Qxu @ K
        Vx[:] = Qx - K.T @ Qu
    if clamped and general:
        Vx[:] += K.T @ (Quu @ k) - Qxu @ k
    finish_value_function(Vxx, Vx, preg, fs, gaps)
    return True, nfact, clamped


_chol_inverse = compiled(_chol_inverse)
_free_set = compiled(_free_set)
_gradient = compiled(_gradient)
_box_qp = compiled(_box_qp)
box_gains_value = compiled(_box_gains_value)


def _box_pass(daddr, saddr, dims, preg, gaps, boxed, lb, ub, u, uoff, th_grad, th_acc, warm, maxiter, general,
              clamped, counts):
    """The whole backward pass on the arrays listed by address (:mod:`.horizon`): the box QP at the nodes where
    ``boxed[t]``, the Riccati step elsewhere.  ``lb``, ``ub``, ``u``: the stacked bounds and controls (node t
    at ``uoff[t]``); ``clamped[t]`` is set per node, ``(factorizations, QP solves)`` added to ``counts``.
    Returns -1, or the first node whose gains failed."""
    S, idx = scratch(dims)
    for t in range(dims.shape[0] - 2, -1, -1):
        if not boxed[t]:
            clamped[t] = False
            if not node_riccati(daddr, saddr, dims, t, preg, gaps, S, idx):
                return t
            continue
        m, a = dims[t, 1], uoff[t]
        Fx, Fu, Lxx, Lxu, Luu, Lx, Lu, Vxx_n, Vx_n, fs = node_arrays(daddr, saddr, dims, t)
        Qxx, Qxu, Quu, Qx, Qu, K, k, Vxx, Vx = q_arrays(saddr, dims, t)
        q_terms(Fx, Fu, Lxx, Lxu, Luu, Lx, Lu, Vxx_n, Vx_n, preg, Qxx, Qxu, Quu, Qx, Qu, S)
        ok, nfact, clamped[t] = box_gains_value(
            preg, fs, gaps, u[a:a + m], lb[a:a + m], ub[a:a + m], th_grad, th_acc, warm, maxiter, general, Qxx, Qxu,
            Quu, Qx, Qu, K, k, matrix_at(saddr[t, QUU_INV], m, m), Vxx, Vx,
        )
        counts[0] += nfact
        counts[1] += 1
        if not ok:
            return t
    return -1


box_pass = compiled(_box_pass)
