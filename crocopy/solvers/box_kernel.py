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

from ..kernels import compiled, matrix_at
from .horizon import QUU_INV
from .riccati_kernel import (
    SMALL,
    action_value_function,
    back_substitution,
    cholesky_lower,
    finish_value_function,
    forward_substitution,
    node_arrays,
    node_riccati,
    q_arrays,
    q_terms_loops,
    scratch,
    value_blas,
    value_loops,
)


def _chol_inverse(H, idx, nf, out, L, col):
    """Inverse of ``H[idx, idx]`` (first ``nf`` entries of ``idx``) into ``out[:nf, :nf]``; False if not PD.

    Column ``c`` is the Cholesky solve of the unit vector ``e_c``, whose forward substitution leaves the entries
    above ``c`` at zero: it starts at row ``c`` (the same numbers, a third fewer operations).
    Scratch: ``L`` (at least ``nf × nf``), ``col`` (at least ``nf``)."""
    if not cholesky_lower(H, idx, nf, L):
        return False
    for c in range(nf):
        for i in range(nf):
            col[i] = 0.0
        col[c] = 1.0
        forward_substitution(L, nf, col, c)
        back_substitution(L, nf, col)
        for i in range(nf):
            out[i, c] = col[i]
    return True


def _free_set(n, x, g, lb, ub, free):
    changed = False
    for j in range(n):
        f = not ((x[j] <= lb[j] and g[j] > 0.0) or (x[j] >= ub[j] and g[j] < 0.0))
        if f != free[j]:
            changed = True
        free[j] = f
    return changed


def _gradient(n, H, q, x, g):
    """``g = q + H x`` in loops (first ``n`` entries)."""
    for i in range(n):
        acc = 0.0
        for j in range(n):
            acc += H[i, j] * x[j]
        g[i] = q[i] + acc


def _free_index(n, free, idx):
    """The free entries' indices into ``idx``; their number."""
    nf = 0
    for j in range(n):
        if free[j]:
            idx[nf] = j
            nf += 1
    return nf


def _box_qp(H, q, lb, ub, th_grad, th_acc, maxiter, W, idx, free, Hinv, L):
    """Projected Newton in place on ``x = W[0, :n]`` (``reg = 0``, ``n = H.shape[0]``); returns (ok, nfact, nf)
    with ``Hinv[:nf,:nf]`` for ``free[:n]`` (indices ``idx[:nf]``).

    ``th_acc`` is the signed Armijo ratio: ``+th_acceptStep`` (paper) or ``-th_acceptStep`` (Crocoddyl).
    Scratch, allocated once per pass: rows 1-4 of ``W`` (at least ``(5, n)``), ``L`` (at least ``n × n``).
    """
    n = H.shape[0]
    x, dx, xa, g, col = W[0], W[1], W[2], W[3], W[4]
    for j in range(n):
        x[j] = min(max(x[j], lb[j]), ub[j])
    nf = -1
    nfact = 0
    for _ in range(maxiter):
        _gradient(n, H, q, x, g)
        changed = _free_set(n, x, g, lb, ub, free) or nf < 0
        if changed:
            nf = _free_index(n, free, idx)
        if nf == 0:
            break
        if changed:
            nfact += 1
            if not _chol_inverse(H, idx, nf, Hinv, L, col):
                return False, nfact, nf
        gmax = 0.0
        for j in range(n):
            dx[j] = 0.0
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
        for j in range(n):
            x[j] = xa[j]
        if gmax <= th_grad:
            break
    if nf < 0:  # maxiter = 0
        _gradient(n, H, q, x, g)
        _free_set(n, x, g, lb, ub, free)
        nf = _free_index(n, free, idx)
        if nf > 0:
            nfact += 1
            if not _chol_inverse(H, idx, nf, Hinv, L, col):
                return False, nfact, nf
    return True, nfact, nf


def _box_gains_value(preg, fs, gaps, u, lb, ub, th_grad, th_acc, warm, maxiter, general, Qxx, Qxu, Quu, Qx, Qu, K,
                     k, Quu_inv, Vxx, Vx, W, idx, free, Hinv, L):
    """A bounded node after its Q terms: the box QP, the gains and the value function; ``(ok, nfact, clamped)``.

    Scratch (allocated once per pass by :func:`box_scratch`, sized by the largest node): ``W`` (at least
    ``(7, nu)``), ``idx``, ``free`` (at least ``nu``), ``Hinv``, ``L`` (at least ``nu × nu``)."""
    nu = Quu.shape[0]
    x, lbu, ubu = W[0], W[5], W[6]
    for j in range(nu):
        x[j] = warm * k[j]
        lbu[j] = lb[j] - u[j]
        ubu[j] = ub[j] - u[j]
    ok, nfact, nf = _box_qp(Quu, Qu, lbu, ubu, th_grad, th_acc, maxiter, W, idx, free, Hinv, L)
    if not ok:
        return False, nfact, False
    Quu_inv[:, :] = 0.0
    for j in range(nu):
        k[j] = -x[j]
    for a in range(nf):
        for b in range(nf):
            Quu_inv[idx[a], idx[b]] = Hinv[a, b]
    small = Qxx.shape[0] <= SMALL
    if small:
        mul_bt(Quu_inv, Qxu, K)
    else:
        np.dot(Quu_inv, Qxu.T, K)
    clamped = nf < nu
    if clamped and not general:
        for j in range(nu):
            if not free[j]:
                Qu[j] = 0.0
    if small:
        value_loops(Qxx, Qxu, Qx, Qu, K, Vxx, Vx)
    else:
        value_blas(Qxx, Qxu, Qx, Qu, K, Vxx, Vx)
    if clamped and general:
        _general_gradient(Quu, Qxu, K, k, Vx, W[1])
    finish_value_function(Vxx, Vx, preg, fs, gaps)
    return True, nfact, clamped


def _general_gradient(Quu, Qxu, K, k, Vx, w):
    """``Vx += Kᵀ (Quu k) - Qxu k`` in loops (scratch ``w``, at least ``nu``)."""
    nu, n = K.shape[0], K.shape[1]
    for i in range(nu):
        acc = 0.0
        for j in range(nu):
            acc += Quu[i, j] * k[j]
        w[i] = acc
    for i in range(n):
        acc = 0.0
        for j in range(nu):
            acc += K[j, i] * w[j] - Qxu[i, j] * k[j]
        Vx[i] += acc


def _mul_bt(A, B, C):
    """``C = A Bᵀ`` in loops."""
    for i in range(A.shape[0]):
        for j in range(B.shape[0]):
            acc = 0.0
            for p in range(A.shape[1]):
                acc += A[i, p] * B[j, p]
            C[i, j] = acc


def _box_scratch(dims):
    """Scratch of :func:`box_gains_value` for every node of ``dims``: ``W, idx, free, Hinv, L``."""
    m = 1
    for t in range(dims.shape[0]):
        m = max(m, dims[t, 1])
    return (np.empty((7, m)), np.empty(m, dtype=np.int64), np.zeros(m, dtype=np.bool_), np.zeros((m, m)),
            np.zeros((m, m)))


_chol_inverse = compiled(_chol_inverse)
_free_set = compiled(_free_set)
_gradient = compiled(_gradient)
_free_index = compiled(_free_index)
_box_qp = compiled(_box_qp)
_general_gradient = compiled(_general_gradient)
mul_bt = compiled(_mul_bt)
box_scratch = compiled(_box_scratch)
box_gains_value = compiled(_box_gains_value)


def _box_pass(daddr, saddr, dims, preg, gaps, boxed, lb, ub, u, uoff, th_grad, th_acc, warm, maxiter, general,
              clamped, counts):
    """The whole backward pass on the arrays listed by address (:mod:`.horizon`): the box QP at the nodes where
    ``boxed[t]``, the Riccati step elsewhere.  ``lb``, ``ub``, ``u``: the stacked bounds and controls (node t
    at ``uoff[t]``); ``clamped[t]`` is set per node, ``(factorizations, QP solves)`` added to ``counts``.
    Returns -1, or the first node whose gains failed."""
    S, idx = scratch(dims)
    W, bidx, free, Hinv, L = box_scratch(dims)
    for t in range(dims.shape[0] - 2, -1, -1):
        if not boxed[t]:
            clamped[t] = False
            if not node_riccati(daddr, saddr, dims, t, preg, gaps, S, idx):
                return t
            continue
        m, a = dims[t, 1], uoff[t]
        Fx, Fu, Lxx, Lxu, Luu, Lx, Lu, Vxx_n, Vx_n, fs = node_arrays(daddr, saddr, dims, t)
        Qxx, Qxu, Quu, Qx, Qu, K, k, Vxx, Vx = q_arrays(saddr, dims, t)
        if dims[t + 1, 0] <= SMALL:
            n, n1, at = dims[t, 0], dims[t + 1, 0], S.ctypes.data
            q_terms_loops(Fx, Fu, Lxx, Lxu, Luu, Lx, Lu, Vxx_n, Vx_n, preg, Qxx, Qxu, Quu, Qx, Qu,
                          matrix_at(at, n, n1), matrix_at(at + 8 * n * n1, m, n1))
        else:
            action_value_function(Fx, Fu, Lxx, Lxu, Luu, Lx, Lu, Vxx_n, Vx_n, preg, Qxx, Qxu, Quu, Qx, Qu)
        ok, nfact, clamped[t] = box_gains_value(
            preg, fs, gaps, u[a:a + m], lb[a:a + m], ub[a:a + m], th_grad, th_acc, warm, maxiter, general, Qxx, Qxu,
            Quu, Qx, Qu, K, k, matrix_at(saddr[t, QUU_INV], m, m), Vxx, Vx, W, bidx, free, Hinv, L,
        )
        counts[0] += nfact
        counts[1] += 1
        if not ok:
            return t
    return -1


box_pass = compiled(_box_pass)
