"""SolverIntro's constrained backward pass in one compiled call (numba), twin of the Python node steps of
:class:`~crocopy.solvers.intro.SolverIntro` (``computeActionValueFunction``, ``_constrained_gains``,
``_schur_gains``, ``_constrained_value_function``).

:func:`intro_pass` runs the recursion t = T-1..0 on the arrays listed by address: the solver's stacked
buffers and the nodes' derivatives (:mod:`.horizon`), the datas' equality rows ``h, Hx, Hu`` (``raddr``,
``nh[t]`` rows each) and the per-node read-outs (``oaddr``, columns :data:`YZ` ... :data:`QUZ`, laid out by
:class:`~crocopy.solvers.intro_buffers.IntroBuffers`; the shapes of the nullspace ones follow the rank written into
``ranks[t]``); the caller has set the terminal value function (``SolverDDP._terminal_value_function``, as before
FDDP's pass).  A node without rows or without controls takes FDDP's step
(:func:`~crocopy.solvers.riccati_kernel.node_riccati`); a node with both enforces its rows by ``method``
(:data:`LU_NULL`, :data:`QR_NULL`, :data:`SCHUR`), each step the twin's (see :mod:`.intro`):

* nullspace: ``[Y Z]`` by the fully pivoted LU of ``Hu`` or by the column-pivoted Householder QR of ``Huᵀ``
  (:mod:`.intro_kernel`), ``[ks Ks] = Hy⁺ [h Hx]`` by Householder least squares (:mod:`.householder_kernel`), the
  reduced Hessian ``Qzz`` by Cholesky (:func:`~crocopy.solvers.riccati_kernel.cholesky_lower`);
* Schur: Cholesky of ``Quu`` and of ``Qzz = Hu Quu⁻¹ Huᵀ``.

The value function is the Q-function along the policy, symmetrised, ``preg``-shifted and gap-deflected
(:func:`~crocopy.solvers.riccati_kernel.finish_value_function`).  The pass returns ``(-1, OK)`` or the first
node (from the end) that failed and why (:data:`QUU_NOT_PD` ... :data:`NONFINITE_VALUE`): the caller raises
what the twin raises there.

:func:`row_norm` gives ``hfeas``, the norm of every node's ``h`` (twin: ``SolverAbstract._norm`` of them).
"""

from __future__ import annotations

import numpy as np

from ..kernels import compiled, matrix_at, uncounted, vector_at
from .horizon import VX, VXX
from .householder_kernel import least_squares
from .intro_kernel import lu_basis, qr_basis
from .riccati_kernel import (
    SMALL,
    action_value_function,
    cholesky_lower,
    finish_value_function,
    node_arrays,
    node_riccati,
    q_arrays,
    q_terms_loops,
    scratch,
    triangular_solve,
)

LU_NULL, QR_NULL, SCHUR = 0, 1, 2
"""``method``: the values of :class:`~crocopy.solvers.intro.EqualitySolverType`."""

OK, QUU_NOT_PD, QZZ_NOT_PD, SCHUR_QUU_NOT_PD, SCHUR_SINGULAR, NONFINITE_ROWS, NONFINITE_VALUE = range(7)
"""Outcome of a node: FDDP's gains failed (a node without rows), the reduced Hessian is not positive definite,
Schur's ``Quu`` is not, the Schur complement is singular (or not finite), the equality rows are not finite,
the value function is not finite."""

YZ, HY, KS, KSM, KZ, KZM, QZ, QZZ, QXZ, QUZ = range(10)
"""Columns of ``oaddr``: where the read-outs ``YZ, Hy, ks, Ks, kz, Kz, Qz, Qzz, Qxz, Quz`` of a node start."""
NR = 10


def _finite(A):
    for i in range(A.shape[0]):
        for j in range(A.shape[1]):
            if not abs(A[i, j]) < np.inf:
                return False
    return True


def _finite1(a):
    for i in range(a.shape[0]):
        if not abs(a[i]) < np.inf:
            return False
    return True


finite = uncounted(_finite)
finite1 = uncounted(_finite1)


def _nullspace_gains(h, Hx, Hu, Qu, Qxu, Quu, k, K, o, method, rtol, W, rows, cols, ident):
    """The nullspace step of a node (``o``: its read-out addresses, ``W``: scratch, ``ident``: ``0, 1, ...``);
    returns ``(outcome, rank)``."""
    p, m = Hu.shape
    n = Hx.shape[1]
    at = W.ctypes.data
    basis = matrix_at(o[YZ], m, m)
    if method == LU_NULL:
        r = lu_basis(Hu, matrix_at(at, p, m), rows, cols, rtol, basis)
    else:
        if not finite(Hu):
            return NONFINITE_ROWS, 0
        q = max(m, p)
        r = qr_basis(
            Hu,
            matrix_at(at, m, p),
            W[m * p : m * p + q],
            W[m * p + q : m * p + 2 * q],
            W[m * p + 2 * q : m * p + 3 * q],
            rtol,
            basis,
        )
    nz = m - r
    Hy, ks, Ks = matrix_at(o[HY], p, r), vector_at(o[KS], r), matrix_at(o[KSM], r, n)
    Yks, YKs = vector_at(o[KZ], m), matrix_at(o[KZM], m, n)
    Qz, Qzz, Qxz, Quz = (
        vector_at(o[QZ], nz),
        matrix_at(o[QZZ], nz, nz),
        matrix_at(o[QXZ], n, nz),
        matrix_at(o[QUZ], m, nz),
    )
    for a in range(p):
        for j in range(r):
            acc = 0.0
            for i in range(m):
                acc += Hu[a, i] * basis[i, j]
            Hy[a, j] = acc
    if r > 0:
        if not (finite(Hy) and finite1(h) and finite(Hx)):
            return NONFINITE_ROWS, r
        least_squares(Hy, h, Hx, matrix_at(at, p, r), matrix_at(at + 8 * p * r, p, n + 1), ks, Ks)
    for i in range(m):
        acc = 0.0
        for x in range(n):
            YKs[i, x] = 0.0
        for j in range(r):
            y = basis[i, j]
            acc += y * ks[j]
            for x in range(n):
                YKs[i, x] += y * Ks[j, x]
        Yks[i] = acc
    R = matrix_at(at + 8 * nz * nz, nz, 1 + n + m)  # [Qz  Qxzᵀ  Quzᵀ] before Qzz⁻¹, solved at once
    ZT = matrix_at(at + 8 * nz * (nz + 1 + n + m), nz, m)
    for a in range(nz):
        for i in range(m):
            ZT[a, i] = basis[i, r + a]
    for a in range(nz):
        for c in range(1 + n + m):
            R[a, c] = 0.0
        for j in range(m):  # (Quu Z)ᵀ = Zᵀ Quu
            z = ZT[a, j]
            for i in range(m):
                R[a, 1 + n + i] += z * Quu[j, i]
        acc = 0.0
        for i in range(m):
            z, q = ZT[a, i], R[a, 1 + n + i]
            acc += z * Qu[i] - q * Yks[i]
            for x in range(n):
                R[a, 1 + x] += z * Qxu[x, i] - q * YKs[i, x]
        R[a, 0] = acc
        for c in range(nz):
            acc = 0.0
            for i in range(m):
                acc += R[a, 1 + n + i] * ZT[c, i]
            Qzz[a, c] = acc
    if nz > 0:
        L = matrix_at(at, nz, nz)
        if not cholesky_lower(Qzz, ident, nz, L):
            return QZZ_NOT_PD, r
        triangular_solve(L, R, False)
        triangular_solve(L, R, True)
    for i in range(m):
        k[i] = Yks[i]
        for x in range(n):
            K[i, x] = YKs[i, x]
    for a in range(nz):
        Qz[a] = R[a, 0]
        for x in range(n):
            Qxz[x, a] = R[a, 1 + x]
        for i in range(m):
            z = ZT[a, i]
            Quz[i, a] = R[a, 1 + n + i]
            k[i] += z * R[a, 0]
            for x in range(n):
                K[i, x] += z * R[a, 1 + x]
    return OK, r


nullspace_gains = uncounted(_nullspace_gains)


def _schur_gains(h, Hx, Hu, Qu, Qxu, Quu, k, K, o, W, ident):
    """The Schur-complement step of a node (``o``: its read-out addresses, ``W``: scratch, ``ident``: ``0, 1, ...``);
    returns the outcome."""
    p, m = Hu.shape
    n = Hx.shape[1]
    at = W.ctypes.data
    L = matrix_at(at, m, m)
    if not cholesky_lower(Quu, ident, m, L):
        return SCHUR_QUU_NOT_PD
    at += 8 * m * m
    B = matrix_at(at, m, p + 1 + n)  # Quu⁻¹ [Huᵀ  Qu  Qux]
    at += 8 * m * (p + 1 + n)
    LAM = matrix_at(at, p, 1 + n)  # Qzz⁻¹ [ks  Ks]
    at += 8 * p * (1 + n)
    Lz = matrix_at(at, p, p)
    for i in range(m):
        for a in range(p):
            B[i, a] = Hu[a, i]
        B[i, p] = Qu[i]
        for x in range(n):
            B[i, p + 1 + x] = Qxu[x, i]
    triangular_solve(L, B, False)
    triangular_solve(L, B, True)
    ks, Ks, Qzz = vector_at(o[KS], p), matrix_at(o[KSM], p, n), matrix_at(o[QZZ], p, p)
    for a in range(p):
        for b in range(p):
            Qzz[a, b] = 0.0
        LAM[a, 0] = h[a]
        for x in range(n):
            LAM[a, 1 + x] = Hx[a, x]
        for i in range(m):
            u = Hu[a, i]
            for b in range(p):
                Qzz[a, b] += u * B[i, b]
            for c in range(n + 1):
                LAM[a, c] -= u * B[i, p + c]
        ks[a] = LAM[a, 0]
        for x in range(n):
            Ks[a, x] = LAM[a, 1 + x]
    if not (finite(Qzz) and finite(LAM)) or not cholesky_lower(Qzz, ident, p, Lz):
        return SCHUR_SINGULAR
    triangular_solve(Lz, LAM, False)
    triangular_solve(Lz, LAM, True)
    for i in range(m):
        for c in range(n + 1):
            acc = B[i, p + c]
            for a in range(p):
                acc += B[i, a] * LAM[a, c]
            if c == 0:
                k[i] = acc
            else:
                K[i, c - 1] = acc
    for name, rows_, cols_ in ((YZ, m, m), (HY, p, p), (QXZ, n, p), (QUZ, m, p), (KZM, m, n)):
        Z = matrix_at(o[name], rows_, cols_)
        for i in range(rows_):
            for j in range(cols_):
                Z[i, j] = 0.0
    for name, size in ((QZ, p), (KZ, m)):
        z = vector_at(o[name], size)
        for i in range(size):
            z[i] = 0.0
    return OK


schur_gains = uncounted(_schur_gains)


def _constrained_value(Qxx, Qxu, Quu, Qx, Qu, K, k, Vxx, Vx, G):
    """``Vx = Qx - Kᵀ Qu - Qxu k + Kᵀ Quu k``, ``Vxx = Qxx - Qxu K - Kᵀ Qux + Kᵀ Quu K``, as
    ``Vx = Qx - Kᵀ Qu + Gᵀ k``, ``Vxx = Qxx - Qxu K + Kᵀ G`` with ``G = Quu K - Qux`` (scratch ``(nu, ndx)``; rows
    innermost, so that the loops vectorise)."""
    n, m = Qxu.shape
    for i in range(m):
        for x in range(n):
            G[i, x] = -Qxu[x, i]
        for j in range(m):
            a = Quu[i, j]
            for x in range(n):
                G[i, x] += a * K[j, x]
    for x in range(n):
        Vx[x] = Qx[x]
        for y in range(n):
            Vxx[x, y] = Qxx[x, y]
    for i in range(m):
        a, b = k[i], Qu[i]
        for x in range(n):
            Vx[x] += G[i, x] * a - K[i, x] * b
    for x in range(n):
        for i in range(m):
            a, b = Qxu[x, i], K[i, x]
            for y in range(n):
                Vxx[x, y] += b * G[i, y] - a * K[i, y]


constrained_value = uncounted(_constrained_value)


def _node_constrained(daddr, saddr, dims, t, raddr, p, o, preg, gaps, method, rtol, S, W, rows, cols, ident):
    """Node ``t`` with ``p`` equality rows: Q terms, gains by ``method``, value function; ``(outcome, rank)``."""
    n, m, n1 = dims[t, 0], dims[t, 1], dims[t + 1, 0]
    Fx, Fu, Lxx, Lxu, Luu, Lx, Lu, Vxx_n, Vx_n, fs = node_arrays(daddr, saddr, dims, t)
    Qxx, Qxu, Quu, Qx, Qu, K, k, Vxx, Vx = q_arrays(saddr, dims, t)
    if n1 > SMALL:
        action_value_function(Fx, Fu, Lxx, Lxu, Luu, Lx, Lu, Vxx_n, Vx_n, preg, Qxx, Qxu, Quu, Qx, Qu)
    else:
        at = S.ctypes.data
        q_terms_loops(
            Fx,
            Fu,
            Lxx,
            Lxu,
            Luu,
            Lx,
            Lu,
            Vxx_n,
            Vx_n,
            preg,
            Qxx,
            Qxu,
            Quu,
            Qx,
            Qu,
            matrix_at(at, n, n1),
            matrix_at(at + 8 * n * n1, m, n1),
        )
    h, Hx, Hu = vector_at(raddr[t, 0], p), matrix_at(raddr[t, 1], p, n), matrix_at(raddr[t, 2], p, m)
    r = 0
    if method == SCHUR:
        outcome = schur_gains(h, Hx, Hu, Qu, Qxu, Quu, k, K, o, W, ident)
    else:
        outcome, r = nullspace_gains(h, Hx, Hu, Qu, Qxu, Quu, k, K, o, method, rtol, W, rows, cols, ident)
    if outcome != OK:
        return outcome, r
    constrained_value(Qxx, Qxu, Quu, Qx, Qu, K, k, Vxx, Vx, matrix_at(W.ctypes.data, m, n))
    finish_value_function(Vxx, Vx, preg, fs, gaps)
    return OK, r


node_constrained = uncounted(_node_constrained)


def _work_size(dims, nh):
    """Scratch for :func:`node_constrained` at every node (the largest of its uses)."""
    size = 1
    for t in range(nh.shape[0]):
        n, m, p = dims[t, 0], dims[t, 1], nh[t]
        q = max(m, p)
        lu_qr = m * p + 3 * q  # LU's U, or QR's A, tau, vn1, vn2
        lsq = p * q + p * (n + 1)
        reduced = m * m + m * (1 + n + m) + m * m  # L, R, ZT of the nullspace step
        schur = m * m + m * (p + 1 + n) + p * (1 + n) + p * p  # L, B, LAM, Lz
        size = max(size, lu_qr, lsq, reduced, schur, m * n)
    return size


def _intro_pass(daddr, saddr, dims, raddr, nh, oaddr, ranks, preg, gaps, method, th_rank):
    """The whole constrained recursion (t = T-1..0); ``(-1, OK)`` or the first node that failed and why."""
    S, idx = scratch(dims)
    T = dims.shape[0] - 1
    q = 1
    for t in range(T):
        q = max(q, dims[t, 1], nh[t])
    W = np.empty(work_size(dims, nh))
    rows = np.empty(q, dtype=np.int64)
    cols = np.empty(q, dtype=np.int64)
    ident = np.arange(q)
    for t in range(T - 1, -1, -1):
        n, m, p = dims[t, 0], dims[t, 1], nh[t]
        if m > 0 and p > 0:
            rtol = th_rank * min(p, m)
            outcome, r = node_constrained(
                daddr, saddr, dims, t, raddr, p, oaddr[t], preg, gaps, method, rtol, S, W, rows, cols, ident
            )
            ranks[t] = r
            if method == SCHUR and outcome == OK:
                ranks[t] = np.linalg.matrix_rank(matrix_at(raddr[t, 2], p, m))
            if outcome != OK:
                return t, outcome
        elif not node_riccati(daddr, saddr, dims, t, preg, gaps, S, idx):
            return t, QUU_NOT_PD
        o = saddr[t]
        if not (finite1(vector_at(o[VX], n)) and finite(matrix_at(o[VXX], n, n))):
            return t, NONFINITE_VALUE
    return -1, OK


work_size = compiled(_work_size)
intro_pass = compiled(_intro_pass)


def _row_norm(raddr, rows, linf):
    """The norm of every listed ``h`` (``rows[t]`` entries at ``raddr[t, 0]``): ``max |h|`` if ``linf`` (NaN if one is
    NaN, as numpy's), else ``Σ |h|``; 0 when there are none."""
    total = 0.0
    for t in range(rows.shape[0]):
        h = vector_at(raddr[t, 0], rows[t])
        for i in range(rows[t]):
            a = abs(h[i])
            if not linf:
                total += a
            elif a > total or a != a:
                total = a
                if a != a:
                    return a
    return total


row_norm = compiled(_row_norm)
