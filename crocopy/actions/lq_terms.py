"""The quadratic cost and linear constraints shared by the discrete and differential LQR models.

With ``z = [x; u]``: cost ``½ xᵀQx + ½ uᵀRu + xᵀNu + qᵀx + rᵀu``; inequalities
``g(z) = G z + g``; equalities ``h(z) = H z + h``.  Terminal nodes use the state blocks only.
Both models take Crocoddyl's argument lists ``(dynamics..., Q, R, N[, G, H], f, q, r[, g, h])``
and ``(n, nu, driftFree=True)``, read here by :func:`lq_arguments` and :func:`size_arguments`.
The cost Hessian ``[[Q, N], [Nᵀ, R]]`` must be symmetric positive semi-definite (checked by
:func:`check_cost_hessian`): an indefinite one makes the problem unbounded below and a solver diverge.
"""

from __future__ import annotations

import numpy as np

from ..validation import as_matrix, as_vector

_TAIL_NAMES = {3: ("f", "q", "r"), 7: ("G", "H", "f", "q", "r", "g", "h")}


def lq_arguments(model: str, dynamics: tuple[str, ...], args: tuple, kwargs: dict) -> dict:
    """Name Crocoddyl's positional ``(dynamics..., Q, R, N[, G, H], f, q, r[, g, h])`` and merge ``kwargs``.

    Raises
    ------
    ValueError
        If the positional arguments after ``N`` are neither ``f, q, r`` nor ``G, H, f, q, r, g, h``.
    """
    head = (*dynamics, "Q", "R", "N")
    vals = dict(zip(head, args[: len(head)]))
    vals.update(kwargs)
    rest = args[len(head):]
    if rest and len(rest) not in _TAIL_NAMES:
        raise ValueError(f"{model} takes ({', '.join(head)}[, f, q, r]) or with G, H, g, h")
    vals.update(zip(_TAIL_NAMES.get(len(rest), ()), rest))
    return vals


def size_arguments(args: tuple, kwargs: dict) -> tuple[int, int, bool]:
    """``(n, nu, driftFree)`` of the size-only constructors ``(n, nu, driftFree=True)``."""
    drift_free = bool(args[2]) if len(args) > 2 else kwargs.get("driftFree", True)
    return int(args[0]), int(args[1]), drift_free


class LQTermsAccess:
    """Read-only ``Q, R, N, q, r, G, H, g, h`` of a model holding an :class:`LQTerms` in ``_lq``."""

    _lq: "LQTerms"

    Q = property(lambda self: self._lq.Q)
    R = property(lambda self: self._lq.R)
    N = property(lambda self: self._lq.N)
    q = property(lambda self: self._lq.q)
    r = property(lambda self: self._lq.r)
    G = property(lambda self: self._lq.G)
    H = property(lambda self: self._lq.H)
    g = property(lambda self: self._lq.g)
    h = property(lambda self: self._lq.h)


class LQTerms:
    """Validated quadratic-cost and linear-constraint data of size ``(nx, nu)``."""

    def __init__(self, nx: int, nu: int, Q, R, N, q, r, G, H, g, h) -> None:
        self.Q = as_matrix(Q, (nx, nx), "Q")
        self.R = as_matrix(R, (nu, nu), "R")
        self.N = as_matrix(N, (nx, nu), "N")
        check_cost_hessian(self.Q, self.R, self.N)
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


def check_cost_hessian(Q: np.ndarray, R: np.ndarray, N: np.ndarray) -> None:
    """Raise ``ValueError`` unless ``Q``, ``R`` are symmetric and ``[[Q, N], [Nᵀ, R]]`` is positive
    semi-definite (to a relative tolerance of 1e-10 of its largest eigenvalue)."""
    for name, M in (("Q", Q), ("R", R)):
        if not np.allclose(M, M.T, rtol=1e-10, atol=1e-12):
            asym = np.abs(M - M.T).max()
            raise ValueError(f"{name} must be symmetric, got max |{name} - {name}.T| = {asym:g}")
    H = np.block([[Q, N], [N.T, R]])
    if not H.size:
        return
    eig = np.linalg.eigvalsh(H)
    if eig[0] < -1e-10 * max(1.0, abs(eig[-1])):
        raise ValueError(
            "the cost Hessian [[Q, N], [N.T, R]] must be positive semi-definite, got smallest eigenvalue"
            f" {eig[0]:g}: the cost is unbounded below"
        )


def default_input_matrix(rows: int, nu: int) -> np.ndarray:
    """The ``(rows, nu)`` identity-like input matrix used by the size-only LQR constructors."""
    return np.eye(rows, nu)


def random_psd(n: int, rng: np.random.Generator | None = None) -> np.ndarray:
    """A random symmetric positive-definite ``(n, n)`` matrix."""
    rng = rng or np.random.default_rng()
    A = rng.standard_normal((n, n))
    return A @ A.T + n * np.eye(n) * 1e-2 + np.eye(n)
