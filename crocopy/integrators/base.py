"""Common part of the integrated action models (a differential model + a time step).

The integrated model's state is the differential model's; its control limits are copied from
the differential model at construction.  Terminal nodes (``u`` omitted) keep ``xnext = x`` and
the differential model's terminal cost, not scaled by ``dt``.
"""

from __future__ import annotations

import numpy as np

from ..action_base import ActionDataAbstract, ActionModelAbstract
from ..diff_action_base import DifferentialActionModelAbstract
from ..state import StateVector


class IntegratedActionModelAbstract(ActionModelAbstract):
    """Base of Euler and Runge-Kutta integrated models.

    Parameters
    ----------
    diffModel : DifferentialActionModelAbstract
        Continuous-time model.
    timeStep : float
        Integration step ``dt`` (>= 0).
    withCostResidual : bool
        Expose the differential model's residual as the node's residual ``r``.
    """

    def __init__(
        self, diffModel: DifferentialActionModelAbstract, timeStep: float = 1e-3, withCostResidual: bool = True
    ) -> None:
        if not isinstance(diffModel, DifferentialActionModelAbstract):
            raise ValueError(f"diffModel must be a DifferentialActionModelAbstract, got {type(diffModel).__name__}")
        super().__init__(
            diffModel.state, diffModel.nu, diffModel.nr if withCostResidual else 0,
            diffModel.ng, diffModel.nh, diffModel.ng_T, diffModel.nh_T,
        )
        self.differential = diffModel
        self.dt = timeStep
        self.withCostResidual = bool(withCostResidual)
        self.g_lb, self.g_ub = diffModel.g_lb, diffModel.g_ub
        if diffModel.nu:
            self._set_control_limits(diffModel.u_lb.copy(), diffModel.u_ub.copy())
        self._euclidean = type(diffModel.state) is StateVector

    @property
    def dt(self) -> float:
        """Integration step."""
        return self._dt

    @dt.setter
    def dt(self, value: float) -> None:
        if not np.isfinite(value) or value < 0:
            raise ValueError(f"timeStep must be a non-negative number, got {value}")
        self._dt = float(value)

    def quasiStatic(self, data: ActionDataAbstract, x: np.ndarray, maxiter: int = 100, tol: float = 1e-9) -> np.ndarray:
        """Delegates to the differential model (zero acceleration at ``x``)."""
        return self.differential.quasiStatic(self._differential_data(data), x, maxiter, tol)

    def _differential_data(self, data: ActionDataAbstract):
        return data.differential

    @staticmethod
    def _copy_constraints(data: ActionDataAbstract, ddata, diff: bool) -> None:
        if data.g.size:
            data.g[:] = ddata.g
        if data.h.size:
            data.h[:] = ddata.h
        if diff:
            if data.g.size:
                data.Gx[:] = ddata.Gx
                data.Gu[:] = ddata.Gu
            if data.h.size:
                data.Hx[:] = ddata.Hx
                data.Hu[:] = ddata.Hu

    def _terminal_calc(self, data: ActionDataAbstract, ddata, x: np.ndarray) -> None:
        self.differential.calc(ddata, x)
        data.xnext[:] = x
        data.cost = ddata.cost
        if self.withCostResidual:
            data.r[:] = ddata.r
        self._copy_constraints(data, ddata, diff=False)

    def _terminal_calcDiff(self, data: ActionDataAbstract, ddata, x: np.ndarray) -> None:
        self.differential.calcDiff(ddata, x)
        if self._euclidean:
            data.Fx[:] = np.eye(self.state.ndx)
        else:
            data.Fx[:] = self.state.Jintegrate(x, np.zeros(self.state.ndx))[0]
        data.Lx[:] = ddata.Lx
        data.Lxx[:] = ddata.Lxx
        self._copy_constraints(data, ddata, diff=True)
