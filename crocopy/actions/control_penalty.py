"""Penalty baseline for control limits: a quadratic barrier on the controls of any action model.

:class:`ActionModelControlPenalty` wraps a model and adds, for bounds ``lb <= u <= ub`` (shape
``(nu,)``)::

    cost += 1/2 weight ||r(u)||^2,   r(u) = min(u - lb, 0) + max(u - ub, 0),

the same quadratic barrier as Crocoddyl's ``ActivationModelQuadraticBarrier`` on a control
residual (zero inside the box, quadratic outside).  Derivatives: ``Lu += weight r``, ``Luu +=
weight diag(r != 0)``.  Plain DDP/FDDP then solve the penalised problem; the limits hold only
approximately (violations shrink as ``weight`` grows), which is the point of the comparison with
Box-DDP/Box-FDDP (the Box-FDDP paper handles state bounds this way and reports that it converges
better than log barriers).
"""

from __future__ import annotations

import numpy as np

from ..action_base import ActionDataAbstract, ActionModelAbstract
from ..validation import as_bound, as_number, check_bounds

__all__ = ["ActionDataControlPenalty", "ActionModelControlPenalty"]


class ActionModelControlPenalty(ActionModelAbstract):
    """Action model with a quadratic-barrier penalty on its controls.

    Parameters
    ----------
    model : ActionModelAbstract
        Inner model.
    weight : float
        Penalty weight (default 1e3).
    lb, ub : array_like, optional
        Bounds, shape ``(nu,)``; default ``model.u_lb``/``model.u_ub``.  The wrapper itself has no
        control limits, so a box solver treats it as unconstrained.
    """

    def __init__(
        self,
        model: ActionModelAbstract,
        weight: float = 1e3,
        lb: np.ndarray | None = None,
        ub: np.ndarray | None = None,
    ) -> None:
        if not isinstance(model, ActionModelAbstract):
            raise ValueError(f"model must be an ActionModelAbstract, got {type(model).__name__}")
        super().__init__(model.state, model.nu, model.nr, model.ng, model.nh, model.ng_T, model.nh_T)
        self._follow_constraints(model)
        self.model = model
        self.weight = as_number(weight, "weight", 0.0)
        self.lb = as_bound(model.u_lb if lb is None else lb, model.nu, "lb", upper=False)
        self.ub = as_bound(model.u_ub if ub is None else ub, model.nu, "ub", upper=True)
        check_bounds(self.lb, self.ub, "lb", "ub")

    def createData(self) -> "ActionDataControlPenalty":
        """Allocate the wrapper data (the inner model's data is ``data.inner``)."""
        return ActionDataControlPenalty(self)

    def _violation(self, data: "ActionDataControlPenalty", u: np.ndarray) -> np.ndarray:
        r = data.violation
        np.minimum(u - self.lb, 0.0, out=r)
        r += np.maximum(u - self.ub, 0.0)
        return r

    def calc(self, data: "ActionDataControlPenalty", x: np.ndarray, u: np.ndarray | None = None) -> None:
        """Inner ``calc`` plus the barrier cost."""
        inner = data.inner
        if u is None:
            self.model.calc(inner, x)
            data.cost = inner.cost
        else:
            self.model.calc(inner, x, u)
            r = self._violation(data, u)
            data.cost = inner.cost + 0.5 * self.weight * float(r @ r)
        data.xnext[:] = inner.xnext
        data.r[:] = inner.r
        data.g[:] = inner.g
        data.h[:] = inner.h

    def calcDiff(self, data: "ActionDataControlPenalty", x: np.ndarray, u: np.ndarray | None = None) -> None:
        """Inner ``calcDiff`` plus the barrier's gradient and (Gauss-Newton exact) Hessian."""
        inner = data.inner
        self.model.calcDiff(inner, x, u)
        for name in ("Fx", "Lx", "Lxx", "Gx", "Hx"):
            getattr(data, name)[:] = getattr(inner, name)
        if u is None:
            return
        for name in ("Fu", "Lu", "Lxu", "Luu", "Gu", "Hu"):
            getattr(data, name)[:] = getattr(inner, name)
        r = self._violation(data, u)
        data.Lu += self.weight * r
        data.Luu.flat[:: self.nu + 1] += self.weight * (r != 0.0)

    def __repr__(self) -> str:
        return f"ActionModelControlPenalty({self.model!r}, weight={self.weight:g})"


class ActionDataControlPenalty(ActionDataAbstract):
    """Data of :class:`ActionModelControlPenalty`: inner data and the bound violation ``r(u)``."""

    def __init__(self, model: ActionModelControlPenalty) -> None:
        super().__init__(model)
        self.inner = model.model.createData()
        self.violation = np.zeros(model.nu)
