"""A reach whose goal is a user's own residual: the built-in ``ResidualModelFrameTranslation``, the same residual
written as numba functions (:class:`NumbaFrameTranslation`, a ``ResidualModelNumba``: compiled nodes stay
compiled) and as a Crocoddyl-style Python subclass (:func:`python_frame_translation`: only that residual runs in
Python).  ``r = p_f(q) - p_ref``, ``Rx = [J_f[:3] (LOCAL_WORLD_ALIGNED), 0]``.
"""

from __future__ import annotations

from types import ModuleType

import numpy as np
import pinocchio as pin

from crocopy.models.residual_numba import ResidualModelNumba

from .arm import build_arm_reaching

VARIANTS = ("builtin", "numba", "python")
"""How :func:`build_user_reach` writes the goal residual."""


class NumbaFrameTranslation(ResidualModelNumba):
    """``r = p_f - p_ref`` as two numba functions (``p_ref`` is :meth:`parameters`)."""

    def __init__(self, state, frame, reference, nu=None) -> None:
        super().__init__(state, 3, nu, frame=frame, kinematics=("placement", "jacobian"), v_dependent=False)
        self.reference = np.array(reference, dtype=float)

    def parameters(self) -> np.ndarray:
        return self.reference

    @staticmethod
    def compute_residual(r, x, u, p, kin):
        for i in range(3):
            r[i] = kin.p[i] - p[i]

    @staticmethod
    def compute_jacobians(Rx, Ru, x, u, p, kin):
        for i in range(3):
            for j in range(kin.J.shape[1]):
                Rx[i, j] = kin.J[i, j]


def python_frame_translation(lib: ModuleType) -> type:
    """``r = p_f - p_ref`` as a Crocoddyl-style Python subclass of ``lib.ResidualModelAbstract`` (``lib``:
    ``crocopy`` or ``crocoddyl``), reading the node's Pinocchio data."""

    class PythonFrameTranslation(lib.ResidualModelAbstract):
        def __init__(self, state, frame, reference, nu) -> None:
            lib.ResidualModelAbstract.__init__(self, state, 3, nu, True, False, False)
            self.frame = frame
            self.reference = np.array(reference, dtype=float)

        def calc(self, data, x, u=None) -> None:
            oMf = pin.updateFramePlacement(self.state.pinocchio, data.shared.pinocchio, self.frame)
            data.r[:] = oMf.translation - self.reference

        def calcDiff(self, data, x, u=None) -> None:
            J = pin.getFrameJacobian(self.state.pinocchio, data.shared.pinocchio, self.frame, pin.LOCAL_WORLD_ALIGNED)
            data.Rx[:, : self.state.nv] = J[:3]

        def createData(self, collector):
            return lib.ResidualDataAbstract(self, collector)

    return PythonFrameTranslation


def build_user_reach(lib: ModuleType, variant: str = "numba", robot: str = "talos_arm",
                     target=(0.4, 0.0, 0.4), nodes: int = 100) -> tuple[object, list, list]:
    """The arm reach of :func:`~.arm.build_arm_reaching` (Talos' arm by default, ``T = nodes``) with its goal
    residual written as ``variant`` (:data:`VARIANTS`; ``"numba"`` needs ``lib`` to be crocopy)."""
    if variant not in VARIANTS:
        raise KeyError(f"variant must be one of {VARIANTS}, got {variant!r}")
    problem, xs, us = build_arm_reaching(lib, robot=robot, target=target, nodes=nodes)
    if variant == "builtin":
        return problem, xs, us
    cls = NumbaFrameTranslation if variant == "numba" else python_frame_translation(lib)
    for model in [*problem.runningModels, problem.terminalModel]:
        dam = model.differential
        item = dam.costs.costs["goal"]
        residual = item.cost.residual
        weight = item.weight
        dam.costs.removeCost("goal")
        goal = cls(dam.state, residual.id, np.array(residual.reference), dam.nu)
        dam.costs.addCost("goal", lib.CostModelResidual(dam.state, goal), weight)
    return lib.ShootingProblem(problem.x0, problem.runningModels, problem.terminalModel), xs, us
