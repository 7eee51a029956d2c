"""Compiled Riccati backward pass (numba), twin of the pure-numpy node steps in :mod:`.ddp`.

:func:`riccati_pass` runs the whole recursion, t = T-1..0, in one call on the arrays listed by address
(:mod:`.horizon`).  For node t with next value function ``(V'x, V'xx)`` (Crocoddyl signs)::

    Qx = Lx + Fxᵀ V'x,  Qu = Lu + Fuᵀ V'x,  Qxx = Lxx + (Fxᵀ V'xx) Fx,
    Qxu = Lxu + (Fxᵀ V'xx) Fu,  Quu = Luu + (Fuᵀ V'xx) Fu + preg I,
    [k K] = Quu⁻¹ [Qu Qux]  (Cholesky Quu = L Lᵀ and two triangular solves),
    Vx = Qx - Kᵀ Qu,  Vxx = sym(Qxx - Qxu K) + preg I,  Vx += Vxx f  (if gaps are open)

Nodes whose next tangent space is small (:data:`SMALL`) run loop kernels (no BLAS call, no allocation);
larger ones :func:`riccati_step` (products by BLAS, ``L⁻¹`` by LAPACK).  A node without controls skips
the gains.  The pass returns -1, or the first node (from the end) whose ``Quu`` is not positive definite
or not finite (the caller tells them apart: it raises the regularisation, or stops on NaN/inf,
:mod:`.nonfinite`).  :func:`expected_terms` gives FDDP's ``Σ Quᵀk - Σ Vxᵀf`` and
``-Σ kᵀQuu k + Σ fᵀVxx f`` and stores ``Vxx f``; :func:`gap_step_term` the trial step's ``Σ (Vxx f)ᵀ dx``.

:func:`terminal_value` starts the recursion at the terminal node.
``feedback_control(u, k, K, dx, α, lb, ub, out)`` writes the rollout's control
``clamp(u - α k - K dx, lb, ub)`` (infinite bounds for the unconstrained solvers).

Numpy twins: the chain of :class:`~crocopy.solvers.ddp.SolverDDP`'s ``computeActionValueFunction``,
``computeGains`` and ``computeValueFunction`` (Cholesky by LAPACK) over the horizon, :func:`terminal_value_numpy`,
:meth:`~crocopy.solvers.fddp.SolverFDDP.updateExpectedImprovement`, :func:`feedback_control_numpy`;
:mod:`crocopy.kernels` chooses.
"""

from __future__ import annotations

import numpy as np

from ..kernels import compiled, matrix_at, vector_at
from .horizon import FS, KM, KV, QU, QUU, QX, QXU, QXX, VX, VXX, VXX_F


def _deflect(Vxx, Vx, fs):
    """``Vx += Vxx fs`` (the gap's deflection of the value gradient)."""
    n = Vx.shape[0]
    for i in range(n):
        acc = 0.0
        for j in range(n):
            acc += Vxx[i, j] * fs[j]
        Vx[i] += acc


deflect = compiled(_deflect)


def _finish_value_function(Vxx, Vx, preg, fs, gaps):
    """Symmetrise ``Vxx``, add ``preg`` to its diagonal and deflect ``Vx`` by the gap (shared by the kernels)."""
    n = Vxx.shape[0]
    for i in range(n):
        for j in range(i + 1, n):
            m = 0.5 * (Vxx[i, j] + Vxx[j, i])
            Vxx[i, j] = m
            Vxx[j, i] = m
        Vxx[i, i] += preg
    if gaps:
        deflect(Vxx, Vx, fs)


finish_value_function = compiled(_finish_value_function)


def _terminal_value(Lxx, Lx, preg, fs, gaps, Vxx, Vx):
    """``V_T``: ``Vxx = Lxx + preg I``, ``Vx = Lx``, then ``Vx += Vxx fs`` if ``gaps``."""
    n = Vx.shape[0]
    for i in range(n):
        for j in range(n):
            Vxx[i, j] = Lxx[i, j]
        Vx[i] = Lx[i]
    if preg:
        for i in range(n):
            Vxx[i, i] += preg
    if gaps:
        deflect(Vxx, Vx, fs)


def terminal_value_numpy(Lxx, Lx, preg, fs, gaps, Vxx, Vx) -> None:
    """Numpy twin of :func:`terminal_value`."""
    Vxx[:] = Lxx
    Vx[:] = Lx
    if preg:
        Vxx.flat[:: Vxx.shape[0] + 1] += preg
    if gaps:
        Vx += Vxx @ fs


terminal_value = compiled(_terminal_value)


def _cholesky_lower(A, idx, n, L):
    """Lower Cholesky factor of ``A[idx[:n], idx[:n]]`` into ``L[:n, :n]``; False if not positive definite
    or not finite (the caller tells the two apart on failure)."""
    for j in range(n):
        s = A[idx[j], idx[j]]
        for p in range(j):
            s -= L[j, p] * L[j, p]
        if not 0.0 < s < np.inf:
            return False
        L[j, j] = np.sqrt(s)
        for i in range(j + 1, n):
            s = A[idx[i], idx[j]]
            for p in range(j):
                s -= L[i, p] * L[j, p]
            L[i, j] = s / L[j, j]
            if not abs(L[i, j]) < np.inf:
                return False
    return True


cholesky_lower = compiled(_cholesky_lower)


def _forward_substitution(L, n, x, start):
    """``x[:n] ← L⁻¹ x[:n]`` for an ``x`` whose entries before ``start`` are zero (they stay zero)."""
    for r in range(start, n):
        acc = x[r]
        for k in range(start, r):
            acc -= L[r, k] * x[k]
        x[r] = acc / L[r, r]


def _back_substitution(L, n, x):
    """``x[:n] ← L⁻ᵀ x[:n]``."""
    for r in range(n - 1, -1, -1):
        acc = x[r]
        for k in range(r + 1, n):
            acc -= L[k, r] * x[k]
        x[r] = acc / L[r, r]


forward_substitution = compiled(_forward_substitution)
back_substitution = compiled(_back_substitution)


def _cholesky_solve(L, n, x):
    """``x[:n] ← (L Lᵀ)⁻¹ x[:n]`` with the lower factor ``L[:n, :n]`` of :func:`cholesky_lower`."""
    forward_substitution(L, n, x, 0)
    back_substitution(L, n, x)


cholesky_solve = compiled(_cholesky_solve)


def _combine(A, C, sign):
    """``C ← A + sign C`` entrywise in loops (2-D; ``sign = ±1``).  Loops, not array expressions: numba's
    broadcast checks compile seconds of error-message code into each kernel."""
    for i in range(C.shape[0]):
        for j in range(C.shape[1]):
            C[i, j] = A[i, j] + sign * C[i, j]


def _combine1(a, c, sign):
    """:func:`combine` for vectors."""
    for i in range(c.shape[0]):
        c[i] = a[i] + sign * c[i]


combine1 = compiled(_combine1)
combine = compiled(_combine)


def _value_blas(Qxx, Qxu, Qx, Qu, K, Vxx, Vx):
    """``Vxx = Qxx - Qxu K`` (BLAS), ``Vx = Qx - Kᵀ Qu`` (before :func:`finish_value_function`)."""
    np.dot(Qxu, K, Vxx)
    combine(Qxx, Vxx, -1.0)
    tvec(K, Qu, Vx)
    combine1(Qx, Vx, -1.0)


def _action_value_function(Fx, Fu, Lxx, Lxu, Luu, Lx, Lu, Vxx_n, Vx_n, preg, Qxx, Qxu, Quu, Qx, Qu):
    """The Q terms of a node (``preg`` on the diagonal of ``Quu``; no control terms when ``nu = 0``)."""
    nu = Fu.shape[1]
    FxTV = Fx.T @ Vxx_n
    np.dot(FxTV, Fx, Qxx)
    combine(Lxx, Qxx, 1.0)
    tvec(Fx, Vx_n, Qx)
    combine1(Lx, Qx, 1.0)
    if nu > 0:
        FuTV = Fu.T @ Vxx_n
        np.dot(FuTV, Fu, Quu)
        combine(Luu, Quu, 1.0)
        np.dot(FxTV, Fu, Qxu)
        combine(Lxu, Qxu, 1.0)
        tvec(Fu, Vx_n, Qu)
        combine1(Lu, Qu, 1.0)
        for i in range(nu):
            Quu[i, i] += preg


def _riccati_step(Fx, Fu, Lxx, Lxu, Luu, Lx, Lu, Vxx_n, Vx_n, preg, fs, gaps, Qxx, Qxu, Quu, Qx, Qu, K, k, Vxx, Vx):
    nu = Fu.shape[1]
    ndx = Fx.shape[1]
    action_value_function(Fx, Fu, Lxx, Lxu, Luu, Lx, Lu, Vxx_n, Vx_n, preg, Qxx, Qxu, Quu, Qx, Qu)
    if nu > 0:
        L = np.zeros((nu, nu))
        if not cholesky_lower(Quu, np.arange(nu), nu, L):
            return False
        Linv = np.linalg.inv(L)
        rhs = np.empty((nu, ndx + 1))
        for i in range(nu):
            for j in range(ndx):
                rhs[i, j] = Qxu[j, i]
            rhs[i, ndx] = Qu[i]
        rhs = Linv.T @ (Linv @ rhs)
        for i in range(nu):
            for j in range(ndx):
                K[i, j] = rhs[i, j]
            k[i] = rhs[i, ndx]
        value_blas(Qxx, Qxu, Qx, Qu, K, Vxx, Vx)
    else:
        copy(Qxx, Qx, Vxx, Vx)
    finish_value_function(Vxx, Vx, preg, fs, gaps)
    return True


def _copy(Qxx, Qx, Vxx, Vx):
    """``Vxx = Qxx``, ``Vx = Qx`` in loops (a node without controls)."""
    for i in range(Qxx.shape[0]):
        Vx[i] = Qx[i]
        for j in range(Qxx.shape[1]):
            Vxx[i, j] = Qxx[i, j]


def feedback_control_numpy(u, k, K, dx, alpha, lb, ub, out) -> None:
    """Numpy twin of :func:`feedback_control`."""
    np.subtract(u, alpha * k, out=out)
    out -= K @ dx
    np.maximum(out, lb, out=out)
    np.minimum(out, ub, out=out)


def _feedback_control(u, k, K, dx, alpha, lb, ub, out):
    for i in range(u.shape[0]):
        s = u[i] - alpha * k[i]
        for j in range(dx.shape[0]):
            s -= K[i, j] * dx[j]
        if s < lb[i]:
            s = lb[i]
        if s > ub[i]:
            s = ub[i]
        out[i] = s


feedback_control = compiled(_feedback_control)


def _mul(A, B, C, transpose):
    """``C = A B``, or ``C = Aᵀ B`` if ``transpose``, in loops (``C`` is overwritten)."""
    n, inner = (A.shape[1], A.shape[0]) if transpose else (A.shape[0], A.shape[1])
    C[:, :] = 0.0
    for i in range(n):
        for p in range(inner):
            a = A[p, i] if transpose else A[i, p]
            for j in range(B.shape[1]):
                C[i, j] += a * B[p, j]


def _tvec(A, v, y):
    """``y = Aᵀ v`` in loops."""
    for i in range(A.shape[1]):
        acc = 0.0
        for p in range(A.shape[0]):
            acc += A[p, i] * v[p]
        y[i] = acc


mul = compiled(_mul)
tvec = compiled(_tvec)


def _q_terms_loops(Fx, Fu, Lxx, Lxu, Luu, Lx, Lu, Vxx_n, Vx_n, preg, Qxx, Qxu, Quu, Qx, Qu, W, Wu):
    """:func:`action_value_function` by loops (no BLAS call, no allocation) with the scratch
    ``W (ndx, ndx')``, ``Wu (nu, ndx')`` for ``Fxᵀ V'xx``, ``Fuᵀ V'xx`` (same association as the twin)."""
    n1, n, m = Fx.shape[0], Fx.shape[1], Fu.shape[1]
    W[:, :] = 0.0
    Wu[:, :] = 0.0
    for p in range(n1):
        for i in range(n):
            a = Fx[p, i]
            for j in range(n1):
                W[i, j] += a * Vxx_n[p, j]
        for i in range(m):
            a = Fu[p, i]
            for j in range(n1):
                Wu[i, j] += a * Vxx_n[p, j]
    Qxx[:, :] = 0.0
    Qxu[:, :] = 0.0
    Quu[:, :] = 0.0
    for i in range(n):
        acc = 0.0
        for p in range(n1):
            acc += Fx[p, i] * Vx_n[p]
            a = W[i, p]
            for j in range(n):
                Qxx[i, j] += a * Fx[p, j]
            for j in range(m):
                Qxu[i, j] += a * Fu[p, j]
        Qx[i] = Lx[i] + acc
    for i in range(m):
        acc = 0.0
        for p in range(n1):
            acc += Fu[p, i] * Vx_n[p]
            a = Wu[i, p]
            for j in range(m):
                Quu[i, j] += a * Fu[p, j]
        Qu[i] = Lu[i] + acc
    for i in range(n):
        for j in range(n):
            Qxx[i, j] = Lxx[i, j] + Qxx[i, j]
        for j in range(m):
            Qxu[i, j] = Lxu[i, j] + Qxu[i, j]
    for i in range(m):
        for j in range(m):
            Quu[i, j] = Luu[i, j] + Quu[i, j]
        Quu[i, i] += preg


def _triangular_solve(L, R, transpose):
    """``R ← L⁻¹ R``, or ``R ← L⁻ᵀ R`` if ``transpose``, in loops (``L`` lower triangular)."""
    m = R.shape[0]
    for s in range(m):
        i = m - 1 - s if transpose else s
        lo, hi = (i + 1, m) if transpose else (0, i)
        for p in range(lo, hi):
            a = L[p, i] if transpose else L[i, p]
            for j in range(R.shape[1]):
                R[i, j] -= a * R[p, j]
        d = L[i, i]
        for j in range(R.shape[1]):
            R[i, j] /= d


triangular_solve = compiled(_triangular_solve)


def _gains_loops(Quu, Qu, Qxu, K, k, idx, L, R):
    """``[k K] = Quu⁻¹ [Qu Qux]`` by Cholesky and two triangular solves in loops (scratch ``L (nu, nu)``,
    ``R (nu, ndx + 1)``); False when ``Quu`` is not positive definite or not finite."""
    m, n = Qxu.shape[1], Qxu.shape[0]
    if not cholesky_lower(Quu, idx, m, L):
        return False
    for i in range(m):
        for j in range(n):
            R[i, j] = Qxu[j, i]
        R[i, n] = Qu[i]
    triangular_solve(L, R, False)
    triangular_solve(L, R, True)
    for i in range(m):
        for j in range(n):
            K[i, j] = R[i, j]
        k[i] = R[i, n]
    return True


def _value_loops(Qxx, Qxu, Qx, Qu, K, Vxx, Vx):
    """``Vxx = Qxx - Qxu K``, ``Vx = Qx - Kᵀ Qu`` in loops (before :func:`finish_value_function`)."""
    mul(Qxu, K, Vxx, False)
    tvec(K, Qu, Vx)
    for i in range(Vxx.shape[0]):
        Vx[i] = Qx[i] - Vx[i]
        for j in range(Vxx.shape[1]):
            Vxx[i, j] = Qxx[i, j] - Vxx[i, j]


value_blas = compiled(_value_blas)
action_value_function = compiled(_action_value_function)
copy = compiled(_copy)
riccati_step = compiled(_riccati_step)
q_terms_loops = compiled(_q_terms_loops)
gains_loops = compiled(_gains_loops)
value_loops = compiled(_value_loops)

SMALL = 24
"""Nodes whose next tangent space has at most this dimension run the loop kernels (no BLAS call and no
allocation: faster on small matrices); larger ones call BLAS/LAPACK as :func:`riccati_step` does."""


def _scratch(dims):
    """Scratch for the loop kernels of every node of ``dims``, and the index ``0..nu_max-1``."""
    n, m = 0, 0
    for t in range(dims.shape[0]):
        n, m = max(n, dims[t, 0]), max(m, dims[t, 1])
    return np.empty(max(n * n + m * n, m * m + m * (n + 1), 1)), np.arange(max(m, 1))


def _node_arrays(daddr, saddr, dims, t):
    """Node ``t``'s derivatives ``Fx, Fu, Lxx, Lxu, Luu, Lx, Lu`` (``daddr``), the next value function
    ``V'xx, V'x`` and its gap ``fs`` (``saddr``, :mod:`.horizon`)."""
    n, m, n1 = dims[t, 0], dims[t, 1], dims[t + 1, 0]
    d, o, o1 = daddr[t], saddr[t], saddr[t + 1]
    return (matrix_at(d[0], n, n), matrix_at(d[1], n, m), matrix_at(d[2], n, n), matrix_at(d[3], n, m),
            matrix_at(d[4], m, m), vector_at(d[5], n), vector_at(d[6], m), matrix_at(o1[VXX], n1, n1),
            vector_at(o1[VX], n1), vector_at(o[FS], n))


def _q_arrays(saddr, dims, t):
    """Node ``t``'s ``Qxx, Qxu, Quu, Qx, Qu, K, k, Vxx, Vx`` in the solver's buffer (``saddr``)."""
    n, m = dims[t, 0], dims[t, 1]
    o = saddr[t]
    return (matrix_at(o[QXX], n, n), matrix_at(o[QXU], n, m), matrix_at(o[QUU], m, m), vector_at(o[QX], n),
            vector_at(o[QU], m), matrix_at(o[KM], m, n), vector_at(o[KV], m), matrix_at(o[VXX], n, n),
            vector_at(o[VX], n))


node_arrays = compiled(_node_arrays)
q_arrays = compiled(_q_arrays)


def _node_riccati(daddr, saddr, dims, t, preg, gaps, S, idx):
    """The Riccati step of node ``t`` on the arrays listed by address (:mod:`.horizon`): the loop kernels
    when small, else :func:`riccati_step`; False when ``Quu`` is not positive definite or not finite."""
    n, m, n1 = dims[t, 0], dims[t, 1], dims[t + 1, 0]
    Fx, Fu, Lxx, Lxu, Luu, Lx, Lu, Vxx_n, Vx_n, fs = node_arrays(daddr, saddr, dims, t)
    Qxx, Qxu, Quu, Qx, Qu, K, k, Vxx, Vx = q_arrays(saddr, dims, t)
    if n1 > SMALL:
        return riccati_step(Fx, Fu, Lxx, Lxu, Luu, Lx, Lu, Vxx_n, Vx_n, preg, fs, gaps, Qxx, Qxu, Quu, Qx, Qu, K, k,
                            Vxx, Vx)
    at = S.ctypes.data
    q_terms_loops(Fx, Fu, Lxx, Lxu, Luu, Lx, Lu, Vxx_n, Vx_n, preg, Qxx, Qxu, Quu, Qx, Qu,
                  matrix_at(at, n, n1), matrix_at(at + 8 * n * n1, m, n1))
    if m > 0:
        if not gains_loops(Quu, Qu, Qxu, K, k, idx, matrix_at(at, m, m), matrix_at(at + 8 * m * m, m, n + 1)):
            return False
        value_loops(Qxx, Qxu, Qx, Qu, K, Vxx, Vx)
    else:
        copy(Qxx, Qx, Vxx, Vx)
    finish_value_function(Vxx, Vx, preg, fs, gaps)
    return True


def _riccati_pass(daddr, saddr, dims, preg, gaps):
    """The whole Riccati recursion (t = T-1..0); -1, or the first node whose gains failed."""
    S, idx = scratch(dims)
    for t in range(dims.shape[0] - 2, -1, -1):
        if not node_riccati(daddr, saddr, dims, t, preg, gaps, S, idx):
            return t
    return -1


def _expected_terms(saddr, dims, gaps):
    """``(Σ Quᵀk - Σ Vxᵀf, -Σ kᵀQuu k + Σ fᵀVxx f)`` (gap sums only if ``gaps``), ``Vxx f`` into its column."""
    T = dims.shape[0] - 1
    dg = 0.0
    dq = 0.0
    for t in range(T):
        m = dims[t, 1]
        o = saddr[t]
        k, Qu, Quu = vector_at(o[KV], m), vector_at(o[QU], m), matrix_at(o[QUU], m, m)
        if m == 0:
            continue
        qk = 0.0
        kqk = 0.0
        for j in range(m):
            qk += Qu[j] * k[j]
            acc = 0.0
            for i in range(m):
                acc += k[i] * Quu[i, j]
            kqk += acc * k[j]
        dg += qk
        dq -= kqk
    if gaps:
        for t in range(T + 1):
            n = dims[t, 0]
            o = saddr[t]
            f, Vx, Vxx_f = vector_at(o[FS], n), vector_at(o[VX], n), vector_at(o[VXX_F], n)
            Vxx = matrix_at(o[VXX], n, n)
            vf = 0.0
            fvf = 0.0
            for i in range(n):
                acc = 0.0
                for j in range(n):
                    acc += Vxx[i, j] * f[j]
                Vxx_f[i] = acc
                vf += Vx[i] * f[i]
                fvf += f[i] * acc
            dg -= vf
            dq += fvf
    return dg, dq


def _gap_step_term(saddr, dims, dx_addr):
    """``Σ_t (Vxx f)_tᵀ dx_t`` (FDDP's expected improvement) over the nodes ``t < len(dx_addr)`` whose ``dx`` address
    is not 0; ``Vxx f`` is read from its column (written by :func:`_expected_terms`)."""
    dv = 0.0
    for t in range(dx_addr.shape[0]):
        if dx_addr[t] == 0:
            continue
        n = dims[t, 0]
        Vxx_f, dx = vector_at(saddr[t][VXX_F], n), vector_at(dx_addr[t], n)
        for i in range(n):
            dv += Vxx_f[i] * dx[i]
    return dv


def _step_term(Vxx_f, dx):
    """``(Vxx f)ᵀ dx`` of one node (a term of FDDP's ``dv`` outside :func:`gap_step_term`), summed in index order."""
    acc = 0.0
    for j in range(dx.shape[0]):
        acc += Vxx_f[j] * dx[j]
    return acc


scratch = compiled(_scratch)
step_term = compiled(_step_term)
node_riccati = compiled(_node_riccati)
riccati_pass = compiled(_riccati_pass)
expected_terms = compiled(_expected_terms)
gap_step_term = compiled(_gap_step_term)
