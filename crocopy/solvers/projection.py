"""Equality-constrained DDP by nullspace projection (Giftthaler & Buchli), ``SolverProjection``.

Each node's equality rows ``h(x, u) = 0`` (``data.h[:nh]`` with ``Hx``, ``Hu``; terminal nodes
``data.h[:nh_T]``) are linearised and handled in the backward pass of
:mod:`crocopy.solvers.projection_lq`: state-input rows restrict the control update to the nullspace
of their Jacobian, pure-state rows are previewed one step (relative degree one), and the policy
``û = u - α k - K (x̂ ⊖ x)`` carries the minimum-norm correction ``ε`` inside ``k`` (so ``α`` also
scales it).  The line search runs on the merit ``cost + σ Σ_t ‖h_t‖₁``; the expected improvement
comes from a linear rollout of the policy (``d₀ = -c₁ + σ‖h‖₁``, ``d₁ = -c₂``) and ``σ`` grows when
needed so that the full step is a descent direction of the merit.  Without equality rows every
step is the :class:`~crocopy.solvers.ddp.SolverDDP` step.  Work per iteration is linear in T.
"""

from __future__ import annotations

import numpy as np

from ..shooting import ShootingProblem
from .base import BackwardPassError, Setting
from .ddp import SolverDDP
from .nonfinite import locate_in_derivatives
from .projection_lq import ConstraintRankError, linear_rollout_model_change, projected_backward_pass

__all__ = ["ConstraintRankError", "SolverProjection"]


class SolverProjection(SolverDDP):
    """DDP with equality constraints by projection (Giftthaler & Buchli's projected iLQR).

    Parameters
    ----------
    problem : ShootingProblem
        Problem whose nodes expose equality rows ``h``/``Hx``/``Hu`` (``nh`` running, ``nh_T`` terminal).

    Attributes
    ----------
    sigma : float
        Weight of the ℓ₁ constraint violation in the merit (raised automatically when needed).
    th_rank : float
        Relative singular-value threshold of the rank and relative-degree tests.
    th_x0 : float
        Largest violation of pure-state rows at ``x0`` accepted (they cannot be corrected).
    hfeas_l1 : float
        ``Σ_t ‖h_t‖₁`` of the current iterate.
    x0_violation : float
        Violation of the pure-state rows at node 0 (checked once the iterate is a rollout from ``x0``).

    Raises
    ------
    ConstraintRankError
        From :meth:`solve`/:meth:`computeDirection` when the linearised constraints of some node are
        rank-deficient, have relative degree above one or over-constrain the controls.
    """

    _nodes_compiled = True  # reads only the action datas' values, derivatives and rows (compiled nodes write them)
    sigma = Setting()
    th_rank = Setting(allow_inf=False)
    th_x0 = Setting()

    def __init__(self, problem: ShootingProblem) -> None:
        super().__init__(problem)
        self.sigma = 10.0
        self.th_rank = 1e-9
        self.th_x0 = 1e-6
        self.hfeas_l1 = 0.0
        self.hfeas_l1_try = 0.0
        self.x0_violation = 0.0
        self._has_eq = any(m.nh for m in problem.runningModels) or bool(problem.terminalModel.nh_T)

    def _on_problem_change(self) -> bool:
        problem = self.problem
        self._has_eq = any(m.nh for m in problem.runningModels) or bool(problem.terminalModel.nh_T)
        return super()._on_problem_change()

    def _score(self) -> float:
        return self.cost + self.sigma * self.hfeas_l1 if self._has_eq else self.cost

    def _score_try(self) -> float:
        return self.cost_try + self.sigma * self.hfeas_l1_try if self._has_eq else self.cost_try

    def _restore_best(self) -> None:
        restored = self._best is not None
        super()._restore_best()
        if restored:
            self.hfeas_l1 = self._equality_l1()
            self.merit = self.cost + self.sigma * self.hfeas_l1
            self.computeEqualityFeasibility()

    def _start(self, init_xs, init_us, is_feasible: bool, init_reg) -> None:
        """As DDP; with equality rows the guess is first rolled out from ``x0`` (the method needs it)."""
        super()._start(init_xs, init_us, is_feasible, init_reg)
        if self._has_eq and not self.isFeasible:
            self.xs = [x.copy() for x in self.problem.rollout(self.us)]
            self.isFeasible = True

    def _equality_l1(self) -> float:
        p = self.problem
        total = sum(float(np.sum(np.abs(d.h[: m.nh]))) for m, d in zip(p.runningModels, p.runningDatas))
        return total + float(np.sum(np.abs(p.terminalData.h[: p.terminalModel.nh_T])))

    def calcDiff(self) -> float:
        """Derivatives of every node at the current iterate, gaps, feasibilities and merit."""
        cost = super().calcDiff()
        self.hfeas_l1 = self._equality_l1()
        self.merit = cost + self.sigma * self.hfeas_l1
        return cost

    def backwardPass(self) -> None:
        """Projected Riccati recursion (see :func:`projected_backward_pass`) into ``k, K, Vx, Vxx, Qu, Quu``."""
        p = self.problem
        T = p.T
        rd, rm, td, tm = p.runningDatas, p.runningModels, p.terminalData, p.terminalModel
        try:
            res = projected_backward_pass(
                [d.Fx for d in rd], [d.Fu for d in rd],
                [*(d.Lx for d in rd), td.Lx], [d.Lu for d in rd],
                [*(d.Lxx for d in rd), td.Lxx], [d.Lxu for d in rd], [d.Luu for d in rd],
                [*(d.Hx[: m.nh] for m, d in zip(rm, rd)), td.Hx[: tm.nh_T]],
                [d.Hu[: m.nh] for m, d in zip(rm, rd)],
                [*(d.h[: m.nh] for m, d in zip(rm, rd)), td.h[: tm.nh_T]],
                None if self.isFeasible else self.fs,
                self.preg, self.preg, self.th_rank,
            )
        except np.linalg.LinAlgError as exc:
            nonfinite = locate_in_derivatives(p)
            if nonfinite is not None:
                raise nonfinite from exc
            raise BackwardPassError(f"reduced Hessian is not positive definite ({exc})") from exc
        for t in range(T):
            self.k[t][:] = res.k[t]
            self.K[t][:] = res.K[t]
            self.Qu[t][:] = res.Qu[t]
            self.Quu[t][:] = res.Quu[t]
        for t in range(T + 1):
            self.Vx[t][:] = res.Vx[t]
            self.Vxx[t][:] = res.Vxx[t]
        if not self.isFeasible:
            return
        self.x0_violation = float(np.max(np.abs(res.d0))) if res.d0.size else 0.0
        if self.x0_violation > self.th_x0:
            raise ConstraintRankError(
                0, "infeasible",
                f"x0 violates pure-state equality rows by {self.x0_violation:.3g} > th_x0 = {self.th_x0:g}; "
                "the initial state cannot be corrected",
            )

    def expectedImprovement(self) -> np.ndarray:
        """``d`` such that ``α (d₀ + ½ α d₁)`` predicts the merit decrease of step ``α``."""
        if not self._has_eq:
            return super().expectedImprovement()
        h1 = self.hfeas_l1
        p = self.problem
        rd, td = p.runningDatas, p.terminalData
        c1, c2 = linear_rollout_model_change(
            [d.Fx for d in rd], [d.Fu for d in rd], [*(d.Lx for d in rd), td.Lx], [d.Lu for d in rd],
            [*(d.Lxx for d in rd), td.Lxx], [d.Lxu for d in rd], [d.Luu for d in rd], self.k, self.K,
        )
        worst = max(c1, c1 + 0.5 * c2)
        if h1 > 0.0 and worst > 0.5 * self.sigma * h1:
            self.sigma = 2.0 * worst / h1
        self.merit = self.cost + self.sigma * h1
        self.d[0] = -c1 + self.sigma * h1
        self.d[1] = -c2
        return self.d

    def tryStep(self, steplength: float = 1.0) -> float:
        """Roll out with step ``steplength``; returns the merit reduction ``merit - merit_try``."""
        self.forwardPass(steplength)
        if not self._has_eq:
            return self.cost - self.cost_try
        self.hfeas_l1_try = self._equality_l1()
        return self.merit - (self.cost_try + self.sigma * self.hfeas_l1_try)

    def _accept_trial(self, alpha: float) -> None:
        super()._accept_trial(alpha)
        if self._has_eq:
            self.hfeas_l1 = self.hfeas_l1_try
            self.merit = self.cost + self.sigma * self.hfeas_l1
            self.computeEqualityFeasibility()

    def stoppingCriteria(self) -> float:
        """``stop = |c₁ + ½ c₂| + σ Σ‖h‖₁`` (the DDP criterion without equality rows)."""
        if not self._has_eq:
            return super().stoppingCriteria()
        self.stop = abs(self.d[0] - self.sigma * self.hfeas_l1 + 0.5 * self.d[1]) + self.sigma * self.hfeas_l1
        return self.stop
