"""Feasibility-driven DDP (Crocoddyl's ``SolverFDDP``; Box-FDDP paper §III without bounds).

The rollout keeps the gaps open by ``(1 - α)``: ``x̂₀ = x0 ⊕ ((α-1) f₀)``,
``x̂_{t+1} = f(x̂_t, û_t) ⊕ ((α-1) f_{t+1})``.  The expected improvement adds the gap terms
``d₀ = Σ Quᵀk - Σ Vxᵀf + dv`` and ``d₁ = -Σ kᵀQuu k + Σ fᵀVxx f - 2 dv`` with
``dv = Σ fᵀ Vxx (x̂ ⊖ x)``.  A step predicted to increase the cost (``dVexp < 0``) is accepted
when the actual change is at most ``th_acceptNegStep`` times the predicted one.
"""

from __future__ import annotations

import numpy as np

from .. import kernels
from ..shooting import ShootingProblem
from . import horizon, riccati_kernel
from .base import Setting
from .ddp import SolverDDP


class SolverFDDP(SolverDDP):
    """Crocoddyl's ``SolverFDDP(problem)``."""

    _nodes_compiled = True
    _line_search = (True, False)
    """``(negative, bounded)`` of the compiled line search (:mod:`.line_search`)."""
    _gap_search = (True, True)
    """``(every, grad_negative)`` of the compiled line search from an infeasible iterate (:mod:`.line_search`): the
    gaps kept open at every step length, and ``|d₀| < th_grad`` passing a negative ``dVexp``."""
    th_acceptNegStep = Setting(allow_inf=False)

    def __init__(self, problem: ShootingProblem) -> None:
        super().__init__(problem)
        self.th_acceptNegStep = 2.0
        self._dg = 0.0
        self._dq = 0.0

    def _accept(self, alpha: float) -> bool:
        if self.dVexp >= 0:
            return abs(self.d[0]) < self.th_grad or self.dV > self.th_acceptStep * self.dVexp
        return abs(self.d[0]) < self.th_grad or self.dV > self.th_acceptNegStep * self.dVexp

    def _accept_trial(self, alpha: float) -> None:
        feasible = self.isFeasible or alpha == 1.0
        super()._accept_trial(alpha)
        self.isFeasible = feasible

    def computeDirection(self, recalc: bool = True) -> None:
        super().computeDirection(recalc)
        self.updateExpectedImprovement()

    _views = (*SolverDDP._views, "_Vxx_f_views", "_Vxx_f")

    def _bind_views(self) -> None:
        super()._bind_views()
        self._Vxx_f_views = self._horizon.views(horizon.VXX_F)
        self._Vxx_f: list[np.ndarray] = []

    def updateExpectedImprovement(self) -> None:
        """Parts of the expected improvement that do not depend on the trial step (compiled while
        :func:`crocopy.kernels_enabled`, over the stacked arrays of :mod:`.horizon`)."""
        gaps = not self.isFeasible
        if kernels.active:
            h = self._horizon
            self._dg, self._dq = riccati_kernel.expected_terms(h.addr, h.dims, gaps)
            self._Vxx_f = self._Vxx_f_views if gaps else []
            return
        dg = dq = 0.0
        for Qu, Quu, k in zip(self.Qu, self.Quu, self.k):
            if k.size:
                dg += Qu @ k
                dq -= k @ Quu @ k
        self._Vxx_f = []
        if gaps:
            self._Vxx_f = [Vxx @ f for Vxx, f in zip(self.Vxx, self.fs)]
            for Vx, Vxx_f, f in zip(self.Vx, self._Vxx_f, self.fs):
                dg -= Vx @ f
                dq += f @ Vxx_f
        self._dg, self._dq = dg, dq

    def expectedImprovement(self) -> np.ndarray:
        """``d`` for the last trial step (``dv`` uses the trial states ``xs_try``)."""
        dv = 0.0
        if not self.isFeasible:
            problem = self.problem
            models = [*problem.runningModels, problem.terminalModel]
            Vxx_fs = self._Vxx_f or [Vxx @ f for Vxx, f in zip(self.Vxx, self.fs)]
            rest = range(len(models))
            nodes = self._nodes
            compiled = (kernels.active and self._Vxx_f is self._Vxx_f_views and nodes is not None
                        and nodes.horizon is not None)
            if compiled:  # the compiled ranges of the rollout wrote their nodes' dx
                h = self._horizon
                dv = riccati_kernel.gap_step_term(h.addr, h.dims, self._addresses().dx_try * nodes.inside)
                rest = [*nodes.python_nodes, problem.T]
            for t in rest:
                m, Vxx_f = models[t], Vxx_fs[t]
                if compiled and t == problem.T and hasattr(nodes.terminal, "diff"):
                    dx = self._terminal_step()[1]  # as the compiled line search takes it
                    nodes.terminal.diff(self.xs[t], self.xs_try[t], dx)
                    dv += riccati_kernel.step_term(Vxx_f, dx)
                    continue
                dx = self._dx_try[t]
                if dx is None:
                    dx = m.state.diff(self.xs[t], self.xs_try[t])
                dv += Vxx_f @ dx
        self.d[0] = self._dg + dv
        self.d[1] = self._dq - 2.0 * dv
        return self.d

    def _terminal_step(self) -> tuple[np.ndarray, np.ndarray]:
        """Two scratch tangent vectors of the terminal node (the compiled line search's ``(α - 1) f₀`` and the
        terminal trial step ``x̂_T ⊖ x_T``)."""
        ndx = self.problem.terminalModel.state.ndx
        scratch = self.__dict__.get("_terminal_scratch")
        if scratch is None or scratch[0].shape[0] != ndx:
            scratch = self._terminal_scratch = (np.zeros(ndx), np.zeros(ndx))
        return scratch

    def tryStep(self, steplength: float = 1.0) -> float:
        self.forwardPass(steplength)
        self.expectedImprovement()
        return self.cost - self.cost_try

    def forwardPass(self, steplength: float) -> None:
        """Rollout with the gaps shrunk by ``(1 - steplength)``; raises ForwardPassError on NaN."""
        self._trial_rollout(steplength, gaps=not self.isFeasible)
