"""Compiled Riccati step of one node (numba), twin of the pure-numpy step in :mod:`.ddp`.

Computes, for node t with next value function ``(V'x, V'xx)`` (Crocoddyl signs)::

    Qx = Lx + Fxᵀ V'x,  Qu = Lu + Fuᵀ V'x,  Qxx = Lxx + Fxᵀ V'xx Fx,
    Qxu = Lxu + Fxᵀ V'xx Fu,  Quu = Luu + Fuᵀ V'xx Fu + preg I,
    [k K] = L⁻ᵀ L⁻¹ [Qu Qux]  (Quu = L Lᵀ; L⁻¹ by LAPACK, the products by BLAS),
    Vx = Qx - Qxu k,  Vxx = sym(Qxx - Qxu K) + preg I,  Vx += Vxx f  (if gaps are open)

``feedback_control(u, k, K, dx, α, lb, ub, out)`` writes the rollout's control
``clamp(u - α k - K dx, lb, ub)`` (infinite bounds for the unconstrained solvers).

``riccati_step`` returns False when ``Quu`` is not positive definite (the caller raises the
regularisation).  Its numpy twin is the chain of :class:`~crocopy.solvers.ddp.SolverDDP`'s
``computeActionValueFunction``, ``computeGains`` and ``computeValueFunction`` (Cholesky by LAPACK),
``feedback_control``'s is :func:`feedback_control_numpy`; :mod:`crocopy.kernels` chooses.
"""

from __future__ import annotations

import numpy as np

from ..kernels import compiled


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
        Vx[:] += Vxx @ fs


finish_value_function = compiled(_finish_value_function)


def _cholesky_lower(A, idx, n, L):
    """Lower Cholesky factor of ``A[idx[:n], idx[:n]]`` into ``L[:n, :n]``; False if not positive definite."""
    for j in range(n):
        s = A[idx[j], idx[j]]
        for p in range(j):
            s -= L[j, p] * L[j, p]
        if not s > 0.0:
            return False
        L[j, j] = np.sqrt(s)
        for i in range(j + 1, n):
            s = A[idx[i], idx[j]]
            for p in range(j):
                s -= L[i, p] * L[j, p]
            L[i, j] = s / L[j, j]
    return True


cholesky_lower = compiled(_cholesky_lower)


def _action_value_function(Fx, Fu, Lxx, Lxu, Luu, Lx, Lu, Vxx_n, Vx_n, preg, Qxx, Qxu, Quu, Qx, Qu):
    """The Q terms of a node (``preg`` on the diagonal of ``Quu``; no control terms when ``nu = 0``)."""
    nu = Fu.shape[1]
    FxTV = Fx.T @ Vxx_n
    Qxx[:, :] = Lxx + FxTV @ Fx
    Qx[:] = Lx + Fx.T @ Vx_n
    if nu > 0:
        FuTV = Fu.T @ Vxx_n
        Quu[:, :] = Luu + FuTV @ Fu
        Qxu[:, :] = Lxu + FxTV @ Fu
        Qu[:] = Lu + Fu.T @ Vx_n
        for i in range(nu):
            Quu[i, i] += preg


action_value_function = compiled(_action_value_function)


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
        rhs[:, :ndx] = Qxu.T
        rhs[:, ndx] = Qu
        rhs = Linv.T @ (Linv @ rhs)
        K[:, :] = rhs[:, :ndx]
        k[:] = rhs[:, ndx]
        Vxx[:, :] = Qxx - Qxu @ K
        Vx[:] = Qx - K.T @ Qu
    else:
        Vxx[:, :] = Qxx
        Vx[:] = Qx
    finish_value_function(Vxx, Vx, preg, fs, gaps)
    return True


riccati_step = compiled(_riccati_step)


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
