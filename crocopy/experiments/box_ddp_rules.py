"""Box-DDP with switchable outer-loop rules: Crocoddyl's defaults or those of Tassa's reference code.

The Box-DDP paper (Tassa, Mansard, Todorov 2014) states no regularisation schedule, line search or
stopping rule; it adapts them "following a Levenberg-Marquardt heuristic" and cites its authors'
code.  The values below are that code's defaults as listed in ``DIGEST.md`` §1.1 (Tassa's public
``iLQG``), next to Crocoddyl's (:class:`~crocopy.solvers.SolverBoxDDP`'s own loop).  Each of the
three rules can be switched on its own, so that the iteration count of an experiment can be
attributed (``crocopy paper box-ddp car``).

``regularization``
    ``"crocoddyl"``: ``preg`` starts at ``reg_min = 1e-9``; ×10 after a step ``α <= 0.01`` or a
    failed backward pass, ÷10 after a step ``α > 0.5``.
    ``"tassa"``: ``λ = 1``, ``dλ = 1``; increase ``dλ ← max(1.6 dλ, 1.6)``, ``λ ← max(λ dλ, 1e-6)``
    after a failed backward pass or line search; decrease ``dλ ← min(dλ / 1.6, 1 / 1.6)``,
    ``λ ← λ dλ`` (0 once below ``1e-6``) after an accepted step; give up above ``1e10``.
    ``λ`` is applied as crocopy's ``preg`` (on the diagonals of ``Quu`` and ``Vxx``), not on ``Quu``
    alone as in the reference code.
``line_search``
    ``"crocoddyl"``: ``α ∈ {2⁻ⁿ, n = 0..9}``, accept when the actual reduction exceeds 0.1 times the
    predicted one.  ``"tassa"``: ``α ∈ 10^linspace(0, -3, 11)``, accept any actual reduction
    (ratio ``z > 0``).
``stopping``
    ``"crocoddyl"``: the predicted reduction of a full step ``|d₀ + ½ d₁| < th_stop = 5e-5``.
    ``"tassa"``: an accepted reduction below ``tol_fun``, or the relative feed-forward
    ``mean_t max_j |k_tj| / (|u_tj| + 1) < 1e-4`` while ``λ < 1e-5``.

Every variant uses the box QP, the clamped rollout and the exact value update of Box-DDP
(``general_value_update = True``).
"""

from __future__ import annotations

import numpy as np

from ..shooting import ShootingProblem
from ..solvers.box_ddp import SolverBoxDDP

__all__ = ["SolverBoxDDPRules"]

RULES = ("crocoddyl", "tassa")


class SolverBoxDDPRules(SolverBoxDDP):
    """Box-DDP whose regularisation, line search and stopping rule are Crocoddyl's or Tassa's.

    The main loop is :meth:`SolverDDP.solve`; Tassa's rules enter through its hooks (acceptance,
    regularisation updates, stopping criterion), so that Crocoddyl's rules are exactly
    :class:`~crocopy.solvers.SolverBoxDDP` with ``general_value_update = True``.

    Parameters
    ----------
    problem : ShootingProblem
        Problem with control bounds on its running models.
    regularization, line_search, stopping : {"crocoddyl", "tassa"}
        The rule of each kind (see the module docstring).
    tol_fun : float
        Tassa's stopping threshold on the accepted cost reduction (default 1e-7).
    """

    def __init__(self, problem: ShootingProblem, regularization: str = "tassa", line_search: str = "tassa",
                 stopping: str = "tassa", tol_fun: float = 1e-7) -> None:
        for name, value in (("regularization", regularization), ("line_search", line_search),
                            ("stopping", stopping)):
            if value not in RULES:
                raise ValueError(f"{name} must be one of {RULES}, got {value!r}")
        super().__init__(problem)
        self.general_value_update = True
        self.regularization, self.line_search, self.stopping = regularization, line_search, stopping
        self.tol_fun = float(tol_fun)
        if line_search == "tassa":
            self.alphas = list(10.0 ** np.linspace(0.0, -3.0, 11))
        if regularization == "tassa":  # every iteration ends in decreaseRegularization (see there):
            # a step is never shorter than min(alphas) = 1e-3, so it is always > th_stepDec, never <= th_stepInc
            self.th_stepDec, self.th_stepInc, self.reg_max = 1e-300, 1e-300, 1e10
        if stopping == "tassa":
            self.th_stop = 0.5  # stoppingCriteria returns 0 (stop) or inf
        self._dlam = 1.0
        self._accepted = False

    def solve(self, init_xs=None, init_us=None, maxiter: int = 500, is_feasible: bool = True, init_reg=None) -> bool:
        """Solve from a rollout ``(init_xs, init_us)`` (Tassa's regularisation starts at ``λ = 1``)."""
        self._dlam = 1.0
        if self.regularization == "tassa" and init_reg is None:
            init_reg = 1.0
        return super().solve(init_xs, init_us, maxiter, is_feasible, init_reg)

    def expectedImprovement(self) -> np.ndarray:
        """Expected improvement; also marks the start of a line search."""
        self._accepted = False
        return super().expectedImprovement()

    def _accept(self, alpha: float) -> bool:
        return self.dV > 0.0 if self.line_search == "tassa" else super()._accept(alpha)

    def _accept_trial(self, alpha: float) -> None:
        super()._accept_trial(alpha)
        self._accepted = True

    def increaseRegularization(self) -> None:
        """Tassa: ``dλ ← max(1.6 dλ, 1.6)``, ``λ ← max(λ dλ, 1e-6)``; Crocoddyl: ×10."""
        if self.regularization == "crocoddyl":
            super().increaseRegularization()
            return
        self._dlam = max(self._dlam * 1.6, 1.6)
        self.preg = self.dreg = max(self.preg * self._dlam, 1e-6)

    def decreaseRegularization(self) -> None:
        """Tassa (called after every line search): decrease after an accepted step, else increase."""
        if self.regularization == "crocoddyl":
            super().decreaseRegularization()
            return
        if not self._accepted:
            self.increaseRegularization()
            return
        self._dlam = min(self._dlam / 1.6, 1.0 / 1.6)
        lam = self.preg * self._dlam
        self.preg = self.dreg = lam if lam >= 1e-6 else 0.0

    def stoppingCriteria(self) -> float:
        """Crocoddyl: the predicted reduction; Tassa: 0 after an accepted reduction below ``tol_fun``
        or a relative feed-forward below 1e-4 with ``λ < 1e-5``, else inf."""
        if self.stopping == "crocoddyl":
            return super().stoppingCriteria()
        ratio = np.mean([np.max(np.abs(k) / (np.abs(u) + 1.0)) for k, u in zip(self.k, self.us) if k.size])
        small_step = ratio < 1e-4 and self.preg < 1e-5
        self.stop = 0.0 if (self._accepted and self.dV < self.tol_fun) or small_step else np.inf
        return self.stop
