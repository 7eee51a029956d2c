"""Linear-quadratic problems with constraint rows for the SQP/CSQP tests (Euclidean states)."""

from __future__ import annotations

import numpy as np

import crocopy


class LinearModel(crocopy.ActionModelAbstract):
    """``x⁺ = A x + B u + c``, cost ``½ xᵀQx + qᵀx + ½ uᵀRu`` and optional rows:
    ``lb <= Gx x + Gu u <= ub`` (``rows = (Gx, Gu, lb, ub)``) and ``Hx x + Hu u - h0 = 0``
    (``eqs = (Hx, Hu, h0)``).  A terminal model (``terminal=True``) has ``nu = 0`` in its calls."""

    def __init__(self, A, B, c, Q, q, R, rows=None, eqs=None, terminal=False):
        nx, nu = B.shape
        ng = 0 if rows is None else rows[0].shape[0]
        nh = 0 if eqs is None else eqs[0].shape[0]
        super().__init__(crocopy.StateVector(nx), nu, 1, ng, nh, ng if terminal else 0, nh if terminal else 0)
        self.A, self.B, self.c, self.Q, self.q, self.R = A, B, c, Q, q, R
        self.rows, self.eqs, self.terminal = rows, eqs, terminal
        if rows is not None:
            self.g_lb, self.g_ub = rows[2], rows[3]

    def calc(self, data, x, u=None):
        u = np.zeros(self.nu) if u is None else u
        data.xnext[:] = self.A @ x + self.B @ u + self.c
        data.cost = 0.5 * x @ self.Q @ x + self.q @ x + (0.0 if self.terminal else 0.5 * u @ self.R @ u)
        if self.rows is not None:
            data.g[:] = self.rows[0] @ x + self.rows[1] @ u
        if self.eqs is not None:
            data.h[:] = self.eqs[0] @ x + self.eqs[1] @ u - self.eqs[2]

    def calcDiff(self, data, x, u=None):
        u = np.zeros(self.nu) if u is None else u
        data.Fx[:], data.Fu[:] = self.A, self.B
        data.Lx[:] = self.Q @ x + self.q
        data.Lxx[:] = self.Q
        if not self.terminal:
            data.Lu[:] = self.R @ u
            data.Luu[:] = self.R
        if self.rows is not None:
            data.Gx[:], data.Gu[:] = self.rows[0], self.rows[1]
        if self.eqs is not None:
            data.Hx[:], data.Hu[:] = self.eqs[0], self.eqs[1]


def random_lq(seed: int = 0, nx: int = 3, nu: int = 2, T: int = 8, rows=None, terminal_rows=None,
              terminal_eqs=None) -> crocopy.ShootingProblem:
    """A random stable LQ problem; ``rows(t)`` gives node ``t``'s rows (or None)."""
    rng = np.random.default_rng(seed)
    A = np.eye(nx) + 0.1 * rng.normal(size=(nx, nx))
    B = rng.normal(size=(nx, nu))
    c = 0.1 * rng.normal(size=nx)
    M = rng.normal(size=(nx, nx))
    Q = 0.1 * (M @ M.T + np.eye(nx))
    q = rng.normal(size=nx)
    R = 0.1 * np.eye(nu)
    running = [LinearModel(A, B, c, Q, q, R, None if rows is None else rows(t)) for t in range(T)]
    terminal = LinearModel(A, B, c, 10 * Q, q, R, terminal_rows, terminal_eqs, terminal=True)
    return crocopy.ShootingProblem(rng.normal(size=nx), running, terminal)


def dense_lq_solution(problem: crocopy.ShootingProblem) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(xs, us, λ)`` of the LQ problem without rows, from one dense KKT solve."""
    T, nx, nu = problem.T, problem.nx, problem.runningModels[0].nu
    n = (T + 1) * nx + T * nu
    H, g = np.zeros((n, n)), np.zeros(n)
    E, e = np.zeros(((T + 1) * nx, n)), np.zeros((T + 1) * nx)
    xi = lambda t: slice(t * nx, (t + 1) * nx)  # noqa: E731
    ui = lambda t: slice((T + 1) * nx + t * nu, (T + 1) * nx + (t + 1) * nu)  # noqa: E731
    for t, m in enumerate([*problem.runningModels, problem.terminalModel]):
        H[xi(t), xi(t)], g[xi(t)] = m.Q, m.q
        if t < T:
            H[ui(t), ui(t)] = m.R
    E[xi(0), xi(0)], e[xi(0)] = np.eye(nx), problem.x0
    for t, m in enumerate(problem.runningModels):
        E[xi(t + 1), xi(t + 1)] = np.eye(nx)
        E[xi(t + 1), xi(t)] = -m.A
        E[xi(t + 1), ui(t)] = -m.B
        e[xi(t + 1)] = m.c
    K = np.block([[H, E.T], [E, np.zeros((E.shape[0], E.shape[0]))]])
    sol = np.linalg.solve(K, np.r_[-g, e])
    z, nu_ = sol[:n], sol[n:]
    xs = np.array([z[xi(t)] for t in range(T + 1)])
    us = np.array([z[ui(t)] for t in range(T)])
    return xs, us, -nu_.reshape(T + 1, nx)
