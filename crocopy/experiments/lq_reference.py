"""Independent optimum of a box-constrained LQ problem: a convex QP solved by an interior-point method.

Problem (time-invariant; controls ``U = (u_0, ..., u_{N-1})`` of shape ``(N, m)``)::

    J(U) = ½ Σ_{i<N} (x_iᵀ Q x_i + u_iᵀ R u_i) + ½ x_Nᵀ Q_f x_N,   x_{i+1} = A x_i + B u_i,
    lb <= u_i <= ub.

:func:`box_lq_optimum` solves it as one sparse QP in ``(x_0..x_N, U)`` with the dynamics as
equality constraints, by Mehrotra's primal-dual predictor-corrector interior-point method; every
Newton system is the sparse KKT matrix ``[[H + D, Cᵀ], [C, 0]]`` factorised by SuperLU.  No
Riccati recursion, no DDP and no box QP of the solvers is involved.

Certificate.  ``J`` is convex in ``U`` with gradient (adjoint sweep)
``λ_N = Q_f x_N``, ``λ_i = Q x_i + Aᵀ λ_{i+1}``, ``∂J/∂u_i = R u_i + Bᵀ λ_{i+1}``.  For every feasible
``V``, ``J(V) >= J(U) + ∇J(U)ᵀ (V - U)``, hence

    0 <= J(U) - J* <= gap(U) = Σ_j max(g_j (u_j - lb_j), g_j (u_j - ub_j), 0),   g = ∇J(U),

computed from the returned controls alone (a rollout and an adjoint sweep).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla


@dataclass
class BoxLQOptimum:
    """Result of :func:`box_lq_optimum`: controls ``us`` ``(N, m)``, cost ``J``, certified ``gap``
    (``0 <= J - J* <= gap``) and interior-point iterations."""

    us: np.ndarray
    J: float
    gap: float
    iterations: int


class BoxLQ:
    """The box-constrained LQ problem above: cost, adjoint gradient and the certificate.

    Parameters
    ----------
    A, B : numpy.ndarray
        Dynamics ``(n, n)``, ``(n, m)``.
    Q, R, Qf : numpy.ndarray
        Running state ``(n, n)``, control ``(m, m)`` and terminal ``(n, n)`` weights.
    x0 : numpy.ndarray
        Initial state ``(n,)``.
    N : int
        Horizon.
    lb, ub : numpy.ndarray
        Control bounds ``(m,)`` (finite).
    """

    def __init__(self, A, B, Q, R, Qf, x0, N: int, lb, ub) -> None:
        self.A, self.B = np.asarray(A, float), np.asarray(B, float)
        self.Q, self.R, self.Qf = np.asarray(Q, float), np.asarray(R, float), np.asarray(Qf, float)
        self.x0, self.N = np.asarray(x0, float), int(N)
        self.n, self.m = self.B.shape
        self.lb = np.tile(np.asarray(lb, float), self.N)
        self.ub = np.tile(np.asarray(ub, float), self.N)
        if not (np.all(np.isfinite(self.lb)) and np.all(np.isfinite(self.ub)) and np.all(self.lb < self.ub)):
            raise ValueError("BoxLQ: lb and ub must be finite with lb < ub")

    @classmethod
    def from_lqr_model(cls, model, x0, N: int) -> BoxLQ:
        """From an :class:`~crocopy.actions.ActionModelLQR` used as running and terminal node."""
        return cls(model.A, model.B, model.Q, model.R, model.Q, x0, N, model.u_lb, model.u_ub)

    def cost_grad(self, z: np.ndarray) -> tuple[float, np.ndarray]:
        """``J(U)`` and ``∇J(U)`` for the flattened controls ``z`` ``(N m,)``."""
        U = z.reshape(self.N, self.m)
        X = np.empty((self.N + 1, self.n))
        X[0] = self.x0
        for i in range(self.N):
            X[i + 1] = self.A @ X[i] + self.B @ U[i]
        J = 0.5 * (np.einsum("ij,jk,ik->", X[:-1], self.Q, X[:-1]) + np.einsum("ij,jk,ik->", U, self.R, U)
                   + X[-1] @ self.Qf @ X[-1])
        lam = self.Qf @ X[-1]
        g = np.empty_like(U)
        for i in range(self.N - 1, -1, -1):
            g[i] = self.R @ U[i] + self.B.T @ lam
            lam = self.Q @ X[i] + self.A.T @ lam
        return float(J), g.ravel()

    def gap(self, z: np.ndarray) -> tuple[float, float]:
        """``(J(z), gap(z))`` for feasible controls ``z``: ``J(z) - J* <= gap``."""
        J, g = self.cost_grad(z)
        return J, float(np.sum(np.maximum(np.maximum(g * (z - self.lb), g * (z - self.ub)), 0.0)))

    def kkt_blocks(self) -> tuple[sp.csc_matrix, sp.csc_matrix, np.ndarray]:
        """Hessian ``H`` and equality constraints ``C y = d`` of the QP in ``y = (x_0..x_N, U)``."""
        n, m, N = self.n, self.m, self.N
        H = sp.block_diag([sp.kron(sp.identity(N), self.Q), self.Qf, sp.kron(sp.identity(N), self.R)])
        Cdyn = sp.hstack([sp.kron(sp.eye(N, N + 1, k=1), sp.identity(n)) - sp.kron(sp.eye(N, N + 1), self.A),
                          -sp.kron(sp.identity(N), self.B)])
        Cx0 = sp.hstack([sp.identity(n), sp.csr_matrix((n, N * n + N * m))])
        return H.tocsc(), sp.vstack([Cx0, Cdyn]).tocsc(), np.concatenate([self.x0, np.zeros(N * n)])


def _max_step(pairs) -> float:
    a = 1.0
    for v, dv in pairs:
        neg = dv < 0
        if neg.any():
            a = min(a, float(np.min(-v[neg] / dv[neg])))
    return a


def _direction(lu, res: tuple, point: tuple, nx: int, target: float):
    """Newton direction of the perturbed KKT system with complementarity target ``s z = target``."""
    rd, rp, r1, r2 = res
    s1, s2, z1, z2 = point
    c1, c2 = (target - s1 * z1 - z1 * r1) / s1, (target - s2 * z2 - z2 * r2) / s2
    sol = lu.solve(np.concatenate([-rd[:nx], -rd[nx:] + c1 - c2, -rp]))
    du = sol[nx:nx + s1.size]
    ds1, ds2 = du + r1, r2 - du
    dz1, dz2 = c1 - z1 / s1 * du, c2 + z2 / s2 * du
    return sol, ds1, ds2, dz1, dz2, _max_step(((s1, ds1), (s2, ds2), (z1, dz1), (z2, dz2)))


def box_lq_optimum(lq: BoxLQ, rtol: float = 1e-11, maxiter: int = 100) -> BoxLQOptimum:
    """Minimise ``lq`` by a primal-dual interior-point method until ``gap <= rtol |J|``; returns the
    iterate with the smallest certified gap.

    Bounds ``u - lb = s₁ >= 0``, ``ub - u = s₂ >= 0`` with multipliers ``z₁, z₂ >= 0``; each iteration
    eliminates ``s, z`` and solves ``[[H + diag(0, z₁/s₁ + z₂/s₂), Cᵀ], [C, 0]]`` twice (Mehrotra's
    affine predictor, then the corrector with centring ``σ = (μ_aff/μ)³``); step to 0.99 of the
    boundary.  The slacks are iterated separately (``u - lb - s₁`` is a residual), and the certificate
    is evaluated at ``clip(u, lb, ub)``.

    Raises
    ------
    RuntimeError
        If no iterate reached ``gap <= rtol |J|`` (the floor is the round-off of the adjoint
        gradient, about ``1e-11 |J|`` on the literal, open-loop unstable generator of the paper).
    """
    H, C, d = lq.kkt_blocks()
    nx, nu = (lq.N + 1) * lq.n, lq.N * lq.m
    lb, ub = lq.lb, lq.ub
    y = np.zeros(nx + nu)
    y[nx:] = 0.5 * (lb + ub)
    lam = np.zeros(C.shape[0])
    s1, s2 = y[nx:] - lb, ub - y[nx:]
    z1, z2 = np.ones(nu), np.ones(nu)
    best = BoxLQOptimum(y[nx:].reshape(lq.N, lq.m).copy(), *lq.gap(y[nx:]), 0)
    for it in range(1, maxiter + 1):
        u = y[nx:]
        r1, r2 = u - lb - s1, ub - u - s2
        rd = H @ y + C.T @ lam
        rd[nx:] += z2 - z1
        rp = C @ y - d
        mu = (s1 @ z1 + s2 @ z2) / (2 * nu)
        kkt = sp.bmat([[H + sp.block_diag([sp.csc_matrix((nx, nx)), sp.diags(z1 / s1 + z2 / s2)]), C.T],
                       [C, None]], format="csc")
        try:
            lu = spla.splu(kkt)
        except RuntimeError:  # the barrier terms overflowed: no further progress possible
            break

        res = (rd, rp, r1, r2)
        _, ds1, ds2, dz1, dz2, a = _direction(lu, res, (s1, s2, z1, z2), nx, 0.0)
        mu_aff = ((s1 + a * ds1) @ (z1 + a * dz1) + (s2 + a * ds2) @ (z2 + a * dz2)) / (2 * nu)
        sol, ds1, ds2, dz1, dz2, a = _direction(lu, res, (s1, s2, z1, z2), nx, (mu_aff / mu) ** 3 * mu)
        a = min(1.0, 0.99 * a)
        y += a * sol[:nx + nu]
        lam += a * sol[nx + nu:]
        s1 += a * ds1
        s2 += a * ds2
        z1 += a * dz1
        z2 += a * dz2
        us = np.clip(y[nx:], lb, ub)
        J, gap = lq.gap(us)
        if gap < best.gap:
            best = BoxLQOptimum(us.reshape(lq.N, lq.m), J, gap, it)
        if gap <= rtol * abs(J):
            return best
    if best.gap <= rtol * abs(best.J):
        return best
    raise RuntimeError(f"box-LQ optimum not certified: best gap {best.gap:.3e} > {rtol:g} |J| = "
                       f"{rtol * abs(best.J):.3e}")
