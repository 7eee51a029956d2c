"""Kinematic unicycle: state ``(x, y, θ)``, control ``(v, ω)``, step ``dt``.

``xnext = (x + v cosθ dt, y + v sinθ dt, θ + ω dt)``; residual ``r = (w₀ x, w₀ y, w₀ θ, w₁ v, w₁ ω)``,
cost ``½‖r‖²``.  The terminal node keeps the state part only.
"""

from __future__ import annotations

import numpy as np

from ..action_base import ActionDataAbstract, ActionModelAbstract
from ..state import StateVector
from ..validation import as_number, as_vector


class ActionModelUnicycle(ActionModelAbstract):
    """Crocoddyl's ``ActionModelUnicycle`` (``costWeights = [10, 1]``, ``dt = 0.1``)."""

    def __init__(self) -> None:
        super().__init__(StateVector(3), 2, 5)
        self.costWeights = np.array([10.0, 1.0])
        self.dt = 0.1

    @property
    def dt(self) -> float:
        """Time step (>= 0, finite), checked on assignment."""
        return self._dt

    @dt.setter
    def dt(self, value: float) -> None:
        self._dt = as_number(value, "dt", 0.0)

    @property
    def costWeights(self) -> np.ndarray:
        """Weights ``(w_state, w_control)``, shape ``(2,)``, finite; checked on assignment."""
        return self._cost_weights

    @costWeights.setter
    def costWeights(self, value: np.ndarray) -> None:
        self._cost_weights = as_vector(value, 2, "costWeights").copy()

    def createData(self) -> "ActionDataUnicycle":
        return ActionDataUnicycle(self)

    def calc(self, data: ActionDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        w = self.costWeights
        data.r[:3] = w[0] * x
        if u is None:
            data.xnext[:] = x
            data.r[3:] = 0.0
        else:
            c, s = np.cos(x[2]), np.sin(x[2])
            data.xnext[0] = x[0] + c * u[0] * self.dt
            data.xnext[1] = x[1] + s * u[0] * self.dt
            data.xnext[2] = x[2] + u[1] * self.dt
            data.r[3:] = w[1] * u
        data.cost = 0.5 * float(data.r @ data.r)

    def calcDiff(self, data: ActionDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        w0, w1 = self.costWeights
        data.Lx[:] = w0 * w0 * x
        data.Lxx[:] = np.diag(np.full(3, w0 * w0))
        if u is None:
            return
        c, s = np.cos(x[2]), np.sin(x[2])
        data.Lu[:] = w1 * w1 * u
        data.Luu[:] = np.diag(np.full(2, w1 * w1))
        data.Fx[:] = np.eye(3)
        data.Fx[0, 2] = -s * u[0] * self.dt
        data.Fx[1, 2] = c * u[0] * self.dt
        data.Fu[:] = 0.0
        data.Fu[0, 0] = c * self.dt
        data.Fu[1, 0] = s * self.dt
        data.Fu[2, 1] = self.dt


class ActionDataUnicycle(ActionDataAbstract):
    """Data of :class:`ActionModelUnicycle` (the fields of :class:`~crocopy.action_base.ActionDataAbstract`)."""
