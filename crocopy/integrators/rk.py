"""Explicit Runge-Kutta integration (orders 2, 3, 4) of a differential action model.

Stage ``i`` evaluates the differential model at ``yᵢ = x ⊕ (cᵢ dt kᵢ₋₁)`` (``y₀ = x``) and at the
control input ``wᵢ = w(cᵢ, u)`` of the control parametrization (``wᵢ = u`` by default), and forms
the tangent rate ``kᵢ = (vᵢ, aᵢ)``; then ``xnext = x ⊕ dt Σ bᵢ kᵢ`` and ``cost = dt Σ bᵢ lᵢ``.
Tableaux (each stage uses only the previous one): RK2 midpoint ``c = (0, ½)``, ``b = (0, 1)``;
RK3 Heun ``c = (0, ⅓, ⅔)``, ``b = (¼, 0, ¾)``; RK4 classic ``c = (0, ½, ½, 1)``,
``b = (⅙, ⅓, ⅓, ⅙)``.  Derivatives propagate ``∂yᵢ/∂(x, u)`` stage by stage; cost Hessians are
Gauss-Newton (the curvature of ``yᵢ`` itself is dropped).  Each stage's derivatives with respect
to ``wᵢ`` are mapped to ``u`` through ``∂wᵢ/∂u`` (:mod:`~crocopy.integrators.base`); the node's
residual and constraints are the first stage's.
"""

from __future__ import annotations

import numpy as np

from ..diff_action_base import DifferentialActionModelAbstract
from ..enums import Jcomponent, RKType
from .base import ControlChainData, IntegratedActionDataAbstract, IntegratedActionModelAbstract, bind_arguments
from .control_poly import ControlParametrizationModelPolyOne, ControlParametrizationModelPolyTwoRK

_TABLEAUX = {
    RKType.two: ((0.0, 0.5), (0.0, 1.0)),
    RKType.three: ((0.0, 1.0 / 3.0, 2.0 / 3.0), (0.25, 0.0, 0.75)),
    RKType.four: ((0.0, 0.5, 0.5, 1.0), (1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0)),
}


class IntegratedActionModelRK(IntegratedActionModelAbstract):
    """Crocoddyl's ``IntegratedActionModelRK(diffModel, [control,] rktype, timeStep=1e-3, withCostResidual=True)``."""

    def __init__(self, diffModel: DifferentialActionModelAbstract, *args: object, **kwargs: object) -> None:
        bound = bind_arguments(
            type(self).__name__, args, kwargs, ("control", "rktype", "timeStep", "withCostResidual")
        )
        rktype = bound["rktype"]
        try:
            rktype = RKType(rktype)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"rktype must be RKType.two, three or four, got {rktype!r}") from exc
        self._init_integrated(diffModel, bound["control"], bound["timeStep"], bound["withCostResidual"])
        self.rk_type = rktype
        self.rk_c, self.rk_b = _TABLEAUX[rktype]
        self.ni = len(self.rk_c)

    def _differential_data(self, data: "IntegratedActionDataRK"):
        """The first stage's data: the differential model evaluated at the node's own state."""
        return data.differential[0]

    def _control_data(self, data: "IntegratedActionDataRK"):
        return data.control[0]

    def _compiled_node(self, data: "IntegratedActionDataRK", terminal: bool, memo: dict) -> object | None:
        """This node's compiled evaluator for a solve (:mod:`crocopy.solvers.compiled_nodes`), offered by the
        differential model (``_compiled_staged_node``) when it has one (:meth:`_offer_compiled`), with crocopy's
        polynomial control parametrizations."""
        return self._offer_compiled(IntegratedActionModelRK, "_compiled_staged_node", data, terminal, memo,
                                    (ControlParametrizationModelPolyOne, ControlParametrizationModelPolyTwoRK))

    def createData(self) -> "IntegratedActionDataRK":
        return IntegratedActionDataRK(self)

    def calc(self, data: "IntegratedActionDataRK", x: np.ndarray, u: np.ndarray | None = None) -> None:
        if data.compiled_stamp is not None:
            data.compiled_stamp[0] = 0.0
        if u is None:
            self._terminal_calc(data, self._differential_data(data), x)
            return
        nv, dt, state = self.state.nv, self._dt, self.state
        cost = 0.0
        dx = data.dx
        dx[:] = 0.0
        for i, (c, b) in enumerate(zip(self.rk_c, self.rk_b)):
            y = data.y[i]
            if i == 0:
                y[:] = x
            else:
                np.multiply(data.ki[i - 1], c * dt, out=data.dyi[i])
                state._integrate_into(x, data.dyi[i], y)
            dd = data.differential[i]
            self.differential._raw_calc(dd, y, self._control_input(data.control[i], c, u))
            data.ki[i][:nv] = y[-nv:]
            data.ki[i][nv:] = dd.xout
            if b:
                dx += (b * dt) * data.ki[i]
                cost += b * dd.cost
        state._integrate_into(x, dx, data.xnext)
        data.cost = dt * cost
        d0 = data.differential[0]
        if self.withCostResidual:
            data.r[:] = d0.r
        self._copy_constraints(data, d0, diff=False)

    def calcDiff(self, data: "IntegratedActionDataRK", x: np.ndarray, u: np.ndarray | None = None) -> None:
        if data.compiled_stamp is not None:
            data.compiled_stamp[0] = 0.0
        if u is None:
            self._terminal_calcDiff(data, self._differential_data(data), x)
            return
        nv, dt, state = self.state.nv, self._dt, self.state
        ndx = state.ndx
        dkdx_sum, dkdu_sum = data.dkdx_sum, data.dkdu_sum
        for i, (c, b) in enumerate(zip(self.rk_c, self.rk_b)):
            dydx, dydu = data.dydx[i], data.dydu[i]
            dd, cd = data.differential[i], data.control[i]
            dkdx, dkdu = data.dkdx[i], data.dkdu[i]
            if i == 0:
                self._first_stage_derivatives(data, dd, cd, x, u, b * dt)
                continue
            Jx, Jdy = state._raw_Jintegrate(x, data.dyi[i], Jcomponent.both)
            dydx[:] = Jx + (c * dt) * (Jdy @ data.dkdx[i - 1])
            dydu[:] = (c * dt) * (Jdy @ data.dkdu[i - 1])
            self.differential._raw_calcDiff(dd, data.y[i], self._control_input(cd, c, u))
            Fu, Lu, Lxu, Luu = self._control_derivatives(cd, dd, c, u, data.control_chain)
            dkdx[:nv] = dydx[nv:]
            dkdu[:nv] = dydu[nv:]
            np.dot(dd.Fx, dydx, out=dkdx[nv:])
            np.dot(dd.Fx, dydu, out=dkdu[nv:])
            dkdu[nv:] += Fu
            if b:
                w = b * dt
                dkdx_sum += w * dkdx
                dkdu_sum += w * dkdu
                LxxJ = dd.Lxx @ dydu
                data.Lx += w * (dydx.T @ dd.Lx)
                data.Lu += w * (dydu.T @ dd.Lx + Lu)
                data.Lxx += w * (dydx.T @ dd.Lxx @ dydx)
                data.Lxu += w * (dydx.T @ (LxxJ + Lxu))
                dLxu = dydu.T @ Lxu
                data.Luu += w * (dydu.T @ LxxJ + dLxu + dLxu.T + Luu)
        if self._euclidean:
            data.Fx[:] = np.eye(ndx) + dkdx_sum
            data.Fu[:] = dkdu_sum
        else:
            Jx, Jdx = state._raw_Jintegrate(x, data.dx, Jcomponent.both)
            data.Fx[:] = Jx + Jdx @ dkdx_sum
            data.Fu[:] = Jdx @ dkdu_sum
        self._copy_constraints(data, data.differential[0], diff=True, cdata=data.control[0])

    def _first_stage_derivatives(self, data: "IntegratedActionDataRK", dd, cd, x: np.ndarray, u: np.ndarray,
                                 w: float) -> None:
        """Stage 0 (``y₀ = x``: ``∂y₀/∂x = I``, ``∂y₀/∂u = 0``): its ``k₀`` Jacobians, and the sums
        started from its weighted terms (``w = b₀ dt``), without the products by ``I`` and ``0``."""
        nv = self.state.nv
        dydx, dydu, dkdx, dkdu = data.dydx[0], data.dydu[0], data.dkdx[0], data.dkdu[0]
        dydx[:] = 0.0
        dydx.reshape(-1)[:: dydx.shape[0] + 1] = 1.0
        dydu[:] = 0.0
        self.differential._raw_calcDiff(dd, x, self._control_input(cd, 0.0, u))
        Fu, Lu, Lxu, Luu = self._control_derivatives(cd, dd, 0.0, u, data.control_chain)
        dkdx[:nv] = dydx[nv:]
        dkdu[:nv] = 0.0
        dkdx[nv:] = dd.Fx
        dkdu[nv:] = Fu
        sums = (data.dkdx_sum, data.dkdu_sum, data.Lx, data.Lu, data.Lxx, data.Lxu, data.Luu)
        if not w:
            for total in sums:
                total[:] = 0.0
            return
        for term, total in zip((dkdx, dkdu, dd.Lx, Lu, dd.Lxx, Lxu, Luu), sums):
            np.multiply(term, w, out=total)


class IntegratedActionDataRK(IntegratedActionDataAbstract):
    """Data of :class:`IntegratedActionModelRK`: one differential and one control data per stage
    (``differential``, ``control``); ``control_chain`` holds a stage's derivatives mapped to the parameters."""

    def __init__(self, model: IntegratedActionModelRK) -> None:
        super().__init__(model)
        ndx, nu, nx, ni = model.state.ndx, model.nu, model.state.nx, model.ni
        self.differential = [model.differential.createData() for _ in range(ni)]
        self.control = [model.control.createData() for _ in range(ni)]
        self.control_chain = ControlChainData(model)
        self.dx = np.zeros(ndx)
        self.y = [np.zeros(nx) for _ in range(ni)]
        self.dyi = [np.zeros(ndx) for _ in range(ni)]
        self.ki = [np.zeros(ndx) for _ in range(ni)]
        self.dydx = [np.zeros((ndx, ndx)) for _ in range(ni)]
        self.dydu = [np.zeros((ndx, nu)) for _ in range(ni)]
        self.dkdx = [np.zeros((ndx, ndx)) for _ in range(ni)]
        self.dkdu = [np.zeros((ndx, nu)) for _ in range(ni)]
        self.dkdx_sum = np.zeros((ndx, ndx))
        self.dkdu_sum = np.zeros((ndx, nu))
        self.compiled_stamp: np.ndarray | None = None
        """The stamp of a compiled evaluation of this data's node (:mod:`crocopy.models.rbd.rk_node`), or None:
        :meth:`IntegratedActionModelRK.calc` and ``calcDiff`` spend it, since they write the stages' datas."""
