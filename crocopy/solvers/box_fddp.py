"""Control-limited feasibility-driven DDP (Mastalli et al., Box-FDDP, Algorithm 1).

* While the iterate is infeasible (open gaps ``fs``) the backward pass is plain FDDP with the
  gap-deflected gradient ``V⁺x = Vx + Vxx f`` and unconstrained gains
  ``k = Quu⁻¹ Qu``, ``K = Quu⁻¹ Qux`` ("equivalent to opening the control bounds").
* Once feasible, each bounded node solves the box QP of :mod:`crocopy.solvers.box_ddp`
  warm-started at the previous iteration's ``-k`` projected into ``[u_lb - u, u_ub - u]``
  (paper eq. 15), with ``K`` on the free subspace (eq. 8).
* Every trial rollout projects the controls onto the box (eq. 16), in both modes, and shrinks the
  gaps by ``(1 - α)`` (eqs. 17, 19): ``x̂₀ = x0 ⊕ ((α-1) f₀)``, ``x̂_{t+1} = f(x̂_t, û_t) ⊕ ((α-1) f_{t+1})``.
* The value-function update and the ``Qu`` zeroing of clamped controls follow
  :mod:`crocopy.solvers.box_ddp` (Crocoddyl's by default, ``general_value_update = True`` for
  Tassa's exact update; the Box-FDDP paper does not restate it).
* Expected improvement (eqs. 20–21) is FDDP's, ``dVexp(α) = α (d₀ + ½ α d₁)`` with the gap terms;
  steps predicted to increase the cost are accepted when the actual increase is at most
  ``th_acceptNegStep = 2`` times the prediction; a full step makes the iterate feasible.

Constants the paper leaves open, set to Crocoddyl's documented defaults: ``th_stop = 5e-5``,
``th_acceptStep = 0.1``, ``th_acceptNegStep = 2``, initial regularisation ``1e-9`` (the paper's),
factors 10, ``reg_max = 1e9``, decrease after steps ``α > 0.5``, increase after ``α <= 0.01``,
step lengths ``2^-n``, ``n = 0..9``; box QP ``th_grad = 1e-5``.  ``compat_crocoddyl = True``
reproduces Crocoddyl 3.2's QP warm-start sign and line-search rule (:mod:`crocopy.solvers.box_ddp`).
"""

from __future__ import annotations

from ..shooting import ShootingProblem
from .box_ddp import BoxSolverMixin
from .fddp import SolverFDDP

__all__ = ["SolverBoxFDDP"]


class SolverBoxFDDP(BoxSolverMixin, SolverFDDP):
    """Crocoddyl's ``SolverBoxFDDP(problem)``.

    Parameters
    ----------
    problem : ShootingProblem
        Problem whose running models carry the control bounds ``u_lb``/``u_ub``.
    """

    _nodes_compiled = True
    _line_search = (False, True)
    """``(negative, bounded)`` of the compiled line search (:mod:`.line_search`)."""
    _gap_search = (False, False)
    """``(every, grad_negative)`` of the compiled line search from an infeasible iterate: gaps kept open where
    ``α ≠ 1``, a negative ``dVexp`` passing on ``dV > th_acceptNegStep dVexp`` alone (:meth:`_accept`)."""

    def __init__(self, problem: ShootingProblem) -> None:
        super().__init__(problem)
        self._init_box()

    def _accept(self, alpha: float) -> bool:
        # A predicted cost increase is admissible only while closing gaps: on a feasible iterate a
        # negative dVexp (possible once clamped controls are zeroed out of d₀) rejects the step.
        if self.dVexp >= 0:
            return abs(self.d[0]) < self.th_grad or self.dV > self.th_acceptStep * self.dVexp
        return not self.isFeasible and self.dV > self.th_acceptNegStep * self.dVexp

    def forwardPass(self, steplength: float) -> None:
        """Rollout with projected controls and gaps contracted by ``(1 - steplength)`` (none after a full step)."""
        gaps = not self.isFeasible and steplength != 1.0
        self._trial_rollout(steplength, gaps=gaps, bounds=(self._lb, self._ub))
