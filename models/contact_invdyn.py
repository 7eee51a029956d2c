"""Contact inverse dynamics: accelerations and contact forces are the control, torques follow from RNEA.

The control is ``u = (a, f)``: the joint acceleration ``a (nv,)`` then the forces of every contact of
the ``ContactModelMultiple`` (``nc_total`` rows, contacts in name order, each in its own
coordinates).  The differential model is ``xout = a`` (``Fx = 0``, ``Fu = (I, 0)``) and

    τ(x, u) = RNEA(q, v, a, fext(f)) = M(q) a + b(q, v) - Σ Jcᵢᵀ fᵢ     (active contacts)

must be producible by the actuation.  Equality constraints (running nodes only) are added to the
constraint manager (the user's, or a new one), named as Crocoddyl names them:

- ``"tau"``: the unactuated rows of ``τ`` vanish
  (``DifferentialActionModelContactInvDynamics.ResidualModelActuation``);
- ``"<contact>_acc"``: the acceleration of an active contact, ``Jc a + a0`` with its Baumgarte
  terms, vanishes (``DifferentialActionModelContactInvDynamics.ResidualModelContact``);
- ``"<contact>_force"``: the force of an inactive contact vanishes (``ResidualModelContactForce``).

The ``_acc``/``_force`` pair of a contact follows its status in the contact set at every ``calc``.
The forces of inactive contacts stay in the contact data (they are decision variables) but are not
applied to the robot.

Kinematics contract with the residuals: after ``calc`` the node's ``pinocchio.Data`` holds ``τ``
(``tau``), the forward kinematics at ``(q, v, a)`` and the frame placements; the contact data hold
``Jc``, ``a0`` (at the acceleration ``a``) and the forces; after ``calcDiff`` the RNEA derivatives,
the contacts' ``da0_dx`` and the force Jacobians ``df_dx = 0``, ``df_du`` (the selection of the
contact's force in ``u``).  The joint data collector holds ``a`` and the actuation commands of ``τ``
(see :mod:`crocopy.models.free_invdyn`).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from crocopy.actuation_base import ActuationModelAbstract, JointDataAbstract
from crocopy.constraints.manager import ConstraintModelManager
from crocopy.costs.sum import CostModelSum
from crocopy.diff_action_base import DifferentialActionDataAbstract, DifferentialActionModelAbstract
from crocopy.not_compiled import class_reason, decline

from .contact_fwd_dynamics import link_cost_data
from .contact_multiple import ContactModelMultiple
from .data_collectors import DataCollectorJointActMultibodyInContact
from .free_invdyn import TAU, add_constraint, check_parts, joint_commands, joint_commands_diff
from .residuals_contact import ResidualModelContactForce
from .residuals_invdyn import (
    ResidualDataActuation,
    ResidualDataContact,
    ResidualModelActuationContact,
    ResidualModelContact,
    contact_layout,
)
from .state_multibody import StateMultibody


class DifferentialActionModelContactInvDynamics(DifferentialActionModelAbstract):
    """Crocoddyl's ``DifferentialActionModelContactInvDynamics(state, actuation, contacts, costs, constraints=None)``.

    Parameters
    ----------
    state : StateMultibody
        Multibody state.
    actuation : ActuationModelAbstract
        Actuation model: which torques can be produced (``tau_set``) and the commands of the joint data.
    contacts : ContactModelMultiple
        Rigid contacts, built with ``nu = state.nv + contacts.nc_total``.
    costs : CostModelSum
        Cost stack with the same ``nu``.
    constraints : ConstraintModelManager, optional
        Constraint stack with the same ``nu``; the internal equalities are added to it (as Crocoddyl
        does), or to a new manager.

    Notes
    -----
    ``nu = nv + nc_total``, ``xout = u[:nv]``.  Control limits are unbounded.  Contacts added to or
    removed from the contact set after construction are not supported (their status may change).
    """

    ResidualModelActuation = ResidualModelActuationContact
    ResidualModelContact = ResidualModelContact

    def __init__(
        self,
        state: StateMultibody,
        actuation: ActuationModelAbstract,
        contacts: ContactModelMultiple,
        costs: CostModelSum,
        constraints: ConstraintModelManager | None = None,
    ) -> None:
        if not isinstance(contacts, ContactModelMultiple):
            raise ValueError(f"contacts must be a ContactModelMultiple, got {type(contacts).__name__}")
        nv, nct = getattr(state, "nv", 0), contacts.nc_total
        check_parts(state, actuation, costs, constraints, nv + nct, contacts)
        if constraints is None:
            constraints = ConstraintModelManager(state, nv + nct)
        if actuation.nu < nv:
            add_constraint(constraints, TAU, ResidualModelActuationContact(state, actuation.nu, nct))
        for name, item in contacts.contacts.items():
            c = item.contact
            add_constraint(constraints, f"{name}_acc", ResidualModelContact(state, c.id, c.nc, nct), item.active)
            force = ResidualModelContactForce(state, c.id, pin.Force.Zero(), c.nc, nv + nct, False)
            add_constraint(constraints, f"{name}_force", force, not item.active)
        super().__init__(state, nv + nct, costs.nr, constraints.ng, constraints.nh, constraints.ng_T, constraints.nh_T)
        self._follow_constraints(constraints)
        self.actuation = actuation
        self.contacts = contacts
        self.costs = costs
        self.constraints = constraints
        self.pinocchio = state.pinocchio
        self._layout = contact_layout(contacts)

    def createData(self) -> "DifferentialActionDataContactInvDynamics":
        return DifferentialActionDataContactInvDynamics(self)

    def _sync_status(self) -> None:
        """Switch each contact's ``_acc``/``_force`` equality to its current status in the contact set."""
        items = self.contacts.contacts
        if len(items) == len(self._layout) and all(
            name in items and items[name].active == on for name, _, _, on in self._layout
        ):
            return
        layout = contact_layout(self.contacts)
        if [(n, o, c) for n, o, c, _ in layout] != [(n, o, c) for n, o, c, _ in self._layout]:
            raise ValueError("the contact set changed (contacts added or removed) after the model was built")
        for name, _, _, active in layout:
            self.constraints.changeConstraintStatus(f"{name}_acc", active)
            self.constraints.changeConstraintStatus(f"{name}_force", not active)
        self._layout = layout

    def calc(
        self, data: "DifferentialActionDataContactInvDynamics", x: np.ndarray, u: np.ndarray | None = None
    ) -> None:
        """``xout = a``, contact accelerations and forces, ``τ = RNEA(q, v, a, fext)``, joint data, costs and
        constraints (terminal: kinematics only)."""
        self._sync_status()
        nq, nv = self.state.nq, self.state.nv
        q, v = x[:nq], x[nq:]
        model, pd, mb = self.pinocchio, data.pinocchio, data.multibody
        if u is None:  # no forces on a terminal node (no residual reads an earlier evaluation's)
            pin.computeForwardKinematicsDerivatives(model, pd, q, v, data.zero_a)
            pin.updateFramePlacements(model, pd)
            self.contacts.updateForce(mb.contacts, np.zeros(self.contacts.nc))
        else:
            a = u[:nv]
            data.xout[:] = a
            pin.forwardKinematics(model, pd, q, v, a)
            pin.computeJointJacobians(model, pd, q)
            pin.updateFramePlacements(model, pd)
            cdata = mb.contacts
            self.contacts.calc(cdata, x)
            self._store_forces(cdata, u[nv:])
            self.contacts.updateAcceleration(cdata, a)
            pin.rnea(model, data.rnea, q, v, a, cdata.fext)
            pd.tau[:] = data.rnea.tau
            joint_commands(self.actuation, mb.actuation, mb.joint, x, pd.tau)
        self.costs.calc(data.costs, x, u)
        data.cost = data.costs.cost
        self.constraints.calc(data.constraints, x, u)

    def _store_forces(self, cdata, f: np.ndarray) -> None:
        """Active contacts' forces to the contact set (``fext``); inactive ones stored, not applied."""
        active = np.concatenate([f[o : o + nc] for _, o, nc, on in self._layout if on] or [np.zeros(0)])
        self.contacts.updateForce(cdata, active)
        for name, offset, nc, on in self._layout:
            if not on:
                self.contacts.contacts[name].contact.storeForce(cdata.contacts[name], f[offset : offset + nc])

    def calcDiff(
        self, data: "DifferentialActionDataContactInvDynamics", x: np.ndarray, u: np.ndarray | None = None
    ) -> None:
        """``Fx = 0``, ``Fu = (I, 0)``; RNEA and contact derivatives, force and joint-data Jacobians, cost and
        constraint derivatives.  Assumes :meth:`calc` ran at the same ``(x, u)``."""
        if u is None:
            for cd in data.multibody.contacts.contacts.values():
                cd.df_dx[:] = 0.0
                cd.df_du[:] = 0.0
        else:
            nq, nv = self.state.nq, self.state.nv
            q, v = x[:nq], x[nq:]
            pd, mb = data.pinocchio, data.multibody
            cdata = mb.contacts
            pin.computeRNEADerivatives(self.pinocchio, pd, q, v, u[:nv], cdata.fext)
            self.contacts.updateRneaDiff(cdata, pd)
            self.contacts.calcDiff(cdata, x)
            for name, offset, nc, _ in self._layout:
                cd = cdata.contacts[name]
                cd.df_dx[:] = 0.0
                cd.df_du[:] = 0.0
                cd.df_du[:, nv + offset : nv + offset + nc] = data.eye[:nc, :nc]
            data.dtau_dx[:, :nv] = pd.dtau_dq
            data.dtau_dx[:, nv:] = pd.dtau_dv
            data.dtau_du[:, :nv] = pd.M
            for name, offset, nc, on in self._layout:
                block = data.dtau_du[:, nv + offset : nv + offset + nc]
                if on:
                    np.negative(cdata.contacts[name].Jc.T, out=block)
                else:
                    block[:] = 0.0
            joint_commands_diff(self.actuation, mb.actuation, mb.joint, x, data.dtau_dx, data.dtau_du)
        self.costs.calcDiff(data.costs, x, u)
        self.constraints.calcDiff(data.constraints, x, u)

    def _compiled_euler_node(self, iam, data, terminal: bool, memo: dict) -> object | None:
        """The compiled evaluator of the Euler node ``(iam, data)`` over this model
        (:func:`.rbd.invdyn_node.invdyn_node`), or None for a subclass or a node it cannot compile."""
        if type(self) is not DifferentialActionModelContactInvDynamics:
            return decline(memo, class_reason(self, "differential model"))
        from .rbd.invdyn_node import invdyn_node

        return invdyn_node(iam, data, terminal, memo)

    def quasiStatic(
        self, data: "DifferentialActionDataContactInvDynamics", x: np.ndarray, maxiter: int = 100, tol: float = 1e-9
    ) -> np.ndarray:
        """Zero acceleration and the active contacts' forces that hold the robot at ``q = x[:nq]`` at rest.

        The forces are the least-norm solution of ``[∂τ/∂u  Jcᵀ] (w, f) = g(q)`` (actuation commands
        ``w``, gravity torques ``g``); ``maxiter`` and ``tol`` are unused (Crocoddyl's signature).

        Returns
        -------
        numpy.ndarray
            Quasi-static control ``(0, f)``, shape ``(nv + nc_total,)``.
        """
        self._sync_status()
        state = self.state
        if np.shape(x) != (state.nx,):
            raise ValueError(f"x has shape {np.shape(x)}, expected ({state.nx},)")
        nq, nv = state.nq, state.nv
        xs = np.array(x, dtype=float)
        xs[nq:] = 0.0
        q = xs[:nq]
        model, pd, mb = self.pinocchio, data.pinocchio, data.multibody
        pin.forwardKinematics(model, pd, q, xs[nq:], np.zeros(nv))
        pin.computeJointJacobians(model, pd, q)
        pin.updateFramePlacements(model, pd)
        self.contacts.calc(mb.contacts, xs)
        w0 = np.zeros(self.actuation.nu)
        self.actuation.calc(mb.actuation, xs, w0)
        self.actuation.calcDiff(mb.actuation, xs, w0)
        gravity = pin.computeGeneralizedGravity(model, data.rnea, q) - mb.actuation.tau
        nc = self.contacts.nc
        solution = np.linalg.pinv(np.hstack([mb.actuation.dtau_du, mb.contacts.Jc[:nc].T])) @ gravity
        u = np.zeros(self.nu)
        i = self.actuation.nu
        for _, offset, n, on in self._layout:
            if on:
                u[nv + offset : nv + offset + n] = solution[i : i + n]
                i += n
        return u

    def __repr__(self) -> str:
        s = self.state
        return (f"DifferentialActionModelContactInvDynamics {{nx={s.nx}, ndx={s.ndx}, nu={self.nu}, "
                f"nc={self.contacts.nc_total}}}")


class DifferentialActionDataContactInvDynamics(DifferentialActionDataAbstract):
    """Data of :class:`DifferentialActionModelContactInvDynamics`.

    Fields besides the differential-action ones: ``pinocchio`` (the node's ``pinocchio.Data``),
    ``multibody`` (``DataCollectorJointActMultibodyInContact``), ``costs``, ``constraints``,
    ``dtau_dx (nv, ndx)`` and ``dtau_du (nv, nu)`` (the torque Jacobians of the inverse dynamics).
    """

    ResidualDataActuation = ResidualDataActuation
    ResidualDataContact = ResidualDataContact

    def __init__(self, model: DifferentialActionModelContactInvDynamics) -> None:
        super().__init__(model)
        nv, nu = model.state.nv, model.nu
        self.pinocchio = model.pinocchio.createData()
        self.rnea = model.pinocchio.createData()
        contacts = model.contacts.createData(self.pinocchio)
        joint = JointDataAbstract(model.state, model.actuation, nu)
        joint.a = self.xout
        joint.da_du = self.Fu
        np.fill_diagonal(self.Fu[:, :nv], 1.0)
        actuation = model.actuation.createData()
        self.multibody = DataCollectorJointActMultibodyInContact(self.pinocchio, actuation, joint, contacts)
        self.costs = model.costs.createData(self.multibody)
        link_cost_data(self, self.costs)
        self.constraints = model.constraints.createData(self.multibody)
        self.constraints.shareMemory(self)
        self.dtau_dx = np.zeros((nv, model.state.ndx))
        self.dtau_du = np.zeros((nv, nu))
        self.zero_a = np.zeros(nv)
        self.eye = np.eye(6)


DifferentialActionModelContactInvDynamics.DifferentialActionDataContactInvDynamics = (
    DifferentialActionDataContactInvDynamics
)
