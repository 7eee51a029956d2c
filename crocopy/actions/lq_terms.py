"""The quadratic cost and linear constraints shared by the discrete and differential LQR models.

With ``z = [x; u]``: cost ``½ xᵀQx + ½ uᵀRu + xᵀNu + qᵀx + rᵀu``; inequalities
``g(z) = G z + g``; equalities ``h(z) = H z + h``.  Terminal nodes use the state blocks only.
"""

from __future__ import annotations

import numpy as np

from ..validation import as_matrix, as_vector


class LQTerms:
    """Validated quadratic-cost and linear-constraint data of size ``(nx, nu)``."""

    def __init__(self, nx: int, nu: int, Q, R, N, q, r, G, H, g, h) -> None:
        self.Q = as_matrix(Q, (nx, nx), "Q")
        self.R = as_matrix(R, (nu, nu), "R")
        self.N = as_matrix(N, (nx, nu), "N")
        self.q = as_vector(q, nx, "q")
        self.r = as_vector(r, nu, "r")
        G = np.zeros((0, nx + nu)) if G is None else np.atleast_2d(np.asarray(G, dtype=float))
        H = np.zeros((0, nx + nu)) if H is None else np.atleast_2d(np.asarray(H, dtype=float))
        self.G = as_matrix(G, (G.shape[0], nx + nu), "G")
        self.H = as_matrix(H, (H.shape[0], nx + nu), "H")
        self.g = as_vector(np.zeros(self.G.shape[0]) if g is None else g, self.G.shape[0], "g")
        self.h = as_vector(np.zeros(self.H.shape[0]) if h is None else h, self.H.shape[0], "h")
        self.nx = nx

    def cost(self, x: np.ndarray, u: np.ndarray | None) -> float:
        c = 0.5 * x @ self.Q @ x + self.q @ x
        if u is not None:
            c += 0.5 * u @ self.R @ u + x @ self.N @ u + self.r @ u
        return float(c)

    def fill_cost_derivatives(self, data, x: np.ndarray, u: np.ndarray | None) -> None:
        data.Lxx[:] = self.Q
        if u is None:
            data.Lx[:] = self.Q @ x + self.q
            return
        data.Lx[:] = self.Q @ x + self.N @ u + self.q
        data.Lu[:] = self.R @ u + self.N.T @ x + self.r
        data.Luu[:] = self.R
        data.Lxu[:] = self.N

    def fill_constraints(self, data, x: np.ndarray, u: np.ndarray | None, diff: bool) -> None:
        nx = self.nx
        ng, nh = self.G.shape[0], self.H.shape[0]
        if ng:
            data.g[:ng] = self.G[:, :nx] @ x + self.g + (0.0 if u is None else self.G[:, nx:] @ u)
            if diff:
                data.Gx[:ng] = self.G[:, :nx]
                data.Gu[:ng] = 0.0 if u is None else self.G[:, nx:]
        if nh:
            data.h[:nh] = self.H[:, :nx] @ x + self.h + (0.0 if u is None else self.H[:, nx:] @ u)
            if diff:
                data.Hx[:nh] = self.H[:, :nx]
                data.Hu[:nh] = 0.0 if u is None else self.H[:, nx:]


def default_input_matrix(rows: int, nu: int) -> np.ndarray:
    """The ``(rows, nu)`` identity-like input matrix used by the size-only LQR constructors."""
    return np.eye(rows, nu)


def random_psd(n: int, rng: np.random.Generator | None = None) -> np.ndarray:
    """A random symmetric positive-definite ``(n, n)`` matrix."""
    rng = rng or np.random.default_rng()
    A = rng.standard_normal((n, n))
    return A @ A.T + n * np.eye(n) * 1e-2 + np.eye(n)
