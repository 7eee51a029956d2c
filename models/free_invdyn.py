"""Free inverse dynamics: the joint acceleration is the control, the torques follow from RNEA.

With ``u = a (nv,)`` the differential model is ``xout = a`` (``Fx = 0``, ``Fu = I``) and the
torques ``τ = RNEA(q, v, a) = M(q) a + b(q, v)`` must be producible by the actuation: the torques
of the rows the actuation cannot set vanish, an equality constraint named ``"tau"``
(``DifferentialActionModelFreeInvDynamics.ResidualModelActuation``, ``nv - na`` rows, running nodes
only) added to the constraint manager (the user's, or a new one).  With a full actuation there is no
such row and no constraint.

Kinematics contract with the residuals (as under forward dynamics, see
:mod:`crocopy.models.free_fwd_dynamics`): ``calc`` runs RNEA (``τ`` in ``pinocchio.Data.tau``) then
the forward kinematics at ``(q, v, a)`` (joint placements, velocities and accelerations); ``calcDiff`` runs
``computeRNEADerivatives`` (``∂τ/∂q``, ``∂τ/∂v``, ``M`` and the kinematic derivatives).  The joint
data collector holds ``a = u`` and the actuation commands of ``τ``: ``tau = c(x, τ)`` (Crocoddyl's
``actuation.commands``), ``dtau_dx = Mtau (∂τ/∂x - ∂a/∂x)``, ``dtau_du = Mtau M``, so that joint-effort
and joint-acceleration residuals read the efforts and accelerations of the inverse dynamics.  The
commands invert the actuation ``τ = a(x, w)``: differentiating ``a(x, c(x, τ)) = τ`` gives
``∂c/∂τ = Mtau`` and ``∂c/∂x = -Mtau ∂a/∂x`` (``∂a/∂x``: the actuation's ``dtau_dx`` at the commands),
exact when ``τ`` is a torque the actuation produces (always with a full actuation; on the ``"tau"``
equality otherwise).  The second term vanishes for the state-independent actuations.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from crocopy.actuation_base import ActuationModelAbstract, JointDataAbstract
from crocopy.constraints.base import ConstraintModelResidual
from crocopy.constraints.manager import ConstraintModelManager
from crocopy.costs.sum import CostModelSum
from crocopy.diff_action_base import DifferentialActionDataAbstract, DifferentialActionModelAbstract
from crocopy.not_compiled import class_reason, decline
from crocopy.validation import as_vector

from .data_collectors import DataCollectorJointActMultibody
from .residuals_frame import check_same_robot
from .residuals_invdyn import ResidualDataActuation, ResidualModelActuationFree
from .state_multibody import StateMultibody

TAU = "tau"


def check_parts(state, actuation, costs, constraints, nu: int, contacts=None) -> None:
    """Validate the constructor arguments of the inverse-dynamics models (``nu``: their control size)."""
    if not isinstance(state, StateMultibody):
        raise ValueError(f"state must be a StateMultibody, got {type(state).__name__}")
    if not isinstance(actuation, ActuationModelAbstract):
        raise ValueError(f"actuation must be an ActuationModelAbstract, got {type(actuation).__name__}")
    check_same_robot(state, actuation, "actuation")
    if not isinstance(costs, CostModelSum):
        raise ValueError(f"costs must be a CostModelSum, got {type(costs).__name__}")
    if constraints is not None and not isinstance(constraints, ConstraintModelManager):
        raise ValueError(f"constraints must be a ConstraintModelManager, got {type(constraints).__name__}")
    for name, part in (("contacts", contacts), ("costs", costs), ("constraints", constraints)):
        if part is not None and part.nu != nu:
            raise ValueError(f"{name}.nu = {part.nu}, expected {nu} (the inverse-dynamics control dimension)")


def add_constraint(constraints: ConstraintModelManager, name: str, residual, active: bool = True) -> None:
    """Add the internal equality ``residual = 0`` (running nodes only) under ``name`` (reserved)."""
    if name in constraints.constraints:
        raise ValueError(f"the constraint name {name!r} is reserved by the inverse-dynamics model")
    constraints.addConstraint(name, ConstraintModelResidual(residual.state, residual, False), active)


def joint_commands(actuation, adata, joint, x: np.ndarray, tau: np.ndarray) -> None:
    """``joint.tau`` = the actuation commands of ``tau`` (and ``adata.tau`` their torques)."""
    actuation.commands(adata, x, tau)
    joint.tau[:] = adata.u
    actuation.calc(adata, x, adata.u)


def joint_commands_diff(actuation, adata, joint, x: np.ndarray, dtau_dx: np.ndarray, dtau_du: np.ndarray) -> None:
    """``joint.dtau_dx = Mtau (dtau_dx - ∂a/∂x)`` and ``joint.dtau_du = Mtau dtau_du`` (``Mtau``: torques →
    commands, ``∂a/∂x``: the actuation's ``dtau_dx`` at the commands)."""
    actuation.calcDiff(adata, x, adata.u)
    actuation.torqueTransform(adata, x, adata.u)
    np.dot(adata.Mtau, dtau_dx - adata.dtau_dx, out=joint.dtau_dx)
    np.dot(adata.Mtau, dtau_du, out=joint.dtau_du)


class DifferentialActionModelFreeInvDynamics(DifferentialActionModelAbstract):
    """Crocoddyl's ``DifferentialActionModelFreeInvDynamics(state, actuation, costs, constraints=None)``.

    Parameters
    ----------
    state : StateMultibody
        Multibody state.
    actuation : ActuationModelAbstract
        Actuation model: which torques can be produced (``tau_set``) and the commands of the joint data.
    costs : CostModelSum
        Cost stack with ``nu = state.nv``.
    constraints : ConstraintModelManager, optional
        Constraint stack with ``nu = state.nv``; the ``"tau"`` equality is added to it (as Crocoddyl
        does), or to a new manager.

    Notes
    -----
    The control is the joint acceleration: ``nu = nv``, ``xout = u``.  Control limits are unbounded.
    """

    ResidualModelActuation = ResidualModelActuationFree

    def __init__(
        self,
        state: StateMultibody,
        actuation: ActuationModelAbstract,
        costs: CostModelSum,
        constraints: ConstraintModelManager | None = None,
    ) -> None:
        nv = getattr(state, "nv", 0)
        check_parts(state, actuation, costs, constraints, nv)
        if constraints is None:
            constraints = ConstraintModelManager(state, nv)
        if actuation.nu < nv:
            add_constraint(constraints, TAU, ResidualModelActuationFree(state, actuation.nu))
        super().__init__(state, nv, costs.nr, constraints.ng, constraints.nh, constraints.ng_T, constraints.nh_T)
        self._follow_constraints(constraints)
        self.actuation = actuation
        self.costs = costs
        self.constraints = constraints
        self.pinocchio = state.pinocchio

    def createData(self) -> "DifferentialActionDataFreeInvDynamics":
        return DifferentialActionDataFreeInvDynamics(self)

    def calc(self, data: "DifferentialActionDataFreeInvDynamics", x: np.ndarray, u: np.ndarray | None = None) -> None:
        """``xout = u``, ``τ = RNEA(q, v, u)``, joint data, costs and constraints (terminal: kinematics only)."""
        nq = self.state.nq
        q, v = x[:nq], x[nq:]
        model, pd = self.pinocchio, data.pinocchio
        if u is None:
            pin.computeForwardKinematicsDerivatives(model, pd, q, v, data.zero_a)
        else:
            data.xout[:] = u
            pin.rnea(model, pd, q, v, u)
            pin.forwardKinematics(model, pd, q, v, u)  # RNEA leaves no placements and gravity in data.a
            mb = data.multibody
            joint_commands(self.actuation, mb.actuation, mb.joint, x, pd.tau)
        self.costs.calc(data.costs, x, u)
        data.cost = data.costs.cost
        self.constraints.calc(data.constraints, x, u)

    def calcDiff(
        self, data: "DifferentialActionDataFreeInvDynamics", x: np.ndarray, u: np.ndarray | None = None
    ) -> None:
        """``Fx = 0``, ``Fu = I``; RNEA derivatives, joint-data Jacobians, cost and constraint derivatives."""
        if u is not None:
            nq, nv = self.state.nq, self.state.nv
            pd, mb = data.pinocchio, data.multibody
            pin.computeRNEADerivatives(self.pinocchio, pd, x[:nq], x[nq:], u)
            data.dtau_dx[:, :nv] = pd.dtau_dq
            data.dtau_dx[:, nv:] = pd.dtau_dv
            joint_commands_diff(self.actuation, mb.actuation, mb.joint, x, data.dtau_dx, pd.M)
        self.costs.calcDiff(data.costs, x, u)
        self.constraints.calcDiff(data.constraints, x, u)

    def _compiled_euler_node(self, iam, data, terminal: bool, memo: dict) -> object | None:
        """The compiled evaluator of the Euler node ``(iam, data)`` over this model
        (:func:`.rbd.invdyn_node.invdyn_node`), or None for a subclass or a node it cannot compile."""
        if type(self) is not DifferentialActionModelFreeInvDynamics:
            return decline(memo, class_reason(self, "differential model"))
        from .rbd.invdyn_node import invdyn_node

        return invdyn_node(iam, data, terminal, memo)

    def quasiStatic(
        self, data: "DifferentialActionDataFreeInvDynamics", x: np.ndarray, maxiter: int = 100, tol: float = 1e-9
    ) -> np.ndarray:
        """Zero acceleration (the control that keeps the robot at rest); ``maxiter``/``tol`` are unused."""
        as_vector(x, self.state.nx, "x")
        return np.zeros(self.nu)

    def __repr__(self) -> str:
        s = self.state
        return f"DifferentialActionModelFreeInvDynamics {{nx={s.nx}, ndx={s.ndx}, nu={self.nu}}}"


class DifferentialActionDataFreeInvDynamics(DifferentialActionDataAbstract):
    """Data of :class:`DifferentialActionModelFreeInvDynamics`.

    Fields besides the differential-action ones: ``pinocchio`` (the node's ``pinocchio.Data``),
    ``multibody`` (``DataCollectorJointActMultibody``), ``costs``, ``constraints`` and
    ``dtau_dx (nv, ndx)`` (``∂τ/∂x`` of the inverse dynamics).
    """

    ResidualDataActuation = ResidualDataActuation

    def __init__(self, model: DifferentialActionModelFreeInvDynamics) -> None:
        super().__init__(model)
        nv = model.state.nv
        self.pinocchio = model.pinocchio.createData()
        joint = JointDataAbstract(model.state, model.actuation, model.nu)
        joint.a = self.xout
        joint.da_du = self.Fu
        np.fill_diagonal(self.Fu, 1.0)
        self.multibody = DataCollectorJointActMultibody(self.pinocchio, model.actuation.createData(), joint)
        self.costs = model.costs.createData(self.multibody)
        for name in ("Lx", "Lu", "Lxx", "Lxu", "Luu"):  # the cost sum writes the derivatives in place
            setattr(self.costs, name, getattr(self, name))
        self.constraints = model.constraints.createData(self.multibody)
        self.constraints.shareMemory(self)
        self.dtau_dx = np.zeros((nv, model.state.ndx))
        self.zero_a = np.zeros(nv)


DifferentialActionModelFreeInvDynamics.DifferentialActionDataFreeInvDynamics = DifferentialActionDataFreeInvDynamics
