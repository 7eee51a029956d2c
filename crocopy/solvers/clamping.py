"""Naive clamping baselines of Tassa, Mansard, Todorov (ICRA 2014, §III-A).

Both run plain DDP gains ``k = Quu⁻¹ Qu``, ``K = Quu⁻¹ Qux`` (Crocoddyl's sign,
``û = u - α k - K (x̂ ⊖ x)``) and differ in where the box ``[u_lb, u_ub]`` enters:

* ``clamping="forward"`` (variant 1, paper eq. 9): the rollout clamps the applied control,
  ``û = clamp(u - α k - K (x̂ ⊖ x))``.  The direction need not be a descent direction.
* ``clamping="backward"`` (variant 2): the feed-forward step is clamped in the backward pass,
  ``-k ← clamp(u - k) - u``, and the rows of ``K`` of the controls this clamps are zeroed ("it might
  also seem sensible"); the rollout also clamps, so the iterates stay inside the box (the paper
  does not say; without it ``K δx`` of the free rows could leave the box).  Since ``k`` and ``K``
  no longer minimise the Q-function, the value function of such nodes uses the general update of
  Tassa's code, ``Vx = Qx - Kᵀ Qu - Qxu k + Kᵀ Quu k``,
  ``Vxx = Qxx - Qxu K - Kᵀ Qux + Kᵀ Quu K`` (the DDP shortcut makes ``Vxx`` indefinite here).

The paper shows both to converge poorly (Fig. 2) — they are baselines for the experiments, not
solvers to use.  Everything else (regularisation, line search, stopping) is :class:`SolverDDP`'s.
"""

from __future__ import annotations

import numpy as np

from ..shooting import ShootingProblem
from .box_ddp import BoxSolverMixin
from .ddp import SolverDDP

__all__ = ["SolverClampedDDP"]


class SolverClampedDDP(BoxSolverMixin, SolverDDP):
    """DDP with naive control clamping (a baseline; see the module docstring).

    Parameters
    ----------
    problem : ShootingProblem
        Problem whose running models carry the control bounds ``u_lb``/``u_ub``.
    clamping : {"forward", "backward"}
        Variant 1 (clamp in the rollout) or variant 2 (clamp the feed-forward and zero the
        feedback rows of clamped controls in the backward pass, and clamp in the rollout).
    """

    def __init__(self, problem: ShootingProblem, clamping: str = "forward") -> None:
        if clamping not in ("forward", "backward"):
            raise ValueError(f"clamping must be 'forward' or 'backward', got {clamping!r}")
        super().__init__(problem)
        self._init_box()
        self.th_stop = 1e-9
        self.clamping = clamping

    def _box_mode(self) -> bool:
        return False

    def computeGains(self, t: int) -> None:
        """Cholesky gains, then (variant 2) the clamped feed-forward with zeroed feedback rows."""
        super().computeGains(t)
        lb = self._lb[t]
        self._clamped[t] = False
        if self.clamping == "backward" and lb is not None:
            u, k = self.us[t], self.k[t]
            target = u - k
            clamped = (target < lb) | (target > self._ub[t])
            if clamped.any():
                np.subtract(u, np.minimum(np.maximum(target, lb), self._ub[t]), out=k)
                self.K[t][clamped] = 0.0
                self._clamped[t] = True

    def computeValueFunction(self, t: int, model) -> None:
        """DDP value function, or the general update at nodes whose gains were clamped."""
        if not self._clamped[t]:
            super().computeValueFunction(t, model)
            return
        k, K, Qu, Quu, Qxu = self.k[t], self.K[t], self.Qu[t], self.Quu[t], self.Qxu[t]
        QxuK = Qxu @ K
        Vxx = self.Vxx[t]
        np.add(self.Qxx[t], K.T @ Quu @ K - QxuK - QxuK.T, out=Vxx)
        Vxx += Vxx.T
        Vxx *= 0.5
        if self.preg:
            Vxx.flat[:: Vxx.shape[0] + 1] += self.preg
        np.add(self.Qx[t], K.T @ (Quu @ k - Qu) - Qxu @ k, out=self.Vx[t])

    def forwardPass(self, steplength: float) -> None:
        """Rollout from ``x0`` with clamped controls; raises ForwardPassError on NaN."""
        self._trial_rollout(steplength, bounds=(self._lb, self._ub))
