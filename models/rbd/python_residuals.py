"""A user's Python residuals inside a compiled node: the node stays compiled, those residuals run in Python.

A Crocoddyl-style residual (a Python subclass of ``ResidualModelAbstract`` with its own ``calc``/``calcDiff``
on the node's Pinocchio data) has no lowering.  On a free-dynamics node (no active contacts, whose datas such a
residual might read) the compiled node keeps the dynamics and every other cost compiled: before each compiled
evaluation, :class:`PythonResiduals` brings the node's Pinocchio data to the state, as the dynamics models do
before their costs (joint placements, and velocities when a residual depends on ``v``; for derivatives also the
joint Jacobians, and the kinematic derivatives when a residual depends on ``v``; frame placements are the
residual's to update, as in Crocoddyl) and calls those residuals, which write their rows of the cost stack; the
compiled call then takes their rows into the activations and sums.  A residual that needs more of the Pinocchio
data (dynamics, accelerations, centre of mass) computes it itself.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin


class PythonResiduals:
    """The Python residuals ``(residual, data)`` of one compiled node and its Pinocchio model and data."""

    def __init__(self, model: pin.Model, pdata: pin.Data, items: list) -> None:
        self.model = model
        self.pdata = pdata
        self.items = items
        self.nq = model.nq
        self.zero_a = np.zeros(model.nv)
        self.velocities = any(residual.v_dependent for residual, _ in items)

    def evaluate(self, x: np.ndarray, u: np.ndarray | None, derivatives: bool = False) -> None:
        """The residuals' rows (and Jacobians with ``derivatives``) at ``(x, u)``."""
        model, pdata, nq = self.model, self.pdata, self.nq
        if self.velocities:
            if derivatives:
                pin.computeForwardKinematicsDerivatives(model, pdata, x[:nq], x[nq:], self.zero_a)
            else:
                pin.forwardKinematics(model, pdata, x[:nq], x[nq:])
        elif derivatives:
            pin.computeJointJacobians(model, pdata, x[:nq])
        else:
            pin.forwardKinematics(model, pdata, x[:nq])
        for residual, rdata in self.items:
            residual._raw_calc(rdata, x, u)
            if derivatives:
                residual._raw_calcDiff(rdata, x, u)

    def jacobians(self, x: np.ndarray, u: np.ndarray | None) -> None:
        """The residuals' Jacobians at ``(x, u)``, where their rows were evaluated last (their ``calc`` is not
        called again, as a Crocoddyl ``calcDiff`` follows a ``calc`` at the same point)."""
        model, pdata, nq = self.model, self.pdata, self.nq
        if self.velocities:
            pin.computeForwardKinematicsDerivatives(model, pdata, x[:nq], x[nq:], self.zero_a)
        else:
            pin.computeJointJacobians(model, pdata, x[:nq])
        for residual, rdata in self.items:
            residual._raw_calcDiff(rdata, x, u)
