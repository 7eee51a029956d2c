"""The stagewise ADMM of :class:`~crocopy.solvers.csqp.SolverCSQP` (Jordana et al. 2023, OSQP-like).

It solves the QP of one SQP iteration with box rows ::

    min  Σ_t ½ wᵀ H_t w + h_tᵀ w            (w = (δx_t, δu_t), Gauss-Newton Hessian of the nodes)
    s.t. δx_0 = d_0,  δx_{t+1} = A_t δx_t + B_t δu_t + d_{t+1},   lo_t <= C_t δx_t + D_t δu_t <= hi_t

keeping the dynamics exact inside the x-update (a Riccati pass over the LQ augmented by
``σ‖w - w̄‖²/2 + ρ‖C w + D u - z + y/ρ‖²/2``, ``C_0`` dropped since ``δx_0`` is fixed) and splitting the
rows: over-relaxation ``ẑ = α v + (1 - α) z`` (``v = C δx + D δu``), projection
``z⁺ = clip(ẑ + y/ρ, lo, hi)``, dual ascent ``y⁺ = y + ρ (ẑ - z⁺)``.  Every ``rho_update_interval``
iterations it computes the residuals ``r_p = max‖v - z⁺‖∞``, ``r_d = max‖[C D]ᵀ ρ (z⁺ - z)‖∞`` and their
scales ``s_p = max(‖v‖∞, ‖z⁺‖∞)``, ``s_d = max‖[C D]ᵀ y⁺‖∞``, adapts ``ρ̄`` to
``ρ̄ √(r_p s_d / (r_d s_p))`` (clipped to ``[rho_min, rho_max]``) when that moves it by more than a factor
``adaptive_rho_tolerance``, and stops when ``r_p <= eps_abs + eps_rel s_p`` and
``r_d <= eps_abs + eps_rel s_d``.  Per-row ``ρ``: ``rho_min`` on free rows, ``1e3 ρ̄`` on equality rows
(``|lb - ub| <= 1e-6``), ``ρ̄`` otherwise.  The factorisation of ``Quu`` is computed once per ``ρ``
(the first iteration after each update); the other iterations only recompute ``k`` and ``p``.

This module is the numpy twin, node by node (used when kernels are off); :mod:`.csqp_kernel` runs the same
iterations compiled, on the stacks this class allocates once per problem shape (:meth:`StagewiseADMM.run`).
"""

from __future__ import annotations

import numpy as np
from scipy.linalg.lapack import dpotrf, dpotrs

from . import csqp_kernel, horizon
from .base import BackwardPassError
from .csqp_kernel import EQUALITY, FREE, INEQUALITY
from .sqp_kernel import readable

EQUALITY_TOL = 1e-6


class NodeRows:
    """The rows ``lo <= C δx + D δu <= hi`` of one node and their ADMM state (``z``, ``y``, ``rho``): views of
    node ``t`` in the stacks of :class:`StagewiseADMM`."""

    def __init__(self, qp: StagewiseADMM, t: int, lb: np.ndarray, ub: np.ndarray) -> None:
        n, nx, nu = lb.size, qp.ndx[t], qp.nu[t]
        self.lb, self.ub = qp.lb[t, :n], qp.ub[t, :n]
        self.C, self.D = qp.C[t, :n, :nx], qp.D[t, :n, :nu]
        self.lo, self.hi = qp.lo[t, :n], qp.hi[t, :n]
        self.z, self.y, self.rho = qp.z[t, :n], qp.y[t, :n], qp.rho[t, :n]
        self.bound(qp, t, lb, ub)

    def bound(self, qp: StagewiseADMM, t: int, lb: np.ndarray, ub: np.ndarray) -> None:
        """Take the bounds ``lb``, ``ub`` (this node's shape) and classify the rows (free, equality, inequality)."""
        n = lb.size
        self.lb[:], self.ub[:] = lb, ub
        free = np.isneginf(lb) & np.isposinf(ub)
        equality = ~free & (np.abs(lb - ub) <= EQUALITY_TOL)
        qp.kind[t, :n] = np.where(free, FREE, np.where(equality, EQUALITY, INEQUALITY))


class StagewiseADMM:
    """ADMM over the nodes ``0..N`` of dimensions ``ndx[t]``, ``nu[t]`` (``nu[N] = 0``) whose rows have the
    bounds ``bounds[t] = (lb, ub)``.

    Its arrays are stacks padded to the largest node (``C (N+1, c, n)``, ``dx (N+1, n)``, ``P (N+1, n, n)``
    ...) shared by the compiled iterations (:mod:`.csqp_kernel`) and, as per-node views (``rows[t].C``,
    ``dx[t]`` ...), by the numpy twin below.
    """

    def __init__(self, ndx: list[int], nu: list[int], bounds: list[tuple[np.ndarray, np.ndarray]]) -> None:
        self._args = (ndx, nu, bounds)
        self.N = N = len(ndx) - 1
        self.ndx, self.nu = ndx, nu
        nc = [lb.size for lb, _ in bounds]
        n, m, c = max(ndx), max(nu), max(nc)
        self.dims = np.array([ndx, nu, nc], dtype=np.int64).T.copy()
        self.kind = np.zeros((N + 1, c), dtype=np.int64)
        self.C, self.D = np.zeros((N + 1, c, n)), np.zeros((N + 1, c, m))
        self.lb, self.ub, self.lo, self.hi = (np.zeros((N + 1, c)) for _ in range(4))
        self.z, self.y, self.rho, self.eta = (np.zeros((N + 1, c)) for _ in range(4))
        self.dx_s, self.dx_bar_s, self.p_s, self.Pd_s = (np.zeros((N + 1, n)) for _ in range(4))
        self.du_s, self.du_bar_s, self.k_s = (np.zeros((N + 1, m)) for _ in range(3))
        self.P_s, self.K_s, self.L_s = np.zeros((N + 1, n, n)), np.zeros((N + 1, m, n)), np.zeros((N + 1, m, m))
        self.rows = [NodeRows(self, t, lb, ub) for t, (lb, ub) in enumerate(bounds)]
        self.active = [t for t, r in enumerate(self.rows) if r.lb.size]
        self.dx = [self.dx_s[t, :k] for t, k in enumerate(ndx)]
        self.du = [self.du_s[t, :k] for t, k in enumerate(nu[:-1])]
        self.dx_bar = [self.dx_bar_s[t, :k] for t, k in enumerate(ndx)]
        self.du_bar = [self.du_bar_s[t, :k] for t, k in enumerate(nu[:-1])]
        self.P = [self.P_s[t, :k, :k] for t, k in enumerate(ndx)]
        self.p = [self.p_s[t, :k] for t, k in enumerate(ndx)]
        self.K = [self.K_s[t, :j, :k] for t, (j, k) in enumerate(zip(nu[:-1], ndx))]
        self.k = [self.k_s[t, :j] for t, j in enumerate(nu[:-1])]
        self._Pd = [self.Pd_s[t, :k] for t, k in enumerate(ndx)]
        self._chol: list = [None] * self.N
        self.rho_bar = 0.1
        self.r_prim = self.r_dual = self.s_prim = self.s_dual = 0.0
        self.factorised = False
        """Whether ``P``, ``K``, ``L`` are the factors of the current ``ρ`` (set by :meth:`run`; every QP starts with
        :meth:`assign_rho`, which clears it)."""

    def update_bounds(self, bounds: list[tuple[np.ndarray, np.ndarray]]) -> None:
        """New values of the rows' bounds, of the shapes the QP was made with (the ADMM state is kept)."""
        for t, (row, (lb, ub)) in enumerate(zip(self.rows, bounds)):
            row.bound(self, t, lb, ub)
        self._args = (self.ndx, self.nu, bounds)
        self.factorised = False

    _STATE = ("z", "y", "rho", "dx_s", "du_s", "dx_bar_s", "du_bar_s", "P_s", "p_s", "Pd_s", "K_s", "k_s", "L_s")

    def __getstate__(self) -> dict:
        """The constructor's arguments, the ADMM state and the read-outs (the views are rebuilt on unpickling)."""
        return {"args": self._args, "arrays": {a: getattr(self, a) for a in self._STATE},
                "scalars": (self.rho_bar, self.r_prim, self.r_dual, self.s_prim, self.s_dual)}

    def __setstate__(self, state: dict) -> None:
        self.__init__(*state["args"])
        for name, a in state["arrays"].items():
            getattr(self, name)[...] = a
        self.rho_bar, self.r_prim, self.r_dual, self.s_prim, self.s_dual = state["scalars"]

    # ------------------------------------------------------------------ Riccati x-update
    def riccati(self, lq, d: list, sigma: float, mu: float, rows: bool, full: bool) -> None:
        """Backward pass of the LQ ``lq`` (``Fx, Fu, Lx, Lu, Lxx, Lxu, Luu`` per node, ``lq[N]`` terminal)
        augmented by ``σ`` and, if ``rows``, by the rows' ``ρ`` and ``η = y - ρ z``; ``full`` refactorises
        ``Quu`` (else reuses ``K``, ``P`` and the factors of the last full pass).  Raises BackwardPassError."""
        N = self.N
        term = lq[N]
        eta = self._eta(rows)
        p = self.p[N]
        p[:] = term.Lx
        if sigma:
            p -= sigma * self.dx_bar[N]
        if rows and self.rows[N].lb.size:
            p += self.rows[N].C.T @ eta[N]
        if full:
            P = self.P[N]
            P[:] = term.Lxx
            if rows and self.rows[N].lb.size:
                r = self.rows[N]
                P += r.C.T @ (r.rho[:, None] * r.C)
            P.flat[:: P.shape[0] + 1] += sigma + mu
        for t in range(N - 1, -1, -1):
            data, r = lq[t], self.rows[t]
            with_rows = rows and r.lb.size
            if full:
                np.dot(self.P[t + 1], d[t + 1], out=self._Pd[t + 1])
            g = self.p[t + 1] + self._Pd[t + 1]
            Qx = data.Lx + data.Fx.T @ g
            Qu = data.Lu + data.Fu.T @ g
            if sigma:
                Qx -= sigma * self.dx_bar[t]
                Qu -= sigma * self.du_bar[t]
            if with_rows:
                if t:
                    Qx += r.C.T @ eta[t]
                Qu += r.D.T @ eta[t]
            if full:
                self._factorise(t, data, r if with_rows else None, sigma, mu)
            if self.nu[t]:
                self.k[t][:] = dpotrs(self._chol[t], Qu, lower=0)[0]
                Qx -= self.K[t].T @ Qu
            self.p[t][:] = Qx

    def _factorise(self, t: int, data, r: NodeRows | None, sigma: float, mu: float) -> None:
        """``Quu`` factors, ``K`` and ``P_t`` of node ``t`` (the terms that do not depend on ``z``, ``y``, ``w̄``)."""
        Pn = self.P[t + 1]
        FxP = data.Fx.T @ Pn
        Qxx = data.Lxx + FxP @ data.Fx
        Qxx.flat[:: Qxx.shape[0] + 1] += sigma
        if r is not None and t:
            Qxx += r.C.T @ (r.rho[:, None] * r.C)
        P = self.P[t]
        if self.nu[t]:
            FuP = data.Fu.T @ Pn
            Quu = data.Luu + FuP @ data.Fu
            Quu.flat[:: Quu.shape[0] + 1] += sigma + mu
            Qxu = data.Lxu + FxP @ data.Fu
            if r is not None:
                rD = r.rho[:, None] * r.D
                Quu += r.D.T @ rD
                if t:
                    Qxu += r.C.T @ rD
            chol, info = dpotrf(Quu, lower=0, clean=0)
            if info != 0 or not np.isfinite(chol).all():
                raise BackwardPassError(f"Quu is not positive definite at node {t}")
            self._chol[t] = chol
            self.K[t][:] = dpotrs(chol, Qxu.T, lower=0)[0]
            Qxx -= Qxu @ self.K[t]
        P[:] = Qxx
        P += P.T
        P *= 0.5
        P.flat[:: P.shape[0] + 1] += mu

    def _eta(self, rows: bool) -> list:
        if not rows:
            return []
        return [r.y - r.rho * r.z for r in self.rows]

    def rollout(self, lq, d: list) -> None:
        """``δx_0 = d_0``, ``δu_t = -k_t - K_t δx_t``, ``δx_{t+1} = A δx_t + B δu_t + d_{t+1}``."""
        dx, du = self.dx, self.du
        dx[0][:] = d[0]
        for t in range(self.N):
            data = lq[t]
            if self.nu[t]:
                np.negative(self.k[t], out=du[t])
                du[t] -= self.K[t] @ dx[t]
                np.dot(data.Fu, du[t], out=dx[t + 1])
                dx[t + 1] += data.Fx @ dx[t]
            else:
                np.dot(data.Fx, dx[t], out=dx[t + 1])
            dx[t + 1] += d[t + 1]

    def multipliers(self) -> list[np.ndarray]:
        """The dynamics' multipliers ``λ_t = p_t + P_t δx_t`` of the last pass."""
        return [p + P @ x for p, P, x in zip(self.p, self.P, self.dx)]

    # ------------------------------------------------------------------ ADMM loop
    def set_anchor(self) -> None:
        """``w̄ ← w`` (the current step becomes the proximal anchor)."""
        for a, b in zip(self.dx_bar, self.dx):
            a[:] = b
        for a, b in zip(self.du_bar, self.du):
            a[:] = b

    def assign_rho(self, rho_min: float) -> None:
        """Per-row ``ρ``: ``rho_min`` (free), ``1e3 ρ̄`` (equality), ``ρ̄`` (the others)."""
        rho, kind = self.rho_bar, self.kind
        self.factorised = False
        self.rho[:] = np.where(kind == FREE, rho_min, np.where(kind == EQUALITY, 1e3 * rho, rho))

    def iterate(self, j: int, s) -> bool:
        """ADMM iteration ``j`` (from 1) with settings ``s`` (the solver); True when the stopping test passed
        (it runs every ``rho_update_interval`` iterations, after the ρ update)."""
        alpha = s.alpha
        check = j % s.rho_update_interval == 0
        r_p = r_d = s_p = s_d = -np.inf
        for t in self.active:
            r = self.rows[t]
            v = r.C @ self.dx[t]
            if t < self.N:
                v += r.D @ self.du[t]
            z_hat = alpha * v + (1.0 - alpha) * r.z
            z_new = np.clip(z_hat + r.y / r.rho, r.lo, r.hi)
            r.y += r.rho * (z_hat - z_new)
            if check:
                dz = r.rho * (z_new - r.z)
                r_p = max(r_p, np.abs(v - z_new).max())
                s_p = max(s_p, np.abs(v).max(), np.abs(z_new).max())
                if s.update_rho_with_heuristic:
                    r_d = max(r_d, np.abs(dz).max())
                    s_d = max(s_d, np.abs(r.y).max())
                else:
                    r_d = max(r_d, _tmax(r.C, dz), _tmax(r.D, dz) if t < self.N else -np.inf)
                    s_d = max(s_d, _tmax(r.C, r.y), _tmax(r.D, r.y) if t < self.N else -np.inf)
            r.z[:] = z_new
        self.set_anchor()
        if not check:
            return False
        self.r_prim, self.r_dual, self.s_prim, self.s_dual = r_p, r_d, s_p, s_d
        self._update_rho(s)
        return self.stopping_test(j, s)

    def stopping_test(self, j: int, s) -> bool:
        """The stopping test of iteration ``j`` on the last residuals (printed if ``s.with_qp_callbacks``)."""
        r_p, r_d = self.r_prim, self.r_dual
        if abs(s.eps_rel) <= np.finfo(float).eps:
            eps_p = eps_d = s.eps_abs
        else:
            eps_p, eps_d = s.eps_abs + s.eps_rel * self.s_prim, s.eps_abs + s.eps_rel * self.s_dual
        if s.with_qp_callbacks:
            print(f"QP iter {j:5d}  r_prim {r_p:.3e} (eps {eps_p:.3e})  r_dual {r_d:.3e} (eps {eps_d:.3e})  "
                  f"rho {self.rho_bar:.3e}")
        return r_p <= eps_p and r_d <= eps_d

    # ------------------------------------------------------------------ compiled iterations
    def run(self, daddr: np.ndarray, haddr: np.ndarray, terminal, s, mu: float, j0: int, j1: int,
            anchor: bool) -> int:
        """ADMM iterations ``j0 <= j < j1`` compiled (:func:`.csqp_kernel.admm_run`; the equality pass first if
        ``anchor``): ``daddr`` lists the running nodes' derivatives (:class:`.horizon.NodeDerivatives`),
        ``haddr`` the solver's horizon buffer (gaps), ``terminal`` the terminal data; settings ``s`` (the
        solver).  Returns the iteration whose stopping test passed, or 0.  Raises BackwardPassError."""
        par = np.array([s.sigma, mu, s.alpha, s.rho_min, s.rho_max, s.adaptive_rho_tolerance, s.eps_abs, s.eps_rel,
                        self.rho_bar])
        ipar = np.array([j0, j1, max(int(s.rho_update_interval), 1), bool(s.update_rho_with_heuristic), anchor,
                         self.factorised], dtype=np.int64)
        out = np.array([self.r_prim, self.r_dual, self.s_prim, self.s_dual, self.rho_bar, self.factorised])
        status = csqp_kernel.admm_run(
            self.dims, daddr, haddr, horizon.FS, readable(terminal.Lx), readable(terminal.Lxx), self.kind, self.C,
            self.D, self.lo, self.hi, self.z, self.y, self.rho, self.eta, self.dx_s, self.du_s, self.dx_bar_s,
            self.du_bar_s, self.P_s, self.p_s, self.Pd_s, self.K_s, self.k_s, self.L_s, par, ipar, out)
        self.r_prim, self.r_dual, self.s_prim, self.s_dual = (float(v) for v in out[:4])
        self.rho_bar = float(out[4])
        self.factorised = bool(out[5])
        if status < 0:
            raise BackwardPassError(f"Quu is not positive definite at node {-status - 1}")
        return int(status)

    def multipliers_into(self, lam: np.ndarray) -> None:
        """``λ_t = p_t + P_t δx_t`` of the last pass into the stack ``lam (N+1, n)``, compiled."""
        csqp_kernel.multipliers(self.dims, self.P_s, self.p_s, self.dx_s, lam)

    def _update_rho(self, s) -> None:
        with np.errstate(divide="ignore", invalid="ignore"):
            estimate = self.rho_bar * np.sqrt((self.r_prim * self.s_dual) / (self.r_dual * self.s_prim))
        if np.isnan(estimate):
            return
        estimate = min(max(estimate, s.rho_min), s.rho_max)
        tol = s.adaptive_rho_tolerance
        if estimate > tol * self.rho_bar or estimate < self.rho_bar / tol:
            self.rho_bar = float(estimate)
            self.assign_rho(s.rho_min)


def _tmax(M: np.ndarray, v: np.ndarray) -> float:
    """``‖Mᵀ v‖∞`` (``-inf`` for an empty product)."""
    return float(np.abs(M.T @ v).max(initial=-np.inf))
