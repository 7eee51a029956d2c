"""Free forward dynamics ``a = M(q)⁻¹ (τ(x, u) - b(q, v))`` of a multibody system (no contacts).

Without armature the acceleration comes from Pinocchio's ABA (LOCAL convention, followed by
``updateGlobalPlacements`` so that the joint placements are available to the residuals) and its derivatives from
``computeABADerivatives``:

    Fx = (∂ABA/∂q, ∂ABA/∂v) + M⁻¹ ∂τ/∂x,   Fu = M⁻¹ ∂τ/∂u.

With an armature ``ε`` (shape ``(nv,)``) the mass matrix is ``M + diag(ε)``; the acceleration is a
Cholesky solve and ``Fx = M⁻¹ (∂τ/∂x - ∂RNEA/∂x)`` from ``computeRNEADerivatives`` at that
acceleration.

Kinematics contract with the residuals: after ``calc`` the node's ``pinocchio.Data`` (shared as
``data.multibody.pinocchio``) holds the joint placements and velocities at ``x``; after
``calcDiff`` it also holds the joint Jacobians ``J`` and the kinematic quantities that
``getFrameVelocityDerivatives`` reads (terminal nodes: ``computeForwardKinematicsDerivatives`` in
``calc``).  Residuals update the frames, centre of mass or momentum they need from those.
Pinocchio's Python bindings return ``M`` and ``Minv`` fully symmetric.  The joint data collector
(``data.multibody.joint``) exposes ``tau = u``, ``a = xout`` and their derivatives for the
joint-effort/acceleration residuals.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from scipy.linalg import cho_factor, cho_solve

from crocopy.actuation_base import ActuationModelAbstract, JointDataAbstract
from crocopy.costs.sum import CostModelSum
from crocopy.diff_action_base import DifferentialActionDataAbstract, DifferentialActionModelAbstract
from crocopy.not_compiled import class_reason, decline
from crocopy.stored import Stored
from crocopy.validation import as_vector

from .data_collectors import DataCollectorJointActMultibody
from .dynamics_options import ActuationStructure, ArmatureMixin
from .rbd.euler_node import euler_node
from .rbd.rk_node import staged_node
from .residuals_frame import check_same_robot
from .state_multibody import StateMultibody


class DifferentialActionModelFreeFwdDynamics(ArmatureMixin, DifferentialActionModelAbstract):
    """Crocoddyl's ``DifferentialActionModelFreeFwdDynamics(state, actuation, costs, constraints=None)``.

    Parameters
    ----------
    state : StateMultibody
        Multibody state.
    actuation : ActuationModelAbstract
        Actuation model (its ``nu`` is the control dimension).
    costs : CostModelSum
        Cost stack (``costs.nu`` must equal ``actuation.nu``).
    constraints : ConstraintModelManager, optional
        Constraint stack filling ``g``/``h`` and their Jacobians.

    Notes
    -----
    ``u_lb``/``u_ub`` default to the actuation's bounds (the URDF effort limits of the actuated
    joints); ``has_control_limits`` stays False until they are assigned, as in Crocoddyl.
    """

    def __init__(
        self,
        state: StateMultibody,
        actuation: ActuationModelAbstract,
        costs: CostModelSum,
        constraints: object | None = None,
    ) -> None:
        if not isinstance(state, StateMultibody):
            raise ValueError(f"state must be a StateMultibody, got {type(state).__name__}")
        if not isinstance(actuation, ActuationModelAbstract):
            raise ValueError(f"actuation must be an ActuationModelAbstract, got {type(actuation).__name__}")
        check_same_robot(state, actuation, "actuation")
        if not isinstance(costs, CostModelSum):
            raise ValueError(f"costs must be a CostModelSum, got {type(costs).__name__}")
        if costs.nu != actuation.nu:
            raise ValueError(f"costs.nu = {costs.nu} does not match actuation.nu = {actuation.nu}")
        if constraints is not None and constraints.nu != actuation.nu:
            raise ValueError(f"constraints.nu = {constraints.nu} does not match actuation.nu = {actuation.nu}")
        ng = nh = ng_T = nh_T = 0
        if constraints is not None:
            ng, nh, ng_T, nh_T = constraints.ng, constraints.nh, constraints.ng_T, constraints.nh_T
        super().__init__(state, actuation.nu, costs.nr, ng, nh, ng_T, nh_T)
        if constraints is not None:
            self._follow_constraints(constraints)
        self.actuation = actuation
        self.costs = costs
        self.constraints = constraints
        self.pinocchio = state.pinocchio
        self._u_lb = np.array(actuation.u_lb, dtype=float)
        self._u_ub = np.array(actuation.u_ub, dtype=float)
        self.armature = np.zeros(state.nv)
        self._act = ActuationStructure(actuation, state.nv)

    def createData(self) -> "DifferentialActionDataFreeFwdDynamics":
        return DifferentialActionDataFreeFwdDynamics(self)

    def calc(self, data: "DifferentialActionDataFreeFwdDynamics", x: np.ndarray, u: np.ndarray | None = None) -> None:
        self._dynamics_calc(data, x, u)
        self.costs._raw_calc(data.costs, x, u)
        data.cost = data.costs.cost
        if self.constraints is not None:
            self.constraints._raw_calc(data.constraints, x, u)

    def _fill_after_kernel(self, data: "DifferentialActionDataFreeFwdDynamics", x: np.ndarray, u: np.ndarray | None,
                           value: float) -> None:
        """What :meth:`calc` at ``(x, u)`` writes besides what a compiled evaluation there wrote (the cost stack's
        arrays, of value ``value``, and ``xout``): the torques, the Pinocchio data, the residuals' own data, the
        constraints and the costs' totals (:meth:`crocopy.models.rbd.euler_node.EulerNode.fill`)."""
        self._dynamics_calc(data, x, u)
        data.costs.stack.calc_residual_datas(x, u)
        data.costs.cost = data.cost = value
        if self.constraints is not None:
            self.constraints._raw_calc(data.constraints, x, u)

    def _dynamics_calc(self, data: "DifferentialActionDataFreeFwdDynamics", x: np.ndarray,
                       u: np.ndarray | None) -> None:
        """The Pinocchio and actuation part of :meth:`calc` (the torques, the acceleration ``xout`` and the Pinocchio
        data; the kinematics alone at a terminal node, ``u = None``)."""
        nq = self.state.nq
        q, v = x[:nq], x[nq:]
        model, pd = self.pinocchio, data.pinocchio
        if u is None:
            pin.computeForwardKinematicsDerivatives(model, pd, q, v, data.zero_a)
        else:
            self.actuation._raw_calc(data.multibody.actuation, x, u)
            data.multibody.joint.tau[:] = u
            tau = data.multibody.actuation.tau
            if self._with_armature:
                pin.computeAllTerms(model, pd, q, v)
                M = data.M
                M[:] = pd.M
                M[data.diag] += self._armature
                data.chol = cho_factor(M, lower=False, check_finite=False)
                np.subtract(tau, pd.nle, out=data.u_drift)
                data.xout[:] = cho_solve(data.chol, data.u_drift, check_finite=False)
            else:
                data.xout[:] = pin.aba(model, pd, q, v, tau, pin.Convention.LOCAL)
                pin.updateGlobalPlacements(model, pd)

    def calcDiff(
        self, data: "DifferentialActionDataFreeFwdDynamics", x: np.ndarray, u: np.ndarray | None = None
    ) -> None:
        if u is not None:
            nq, nv = self.state.nq, self.state.nv
            q, v = x[:nq], x[nq:]
            model, pd = self.pinocchio, data.pinocchio
            act = data.multibody.actuation
            if not self._act.constant:
                self.actuation._raw_calcDiff(act, x, u)
            if self._with_armature:
                pin.computeRNEADerivatives(model, pd, q, v, data.xout)
                data.Minv[:] = cho_solve(data.chol, data.eye, check_finite=False)
                data.dtau[:, :nv] = pd.dtau_dq
                data.dtau[:, nv:] = pd.dtau_dv
                np.subtract(act.dtau_dx, data.dtau, out=data.dtau)
                np.dot(data.Minv, data.dtau, out=data.Fx)
            else:
                ddq_dq, ddq_dv, Minv = pin.computeABADerivatives(model, pd, q, v, act.tau)  # views of pd's
                data.Minv[:] = Minv
                Fx = data.Fx
                Fx[:, :nv] = ddq_dq
                Fx[:, nv:] = ddq_dv
                if self._act.dtau_dx_nonzero:
                    Fx += Minv @ act.dtau_dx
            self._act.times_dtau_du(data.Minv, act.dtau_du, data.Fu)
        self.costs._raw_calcDiff(data.costs, x, u)
        if self.constraints is not None:
            self.constraints._raw_calcDiff(data.constraints, x, u)

    def _compiled_euler_node(self, iam, data, terminal: bool, memo: dict) -> object | None:
        """The compiled evaluator of the Euler node ``(iam, data)`` over this model
        (:func:`.rbd.euler_node.euler_node`), or None for a subclass or a node it cannot compile."""
        if type(self) is not DifferentialActionModelFreeFwdDynamics:
            return decline(memo, class_reason(self, "differential model"))
        return euler_node(iam, data, terminal, memo)

    def _compiled_staged_node(self, iam, data, terminal: bool, memo: dict) -> object | None:
        """The compiled evaluator of the Runge-Kutta node, or of the Euler node with a control parametrization,
        ``(iam, data)`` over this model: one compiled Euler node per stage (:func:`.rbd.rk_node.staged_node`, which
        offers them through :meth:`_compiled_euler_node`)."""
        return staged_node(iam, data, terminal, memo)

    def quasiStatic(
        self, data: "DifferentialActionDataFreeFwdDynamics", x: np.ndarray, maxiter: int = 100, tol: float = 1e-9
    ) -> np.ndarray:
        """Controls that cancel gravity at ``x`` with zero velocity: ``commands(x, rnea(q, 0, 0))``."""
        x = as_vector(x, self.state.nx, "x")
        nq = self.state.nq
        tau = pin.rnea(self.pinocchio, data.pinocchio, x[:nq], np.zeros(self.state.nv), np.zeros(self.state.nv))
        act = data.multibody.actuation
        self.actuation.commands(act, x, tau)
        return act.u.copy()


class DifferentialActionDataFreeFwdDynamics(DifferentialActionDataAbstract):
    """Data of :class:`DifferentialActionModelFreeFwdDynamics`.

    Fields besides the differential-action ones: ``pinocchio`` (the node's ``pinocchio.Data``),
    ``multibody`` (``DataCollectorJointActMultibody``), ``costs``, ``constraints``, ``Minv (nv, nv)``
    and ``u_drift = τ - b (nv,)`` (armature case).
    """

    Minv = Stored()

    def __init__(self, model: DifferentialActionModelFreeFwdDynamics) -> None:
        super().__init__(model)
        nv, ndx = model.state.nv, model.state.ndx
        self.pinocchio = model.pinocchio.createData()
        actuation = model.actuation.createData()
        joint = JointDataAbstract(model.state, model.actuation, model.nu)
        joint.a = self.xout
        joint.da_dx = self.Fx
        joint.da_du = self.Fu
        np.fill_diagonal(joint.dtau_du, 1.0)
        self.multibody = DataCollectorJointActMultibody(self.pinocchio, actuation, joint)
        self.costs = model.costs.createData(self.multibody)
        for name in ("Lx", "Lu", "Lxx", "Lxu", "Luu"):  # the cost sum writes the derivatives in place
            setattr(self.costs, name, getattr(self, name))
        self.constraints = None
        if model.constraints is not None:
            self.constraints = model.constraints.createData(self.multibody)
            self.constraints.shareMemory(self)
        self.Minv = np.zeros((nv, nv))
        self.u_drift = np.zeros(nv)
        self.M = np.zeros((nv, nv))
        self.dtau = np.zeros((nv, ndx))
        self.eye = np.eye(nv)
        self.zero_a = np.zeros(nv)
        self.diag = np.diag_indices(nv)
        self.chol = None
