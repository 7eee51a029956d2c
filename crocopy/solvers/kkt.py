"""Newton's method on the whole stacked problem (Crocoddyl's ``SolverKKT``).

Primal unknowns ``w = (δx₀ … δx_T, δu₀ … δu_{T-1})`` (``nw = (T+1) ndx + Σ nu``), one multiplier
``λ_t`` (``ndx``) per dynamics row, ``nkkt = nw + (T+1) ndx``.  At the current iterate the
Gauss-Newton KKT system ``kkt · primaldual = -kktref`` is::

    kkt    = [[Hw, Jᵀ], [J, 0]]         Hw = blockdiag over nodes of [[Lxx, Lxu], [Lux, Luu]]
    kktref = [g; c]                     g  = (Lx₀ … Lx_T, Lu₀ … Lu_{T-1})

with the dynamics rows ``δx₀ = x0 ⊖ x₀`` and ``δx_{t+1} - Fx δx_t - Fu δu_t = f(x_t, u_t) ⊖ x_{t+1}``
(``c = -fs``).  ``primaldual`` splits into ``dxs``, ``dus`` and ``lambdas``.  The expected
improvement is ``d = (-gᵀ w, -wᵀ Hw w)``; the trial step is ``x ⊕ α δx``, ``u + α δu`` (no rollout:
the dynamics are met at convergence), accepted unless ``dVexp ≥ 0`` and ``dV ≤ th_acceptStep dVexp``;
``stop = ‖g + Jᵀ λ‖² + ‖c‖²``, and ``solve`` returns True once ``stop < th_stop``.  Equality and
inequality rows of the nodes are not part of the system (as in Crocoddyl).  The system is dense:
work grows as ``nkkt³``, for small problems and tests.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

from ..shooting import ShootingProblem
from .base import Setting, SolverAbstract


class SolverKKT(SolverAbstract):
    """Crocoddyl's ``SolverKKT(problem)``: full-space Newton steps with a backtracking line search.

    Attributes
    ----------
    kkt : np.ndarray, shape (nkkt, nkkt)
        KKT matrix of the current iterate.
    kktref : np.ndarray, shape (nkkt,)
        Right-hand side ``[g; c]`` (the system solved is ``kkt · primaldual = -kktref``).
    primaldual : np.ndarray, shape (nkkt,)
        Newton step and multipliers.
    dxs, dus, lambdas : list of np.ndarray
        Views of ``primaldual``: T+1 state steps, T control steps, T+1 multipliers.
    """

    x_reg = Setting(allow_inf=False)
    u_reg = Setting(allow_inf=False)

    def __init__(self, problem: ShootingProblem) -> None:
        super().__init__(problem)
        models = [*problem.runningModels, problem.terminalModel]
        ndx = [m.state.ndx for m in models]
        nus = [m.nu for m in problem.runningModels]
        self._x_off = np.concatenate([[0], np.cumsum(ndx)]).astype(int)
        nx_total = int(self._x_off[-1])
        self._u_off = nx_total + np.concatenate([[0], np.cumsum(nus)]).astype(int)
        self._nw = int(self._u_off[-1])
        self._l_off = self._nw + self._x_off
        n = self._nw + nx_total
        self.kkt = np.zeros((n, n))
        self.kktref = np.zeros(n)
        self.primaldual = np.zeros(n)
        self.dxs = [self.primaldual[a:b] for a, b in zip(self._x_off[:-1], self._x_off[1:])]
        self.dus = [self.primaldual[a:b] for a, b in zip(self._u_off[:-1], self._u_off[1:])]
        self.lambdas = [self.primaldual[a:b] for a, b in zip(self._l_off[:-1], self._l_off[1:])]
        self.x_reg = 0.0
        self.u_reg = 0.0
        self.feas = 0.0
        self.dfeas = 0.0
        self.cost_try = 0.0
        self.alphas = [2.0 ** (-n) for n in range(10)]
        self._gaps: list[np.ndarray] = []

    def solve(self, init_xs=None, init_us=None, maxiter: int = 100, is_feasible: bool = False, init_reg=None) -> bool:
        """Newton iterations from ``(init_xs, init_us)``; True once ``stop < th_stop`` (see ``reason``)."""
        self._check_x0()
        self.setCandidate(init_xs, init_us, is_feasible)
        self.reason = ""
        for self.iter in range(maxiter):
            try:
                self.computeDirection(True)
            except (np.linalg.LinAlgError, ValueError) as exc:
                self.reason = f"the KKT system could not be solved ({exc})"
                return False
            self.stoppingCriteria()
            self.expectedImprovement()
            for alpha in self.alphas:
                self.stepLength = alpha
                with np.errstate(over="ignore", invalid="ignore"):
                    self.dV = self.tryStep(alpha)
                self.dVexp = alpha * (self.d[0] + 0.5 * alpha * self.d[1])
                if np.isfinite(self.cost_try) and (self.dVexp < 0 or self.dV > self.th_acceptStep * self.dVexp):
                    self.xs = [x.copy() for x in self._xs_try]
                    self.us = [u.copy() for u in self._us_try]
                    self.cost = self.cost_try
                    break
            self._run_callbacks()
            if self.stop < self.th_stop:
                self.reason = "converged"
                return True
            if not np.isfinite(self.stop):
                self.reason = "the KKT residual is not finite"
                return False
        self.iter = maxiter
        self.reason = f"maximum number of iterations ({maxiter}) reached"
        return False

    def calcDiff(self) -> float:
        """Evaluate and differentiate every node at the current iterate; compute the gaps.

        As Crocoddyl's, the gaps enter ``kktref`` only: ``fs`` and ``ffeas`` stay 0 (the verbose
        print-out shows ``||ffeas||`` 0).
        """
        p = self.problem
        p.calc(self.xs, self.us)
        self.cost = p.calcDiff(self.xs, self.us)
        models = p.runningModels
        self._gaps = [(models[0] if models else p.terminalModel).state.diff(self.xs[0], p.x0)]
        self._gaps += [m.state.diff(x, d.xnext) for m, d, x in zip(models, p.runningDatas, self.xs[1:])]
        return self.cost

    def computeDirection(self, recalc: bool = True) -> None:
        """Assemble the KKT system at the current iterate (derivatives if ``recalc``) and solve it."""
        if recalc:
            self.calcDiff()
        p = self.problem
        kkt, ref = self.kkt, self.kktref
        kkt[:] = 0.0
        xo, uo, lo, nw = self._x_off, self._u_off, self._l_off, self._nw
        for t, d in enumerate(p.runningDatas):
            xs, us = slice(xo[t], xo[t + 1]), slice(uo[t], uo[t + 1])
            kkt[xs, xs] = d.Lxx
            kkt[xs, us] = d.Lxu
            kkt[us, xs] = d.Lxu.T
            kkt[us, us] = d.Luu
            ref[xs] = d.Lx
            ref[us] = d.Lu
            lam = slice(lo[t + 1], lo[t + 2])
            kkt[lam, xs] = -d.Fx
            kkt[lam, us] = -d.Fu
        T = p.T
        xT = slice(xo[T], xo[T + 1])
        kkt[xT, xT] = p.terminalData.Lxx
        ref[xT] = p.terminalData.Lx
        for t in range(T + 1):
            lam, xs = slice(lo[t], lo[t + 1]), slice(xo[t], xo[t + 1])
            kkt[lam, xs] = np.eye(xs.stop - xs.start)
            ref[lam] = -self._gaps[t]
        kkt[:nw, nw:] = kkt[nw:, :nw].T
        self.primaldual[:] = -scipy.linalg.solve(kkt, ref, assume_a="sym")

    def expectedImprovement(self) -> np.ndarray:
        """``d = (-gᵀ w, -wᵀ Hw w)`` for the Newton step ``w``."""
        nw = self._nw
        w = self.primaldual[:nw]
        self.d[0] = -float(self.kktref[:nw] @ w)
        self.d[1] = -float(w @ self.kkt[:nw, :nw] @ w)
        return self.d

    def stoppingCriteria(self) -> float:
        """``‖g + Jᵀ λ‖² + ‖c‖²`` with the multipliers of the last KKT solve."""
        nw = self._nw
        r = self.kktref[:nw] + self.kkt[:nw, nw:] @ self.primaldual[nw:]
        c = self.kktref[nw:]
        self.stop = float(r @ r + c @ c)
        return self.stop

    def tryStep(self, steplength: float = 1.0) -> float:
        """Cost reduction ``cost - cost_try`` at ``x ⊕ α δx``, ``u + α δu`` (no rollout)."""
        p = self.problem
        models = [*p.runningModels, p.terminalModel]
        self._xs_try = [m.state.integrate(x, steplength * dx) for m, x, dx in zip(models, self.xs, self.dxs)]
        self._us_try = [u + steplength * du for u, du in zip(self.us, self.dus)]
        self.cost_try = p.calc(self._xs_try, self._us_try)
        return self.cost - self.cost_try
