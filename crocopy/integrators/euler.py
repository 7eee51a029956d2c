"""Symplectic Euler integration of a differential action model.

With ``x = (q, v)``, the control input ``w = w(0, u)`` of the control parametrization at the start of
the step (``w = u`` by default) and ``a = a(x, w)``: ``dx = ((v + a dt) dt, a dt)``, ``xnext = x ⊕ dx``,
``cost = dt l(x, w)``; the derivatives below are with respect to ``w``, mapped to ``u`` as in
:mod:`~crocopy.integrators.base`.  Derivatives by the chain rule through the state's ``Jintegrate``::

    ∂dx/∂x = [[dt² Fx + dt [0 I]], [dt Fx]],   ∂dx/∂u = [[dt² Fu], [dt Fu]]
    Fx = J_x + J_dx ∂dx/∂x,                  Fu = J_dx ∂dx/∂u

States that implement ``JintegrateTransport`` apply ``J_dx`` by transporting the rows of ``∂dx/∂x``
and ``∂dx/∂u`` in place (no dense ``(ndx, ndx)`` product).
"""

from __future__ import annotations

import numpy as np

from .. import kernels
from ..enums import Jcomponent
from ..kernels import log_fallback
from ..state import StateAbstract
from . import euler_kernel as integrator_kernel
from .base import ControlChainData, IntegratedActionDataAbstract, IntegratedActionModelAbstract
from .control_poly import ControlParametrizationModelPolyOne, ControlParametrizationModelPolyTwoRK


class IntegratedActionModelEuler(IntegratedActionModelAbstract):
    """Crocoddyl's ``IntegratedActionModelEuler(diffModel, [control,] timeStep=1e-3, withCostResidual=True)``.

    While :func:`crocopy.kernels_enabled` the step and the chain rule run
    :mod:`~crocopy.integrators.euler_kernel`'s compiled functions, else their numpy twins.  A
    Lie-group state without ``JintegrateTransport`` gets the dense ``Jintegrate`` product instead of
    the compiled chain rule (logged once per state class at DEBUG level on the ``"crocopy"`` logger).
    """

    def __init__(self, diffModel, *args: object, **kwargs: object) -> None:
        super().__init__(diffModel, *args, **kwargs)
        self._transport = not self._euclidean and (
            type(self.state).JintegrateTransport is not StateAbstract.JintegrateTransport
        )
        if not (self._euclidean or self._transport):
            kernel = "the compiled Euler chain rule"
            log_fallback(type(self.state), ["JintegrateTransport"], kernel, how="does not implement")

    def _compiled_node(self, data: "IntegratedActionDataEuler", terminal: bool, memo: dict) -> object | None:
        """This node's compiled evaluator for a solve (:mod:`crocopy.solvers.compiled_nodes`), offered by the
        differential model when it has one (:meth:`_offer_compiled`): ``_compiled_euler_node``, or with crocopy's
        other polynomial control parametrizations ``_compiled_staged_node``."""
        hook = "_compiled_euler_node" if self._identity_control else "_compiled_staged_node"
        return self._offer_compiled(IntegratedActionModelEuler, hook, data, terminal, memo,
                                    (ControlParametrizationModelPolyOne, ControlParametrizationModelPolyTwoRK))

    def createData(self) -> "IntegratedActionDataEuler":
        return IntegratedActionDataEuler(self)

    def calc(self, data: "IntegratedActionDataEuler", x: np.ndarray, u: np.ndarray | None = None) -> None:
        ddata = data.differential
        if data.compiled_stamp is not None:
            data.compiled_stamp[0] = 0.0
        if u is None:
            self._terminal_calc(data, ddata, x)
            return
        w = u if self._identity_control else self._control_input(data.control, 0.0, u)
        self.differential._raw_calc(ddata, x, w)
        dt = self._dt
        dx = data.dx
        if kernels.active:
            integrator_kernel.euler_step(ddata.xout, x, dt, dx)
        else:
            integrator_kernel.euler_step_numpy(ddata.xout, x, dt, dx)
        self.state._integrate_into(x, dx, data.xnext)
        data.cost = dt * ddata.cost
        if self.withCostResidual:
            data.r[:] = ddata.r
        if data.g.size or data.h.size:
            self._copy_constraints(data, ddata, diff=False)

    def calcDiff(self, data: "IntegratedActionDataEuler", x: np.ndarray, u: np.ndarray | None = None) -> None:
        ddata = data.differential
        if u is None:
            self._terminal_calcDiff(data, ddata, x)
            return
        cdata = data.control
        if self._identity_control:
            self.differential._raw_calcDiff(ddata, x, u)
            Fu, Lu, Lxu, Luu = ddata.Fu, ddata.Lu, ddata.Lxu, ddata.Luu
        else:
            self.differential._raw_calcDiff(ddata, x, self._control_input(cdata, 0.0, u))
            Fu, Lu, Lxu, Luu = self._control_derivatives(cdata, ddata, 0.0, u, data.control_chain)
        euclidean = self._euclidean
        if euclidean or self._transport:
            chain = integrator_kernel.euler_chain if kernels.active else integrator_kernel.euler_chain_numpy
            chain(
                ddata.Fx, Fu, ddata.Lx, Lu, ddata.Lxx, Lxu, Luu, self._dt, euclidean,
                data.Fx, data.Fu, data.Lx, data.Lu, data.Lxx, data.Lxu, data.Luu,
            )
            if not euclidean:
                self.state._integrate_chain_rule(x, data.dx, data.Fx, data.Fu)
            if data.g.size or data.h.size:
                self._copy_constraints(data, ddata, diff=True, cdata=cdata)
            return
        nv, dt = self.state.nv, self._dt
        dxdx, dxdu = data.ddx_dx, data.ddx_du
        np.multiply(ddata.Fx, dt, out=dxdx[nv:])
        np.multiply(dxdx[nv:], dt, out=dxdx[:nv])
        dxdx.reshape(-1)[data.qv_diagonal] += dt
        np.multiply(Fu, dt, out=dxdu[nv:])
        np.multiply(dxdu[nv:], dt, out=dxdu[:nv])
        Jx, Jdx = self.state._raw_Jintegrate(x, data.dx, Jcomponent.both)
        np.dot(Jdx, dxdx, out=data.Fx)
        data.Fx += Jx
        np.dot(Jdx, dxdu, out=data.Fu)
        np.multiply(ddata.Lx, dt, out=data.Lx)
        np.multiply(Lu, dt, out=data.Lu)
        np.multiply(ddata.Lxx, dt, out=data.Lxx)
        np.multiply(Lxu, dt, out=data.Lxu)
        np.multiply(Luu, dt, out=data.Luu)
        self._copy_constraints(data, ddata, diff=True, cdata=cdata)


class IntegratedActionDataEuler(IntegratedActionDataAbstract):
    """Data of :class:`IntegratedActionModelEuler`: ``differential`` and ``control`` data, ``dx`` and the
    chain-rule blocks (``control_chain``: the differential derivatives mapped to the parameters)."""

    def __init__(self, model: IntegratedActionModelEuler) -> None:
        super().__init__(model)
        ndx, nv, nu = model.state.ndx, model.state.nv, model.nu
        self.differential = model.differential.createData()
        self.control = model.control.createData()
        self.control_chain = ControlChainData(model)
        self.dx = np.zeros(ndx)
        self.ddx_dx = np.zeros((ndx, ndx))
        self.ddx_du = np.zeros((ndx, nu))
        self.qv_diagonal = slice(ndx - nv, (ndx - nv) + nv * (ndx + 1), ndx + 1)
        self.compiled_stamp: np.ndarray | None = None
        """The stamp of a compiled evaluation of this data's node (``stamp[0] = 1`` while the node's own arrays hold
        its last values, :mod:`crocopy.solvers.compiled_nodes`), or None: :meth:`IntegratedActionModelEuler.calc`
        spends it, since it writes the data at another point."""

