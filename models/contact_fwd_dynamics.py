"""Contact forward dynamics: the KKT system of a multibody in rigid contact.

With ``M`` the joint-space inertia (plus armature), ``b`` the nonlinear effects, ``τ`` the
actuation torques and the stacked contacts ``Jc a + a0 = 0``::

    [M  Jcᵀ] [ a ]   [τ - b]
    [Jc  0 ] [-λ ] = [ -a0 ],      K⁻¹ = [[A, B], [Bᵀ, C]]

(``inv_damping`` regularises ``Jc M⁻¹ Jcᵀ``).

Redundant contacts.  Without damping, a contact set whose stacked ``Jc`` has dependent rows is solved by least
squares, :mod:`~crocopy.models.redundant_kkt` (unique accelerations, minimum-norm forces: a redundant force is
shared equally), on both paths: the compiled node declines it (:mod:`.rbd.contact_lowering`) and the Python
node takes the least-squares route from the start.  A set is redundant when two active contacts share a body, or
when ``Jc`` loses rank at a generic configuration (checked once per active set, at a fixed pseudo-random
configuration): 6D contacts on the four 3-dof legs of ANYmal, 3D contacts on the four 2-dof legs of solo8 or
``quadruped``.  A ``JMinvJt_damping > 0`` instead regularises the regular KKT solve (and compiles).  A set that
loses rank only at particular configurations (a stretched leg) takes least squares where the KKT solve gives
NaN.  When the rank deficiency is structural the redundant force directions turn with the configuration: the
forces' configuration derivatives add ``dP λ = (I - P) ∂(Jc w)/∂q``, ``w = Jc⁺ λ`` (``P`` the projector onto the
range of ``Jc``; :func:`turning_forces`, 3D/6D contacts).  The derivatives are exact where the redundant rows
agree (the drift ``a0`` in the range of ``Jc``: the same contact twice, a robot at rest without position gains);
where they contradict each other (a moving robot whose redundant rows disagree, position errors) the
least-squares compromise's derivatives are approximate (they leave out the pseudo-inverse's own derivative).
Differentiating ``M a + b - Jcᵀ λ = τ`` (RNEA with the
contact forces as external forces, ``∂ID/∂x``) and the contact constraint (``da0_dx``)::

    ∂a/∂x = A (∂τ/∂x - ∂ID/∂x) - B da0_dx,     ∂a/∂u = A ∂τ/∂u
    ∂λ/∂x = -Bᵀ (∂τ/∂x - ∂ID/∂x) + C da0_dx,   ∂λ/∂u = -Bᵀ ∂τ/∂u

The force Jacobians are written to every contact's data (``df_dx``, ``df_du``) when
``enable_force`` is True, so that force residuals can use them.  The joint data collector
(``data.multibody.joint``) exposes ``tau = u``, ``a = xout`` and their derivatives (``∂τ/∂u = I``,
``da_dx = Fx``, ``da_du = Fu``) for the joint-effort/acceleration residuals, as under free dynamics.
On a terminal node (no control) the contact forces and their Jacobians are set to zero, so that no
residual reads the forces of an earlier evaluation.

A node without active contacts (a flight phase), without armature and without ``computeAllContacts``
is free dynamics: Pinocchio's ABA (LOCAL convention, then ``updateGlobalPlacements``) and
``computeABADerivatives``, ``Fx = (∂ABA/∂q, ∂ABA/∂v) + M⁻¹ ∂τ/∂x``, ``Fu = M⁻¹ ∂τ/∂u``, with the
kinematics contract of :mod:`~crocopy.models.free_fwd_dynamics` (residuals update the frames, centre
of mass or momentum they need).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from crocopy.actuation_base import ActuationModelAbstract, JointDataAbstract
from crocopy.constraints.manager import ConstraintModelManager
from crocopy.costs.sum import CostModelSum
from crocopy.diff_action_base import DifferentialActionDataAbstract, DifferentialActionModelAbstract
from crocopy.not_compiled import class_reason, decline
from crocopy.stored import bind
from crocopy.validation import as_bool

from .contact_multiple import ContactModelMultiple
from .contacts import ContactModel3D, ContactModel6D
from .data_collectors import DataCollectorJointActMultibodyInContact
from .dynamics_options import ActuationStructure, ArmatureMixin, KKTDampingMixin
from .redundant_kkt import solve_redundant_kkt

_LOCAL_CONVENTION = pin.Convention.LOCAL
_FRAME_CONTACTS = (ContactModel3D, ContactModel6D)
_all, _isfinite = np.logical_and.reduce, np.isfinite


def check_vector_shape(value: np.ndarray, size: int, name: str) -> None:
    """Raise ``ValueError`` unless ``value`` is a vector of shape ``(size,)``."""
    if getattr(value, "shape", None) != (size,) and np.shape(value) != (size,):
        raise ValueError(f"{name} has shape {np.shape(value)}, expected ({size},)")


def all_finite(values: np.ndarray) -> bool:
    """True if every entry of ``values`` is finite (two compiled calls, no Python-level wrapper)."""
    return bool(_all(_isfinite(values)))


def link_cost_data(data: object, costs_data: object) -> None:
    """Make the action data's cost derivatives the cost-sum data's arrays (no copies per call)."""
    for name in ("Lx", "Lu", "Lxx", "Lxu", "Luu"):
        bind(data, name, getattr(costs_data, name))


def turning_forces(model: pin.Model, pd: pin.Data, q: np.ndarray, active: list, Jc: np.ndarray,
                   lam: np.ndarray) -> np.ndarray:
    """``(I - P) ∂(Jc(q) w)/∂q`` at ``w = Jc⁺ λ`` (``(nc, nv)``, ``P = Jc Jc⁺``): the configuration derivative of the
    minimum-norm forces ``λ = P λ`` beyond what the KKT solution operator gives, ``dP λ``, for ``active`` 3D/6D
    contacts (``pd.oMf`` at ``q`` read).

    With ``V = Σ oS_i w_i`` the world spatial velocity (at the origin) of a contact's joint for joint velocity ``w``
    and ``V_j`` that of the parent of joint ``j``, a dof ``k`` of joint ``j`` in the support (``s = oS_k``) moves
    ``V`` by ``s × (V - V_j)``; a LOCAL row reads ``oX_f⁻¹ (V_j × s)``, a LOCAL_WORLD_ALIGNED (or WORLD) row
    ``[dV_v - (s_v + s_ω × p) × V_ω - p × dV_ω; dV_ω]`` at the frame position ``p``.
    """
    nv = model.nv
    w = np.linalg.pinv(Jc, rcond=1e-9) @ lam
    J = pin.computeJointJacobians(model, pd, q)
    D = np.zeros((Jc.shape[0], nv))
    row = 0
    for _, m in active:
        placement = pd.oMf[m.id]
        R, p = placement.rotation, placement.translation
        chain = list(model.supports[model.frames[m.id].parentJoint])[1:]
        V = sum((J[:, model.joints[j].idx_v: model.joints[j].idx_v + model.joints[j].nv]
                 @ w[model.joints[j].idx_v: model.joints[j].idx_v + model.joints[j].nv] for j in chain), np.zeros(6))
        Vb = np.zeros(6)
        for j in chain:
            iv, n = model.joints[j].idx_v, model.joints[j].nv
            for k in range(iv, iv + n):
                s = J[:, k]
                if m.type == pin.LOCAL:
                    dm = _motion_cross(Vb, s)
                    col = np.r_[R.T @ (dm[:3] - np.cross(p, dm[3:])), R.T @ dm[3:]]
                else:
                    dV = _motion_cross(s, V - Vb)
                    dp = s[:3] + np.cross(s[3:], p)
                    col = np.r_[dV[:3] - np.cross(dp, V[3:]) - np.cross(p, dV[3:]), dV[3:]]
                D[row: row + m.nc, k] = col[: m.nc]
            Vb = Vb + J[:, iv: iv + n] @ w[iv: iv + n]
        row += m.nc
    return D - Jc @ (np.linalg.pinv(Jc, rcond=1e-9) @ D)


def _motion_cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a × b`` of two spatial motions ``[linear; angular]``."""
    return np.r_[np.cross(a[3:], b[:3]) + np.cross(a[:3], b[3:]), np.cross(a[3:], b[3:])]


class DifferentialActionModelContactFwdDynamics(ArmatureMixin, KKTDampingMixin, DifferentialActionModelAbstract):
    """Crocoddyl's ``DifferentialActionModelContactFwdDynamics(state, actuation, contacts, costs,
    constraints=None, inv_damping=0., enable_force=False)``.

    Parameters
    ----------
    state : StateMultibody
        Multibody state.
    actuation : ActuationModelAbstract
        Actuation model (``nu`` of the model; control limits default to its ``u_lb``/``u_ub``, i.e.
        the URDF effort limits).
    contacts : ContactModelMultiple
        Rigid contacts.
    costs : CostModelSum
        Running or terminal cost.
    constraints : ConstraintModelManager, optional
        Constraints (Crocoddyl's overload without it is also accepted:
        ``(state, actuation, contacts, costs, inv_damping, enable_force)``).
    inv_damping : float
        Damping of ``Jc M⁻¹ Jcᵀ``.  Without it a redundant contact set (contacts sharing a body, or a ``Jc`` of
        deficient rank) is solved by least squares (see the module docstring).
    enable_force : bool
        Compute the contact-force Jacobians (needed by force residuals).

    Notes
    -----
    When every active contact has an exact Pinocchio counterpart (3D contacts, LOCAL 6D contacts,
    6D contacts without position gain), ``inv_damping`` is 0 and there is no armature, the
    dynamics and their derivatives come from ``pinocchio.constraintDynamics`` and
    ``computeConstraintDynamicsDerivatives`` (same numbers, one C++ call each).  On that path the
    per-contact ``Jc``, ``a0``, ``da0_dx`` and ``Kinv`` are not refreshed; set the crocopy-specific
    attribute ``use_pinocchio_constraints = False`` to always use the explicit KKT path.
    """

    def __init__(
        self,
        state,
        actuation: ActuationModelAbstract,
        contacts: ContactModelMultiple,
        costs: CostModelSum,
        constraints: ConstraintModelManager | float | None = None,
        inv_damping: float | bool = 0.0,
        enable_force: bool = False,
    ) -> None:
        if constraints is not None and not isinstance(constraints, ConstraintModelManager):
            constraints, inv_damping, enable_force = None, constraints, inv_damping
        if not isinstance(getattr(state, "pinocchio", None), pin.Model):
            raise ValueError(f"state must be a StateMultibody, got {type(state).__name__}")
        if not isinstance(actuation, ActuationModelAbstract):
            raise ValueError(f"actuation must be an ActuationModelAbstract, got {type(actuation).__name__}")
        if not isinstance(contacts, ContactModelMultiple):
            raise ValueError(f"contacts must be a ContactModelMultiple, got {type(contacts).__name__}")
        if not isinstance(costs, CostModelSum):
            raise ValueError(f"costs must be a CostModelSum, got {type(costs).__name__}")
        nu = actuation.nu
        for name, part in (("contacts", contacts), ("costs", costs), ("constraints", constraints)):
            if part is None:
                continue
            if part.nu != nu:
                raise ValueError(f"{name}.nu = {part.nu} does not match actuation.nu = {nu}")
            if part.state.nx != state.nx or part.state.ndx != state.ndx:
                raise ValueError(f"{name} was built on a state of another dimension than state")
        if actuation.state.nx != state.nx:
            raise ValueError("actuation was built on a state of another dimension than state")
        ng = constraints.ng if constraints is not None else 0
        nh = constraints.nh if constraints is not None else 0
        ng_T = constraints.ng_T if constraints is not None else 0
        nh_T = constraints.nh_T if constraints is not None else 0
        super().__init__(state, nu, costs.nr, ng, nh, ng_T, nh_T)
        self.actuation = actuation
        self.contacts = contacts
        self.costs = costs
        self.constraints = constraints
        self.pinocchio = state.pinocchio
        self.enable_force = as_bool(enable_force, "enable_force")
        self._act = ActuationStructure(actuation, state.nv)
        self.use_pinocchio_constraints = True
        self.JMinvJt_damping = inv_damping
        self.armature = np.zeros(state.nv)
        if constraints is not None:
            self._follow_constraints(constraints)
        # as in Crocoddyl: the bounds default to the actuation's (URDF effort limits) while
        # has_control_limits stays False until they are assigned
        self._u_lb = np.array(actuation.u_lb, dtype=float)
        self._u_ub = np.array(actuation.u_ub, dtype=float)

    def createData(self) -> "DifferentialActionDataContactFwdDynamics":
        return DifferentialActionDataContactFwdDynamics(self)

    def _redundant_contacts(self) -> bool:
        """Whether ``calc`` solves the contact dynamics in the least-squares sense from the start: no damping, and
        active contacts sharing a body or a stacked ``Jc`` of deficient rank at a generic configuration (see the
        module docstring)."""
        if not self.contacts.nc or self._damping != 0.0:
            return False
        if self.contacts._shared_joints:
            return True
        cached = self.__dict__.get("_rank_checked")
        if cached is None or cached[0] is not self.contacts._active:
            cached = self._rank_checked = (self.contacts._active, self._generic_rank() < self.contacts.nc)
        return cached[1]

    def _generic_rank(self) -> int:
        """The rank of the active contacts' stacked ``Jc (nc, nv)`` at a pseudo-random configuration (the same at
        every call): singular values above ``1e-9`` times the largest."""
        state, nc = self.state, self.contacts.nc
        rng = np.random.default_rng(0)
        q = pin.integrate(self.pinocchio, pin.neutral(self.pinocchio), rng.uniform(-1.0, 1.0, state.nv))
        x = np.concatenate([q, rng.uniform(-1.0, 1.0, state.nv)])
        data = self.createData()
        self._kinematics(data, q, x[state.nq:])
        self.contacts.calc(data.multibody.contacts, x)
        sigma = np.linalg.svd(data.multibody.contacts.Jc[:nc], compute_uv=False)
        return int(np.sum(sigma > 1e-9 * max(float(sigma[0]), np.finfo(float).tiny)))

    def _compiled_euler_node(self, iam, data, terminal: bool, memo: dict) -> object | None:
        """The compiled evaluator of the Euler node ``(iam, data)`` over this model (:func:`.rbd.euler_node.euler_node`
        with its active contacts, :mod:`.rbd.contact_lowering`), or None for a subclass or a node it cannot compile."""
        if type(self) is not DifferentialActionModelContactFwdDynamics:
            return decline(memo, class_reason(self, "differential model"))
        from .rbd.contact_lowering import active_contacts
        from .rbd.euler_node import euler_node

        contacts = active_contacts(self, memo)
        return None if contacts is None else euler_node(iam, data, terminal, memo, contacts)

    def _compiled_staged_node(self, iam, data, terminal: bool, memo: dict) -> object | None:
        """The compiled evaluator of the Runge-Kutta node, or of the Euler node with a control parametrization,
        ``(iam, data)`` over this model: one compiled Euler node per stage (:func:`.rbd.rk_node.staged_node`, which
        offers them through :meth:`_compiled_euler_node`)."""
        from .rbd.rk_node import staged_node

        return staged_node(iam, data, terminal, memo)

    def _kinematics(self, data: "DifferentialActionDataContactFwdDynamics", q: np.ndarray, v: np.ndarray) -> None:
        model, pd = self.pinocchio, data.pinocchio
        pin.computeAllTerms(model, pd, q, v)
        pin.updateFramePlacements(model, pd)
        if self._with_armature:
            pd.M[data.diag, data.diag] += self._armature

    def calc(
        self, data: "DifferentialActionDataContactFwdDynamics", x: np.ndarray, u: np.ndarray | None = None
    ) -> None:
        """Contact dynamics ``xout`` and forces (``u`` given), costs and constraints."""
        state = self.state
        q, v = x[: state.nq], x[state.nq :]
        mb = data.multibody
        if u is None:
            pin.computeForwardKinematicsDerivatives(self.pinocchio, data.pinocchio, q, v, data.zero_a)
            pin.updateFramePlacements(self.pinocchio, data.pinocchio)
            self.contacts.updateForce(mb.contacts, data.zero_force)
            self.costs.calc(data.costs, x)
            data.cost = data.costs.cost
            if self.constraints is not None:
                self.constraints.calc(data.constraints, x)
            return
        nc = self.contacts.nc
        pd = data.pinocchio
        self.actuation.calc(mb.actuation, x, u)
        mb.joint.tau[:] = u
        data.rigid = None
        data.aba = False
        # redundant contacts (shared body) or a singular KKT system: least squares, see redundant_kkt.py
        data.lstsq = self._redundant_contacts()
        if nc and self.use_pinocchio_constraints and not self._with_armature and self._damping == 0.0 \
                and not data.lstsq:
            data.rigid = self.contacts.rigidConstraints(mb.contacts, pd)
        if data.rigid is not None:
            cms, cds = data.rigid
            data.xout[:] = pin.constraintDynamics(self.pinocchio, pd, q, v, mb.actuation.tau, cms, cds, data.prox)
            data.lstsq = not all_finite(data.xout)
            data.rigid = None if data.lstsq else data.rigid
        if data.rigid is not None:
            pin.forwardKinematics(self.pinocchio, pd, q, v, data.zero_a)
            pin.updateFramePlacements(self.pinocchio, pd)
            lam = pd.lambda_c
        elif nc:
            self._kinematics(data, q, v)
            self.contacts.calc(mb.contacts, x)
            if not data.lstsq:
                data.xout[:] = pin.forwardDynamics(
                    self.pinocchio, pd, mb.actuation.tau, mb.contacts.Jc[:nc], mb.contacts.a0[:nc], self._damping
                )
                lam = pd.lambda_c
                data.lstsq = self._damping == 0.0 and not all_finite(data.xout)
            if data.lstsq:
                lam = self._redundant_dynamics(data, nc)
        elif not self._with_armature and not self.contacts.computeAllContacts:
            data.xout[:] = pin.aba(self.pinocchio, pd, q, v, mb.actuation.tau, _LOCAL_CONVENTION)
            pin.updateGlobalPlacements(self.pinocchio, pd)
            data.aba = True
            lam = data.no_force
        else:
            self._kinematics(data, q, v)
            np.add(np.triu(pd.M), np.triu(pd.M, 1).T, out=data.M)  # for calcDiff: the RNEA derivatives overwrite pd.M
            try:
                data.xout[:] = np.linalg.solve(data.M, mb.actuation.tau - pd.nle)
            except np.linalg.LinAlgError:  # a diverged trial state (non-finite inertia): no acceleration
                data.xout[:] = np.nan
            lam = data.no_force
        self.contacts.updateAcceleration(mb.contacts, data.xout)
        self.contacts.updateForce(mb.contacts, lam)
        self.costs.calc(data.costs, x, u)
        data.cost = data.costs.cost
        if self.constraints is not None:
            self.constraints.calc(data.constraints, x, u)

    def _redundant_dynamics(self, data: "DifferentialActionDataContactFwdDynamics", nc: int) -> np.ndarray:
        """Accelerations and minimum-norm forces of a rank-deficient contact set (``Kinv`` for calcDiff)."""
        pd, mb = data.pinocchio, data.multibody
        try:
            data.xout[:], lam = solve_redundant_kkt(
                pd.M, mb.actuation.tau - pd.nle, mb.contacts.Jc[:nc], mb.contacts.a0[:nc], data.Kinv
            )
        except np.linalg.LinAlgError:  # a diverged trial state (non-finite inertia)
            data.xout[:] = np.nan
            lam = np.full(nc, np.nan)
        data.lam = lam
        return lam

    def calcDiff(
        self, data: "DifferentialActionDataContactFwdDynamics", x: np.ndarray, u: np.ndarray | None = None
    ) -> None:
        """Dynamics Jacobians ``Fx``, ``Fu``, force Jacobians (``enable_force``), cost and constraint derivatives.

        Assumes :meth:`calc` was called at the same ``(x, u)``.
        """
        state = self.state
        if u is None:
            data.df_dx[:] = 0.0
            data.df_du[:] = 0.0
            self.contacts.updateForceDiff(data.multibody.contacts, data.df_dx, data.df_du)
            self.costs.calcDiff(data.costs, x)
            if self.constraints is not None:
                self.constraints.calcDiff(data.constraints, x)
            return
        nv, nc = state.nv, self.contacts.nc
        q, v = x[: state.nq], x[state.nq :]
        model, pd, mb = self.pinocchio, data.pinocchio, data.multibody
        cdata, adata = mb.contacts, mb.actuation
        if data.rigid is not None:
            self._calcDiff_rigid(data, x, u)
            return
        if data.aba:
            self._calcDiff_aba(data, x, u)
            return
        # Pinocchio writes only the tree's entries of dtau_dq/dtau_dv; the constraint-dynamics path of an earlier
        # evaluation (no damping, no armature) leaves other values in the rest
        pd.dtau_dq[:] = 0.0
        pd.dtau_dv[:] = 0.0
        pin.computeRNEADerivatives(model, pd, q, v, data.xout, cdata.fext)
        self.contacts.updateRneaDiff(cdata, pd)
        self.actuation.calcDiff(adata, x, u)
        rhs = data.rhs
        np.subtract(adata.dtau_dx[:, :nv], pd.dtau_dq, out=rhs[:nv, :nv])
        np.subtract(adata.dtau_dx[:, nv:], pd.dtau_dv, out=rhs[:nv, nv:])
        if nc:
            if not data.lstsq:
                data.Kinv[:] = pin.getKKTContactDynamicMatrixInverse(model, pd, cdata.Jc[:nc])
            self.contacts.calcDiff(cdata, x)
            np.negative(cdata.da0_dx[:nc], out=rhs[nv:])
            Kinv = data.Kinv
            np.dot(Kinv, rhs, out=data.KinvRhs)
            data.Fx[:] = data.KinvRhs[:nv]
            np.dot(Kinv[:nv, :nv], adata.dtau_du, out=data.Fu)
            if self.enable_force:
                np.negative(data.KinvRhs[nv:], out=data.df_dx)
                np.dot(Kinv[nv:, :nv], adata.dtau_du, out=data.df_du)
                np.negative(data.df_du, out=data.df_du)
                if data.lstsq and all(type(m) in _FRAME_CONTACTS for _, m in self.contacts._active):
                    data.df_dx[:, :nv] += turning_forces(model, pd, q, self.contacts._active, cdata.Jc[:nc], data.lam)
        else:
            Minv = np.linalg.inv(data.M)
            np.dot(Minv, rhs, out=data.Fx)
            np.dot(Minv, adata.dtau_du, out=data.Fu)
        if self.enable_force:
            self.contacts.updateAccelerationDiff(cdata, data.Fx)
            self.contacts.updateForceDiff(cdata, data.df_dx, data.df_du)
        self.costs.calcDiff(data.costs, x, u)
        if self.constraints is not None:
            self.constraints.calcDiff(data.constraints, x, u)

    def _chain_rule(self, adata, d_dq, d_dv, d_dtau, d_dx, d_du) -> None:
        """``d_dx = (d_dq, d_dv) + d_dtau ∂τ/∂x`` and ``d_du = d_dtau ∂τ/∂u``."""
        nv = self.state.nv
        d_dx[:, :nv] = d_dq
        d_dx[:, nv:] = d_dv
        if self._act.dtau_dx_nonzero:
            d_dx += d_dtau @ adata.dtau_dx
        self._act.times_dtau_du(d_dtau, adata.dtau_du, d_du)

    def _calcDiff_rigid(self, data: "DifferentialActionDataContactFwdDynamics", x: np.ndarray, u: np.ndarray) -> None:
        """Derivatives from Pinocchio's constraint-dynamics derivatives (same maths as the KKT path)."""
        pd, mb = data.pinocchio, data.multibody
        adata, cdata = mb.actuation, mb.contacts
        cms, cds = data.rigid
        pin.computeConstraintDynamicsDerivatives(self.pinocchio, pd, cms, cds, data.prox)
        self.actuation.calcDiff(adata, x, u)
        self._chain_rule(adata, pd.ddq_dq, pd.ddq_dv, pd.ddq_dtau, data.Fx, data.Fu)
        if self.enable_force:
            self._chain_rule(adata, pd.dlambda_dq, pd.dlambda_dv, pd.dlambda_dtau, data.df_dx, data.df_du)
            self.contacts.updateAccelerationDiff(cdata, data.Fx)
            self.contacts.updateForceDiff(cdata, data.df_dx, data.df_du)
        self.costs.calcDiff(data.costs, x, u)
        if self.constraints is not None:
            self.constraints.calcDiff(data.constraints, x, u)

    def _calcDiff_aba(self, data: "DifferentialActionDataContactFwdDynamics", x: np.ndarray, u: np.ndarray) -> None:
        """Derivatives of a node without active contacts, from Pinocchio's ABA derivatives:
        ``Fx = (∂ABA/∂q, ∂ABA/∂v) + M⁻¹ ∂τ/∂x``, ``Fu = M⁻¹ ∂τ/∂u``."""
        nq = self.state.nq
        pd, mb = data.pinocchio, data.multibody
        adata = mb.actuation
        self.actuation.calcDiff(adata, x, u)
        pin.computeABADerivatives(self.pinocchio, pd, x[:nq], x[nq:], adata.tau)
        self._chain_rule(adata, pd.ddq_dq, pd.ddq_dv, pd.Minv, data.Fx, data.Fu)
        if self.enable_force:
            self.contacts.updateAccelerationDiff(mb.contacts, data.Fx)
            self.contacts.updateForceDiff(mb.contacts, data.df_dx, data.df_du)
        self.costs.calcDiff(data.costs, x, u)
        if self.constraints is not None:
            self.constraints.calcDiff(data.constraints, x, u)

    def quasiStatic(
        self, data: "DifferentialActionDataContactFwdDynamics", x: np.ndarray, maxiter: int = 100, tol: float = 1e-9
    ) -> np.ndarray:
        """Control that keeps the robot at rest at ``q = x[:nq]`` with the active contacts.

        Solves ``[∂τ/∂u  Jcᵀ] [u; λ] = g(q)`` in the least-norm sense (zero velocity and
        acceleration); ``maxiter`` and ``tol`` are unused (kept for Crocoddyl's signature).

        Returns
        -------
        numpy.ndarray
            Quasi-static control, shape ``(nu,)``.
        """
        state = self.state
        check_vector_shape(x, state.nx, "x")
        xs = x.copy()
        xs[state.nq :] = 0.0
        q = xs[: state.nq]
        self._kinematics(data, q, xs[state.nq :])
        mb = data.multibody
        nc = self.contacts.nc
        self.contacts.calc(mb.contacts, xs)
        u0 = np.zeros(self.nu)
        self.actuation.calc(mb.actuation, xs, u0)
        self.actuation.calcDiff(mb.actuation, xs, u0)
        Jst = np.hstack([mb.actuation.dtau_du, mb.contacts.Jc[:nc].T])
        tau_g = data.pinocchio.nle - mb.actuation.tau
        return (np.linalg.pinv(Jst) @ tau_g)[: self.nu]

    def __repr__(self) -> str:
        return f"DifferentialActionModelContactFwdDynamics(nx={self.state.nx}, nu={self.nu}, nc={self.contacts.nc})"


class DifferentialActionDataContactFwdDynamics(DifferentialActionDataAbstract):
    """Data of :class:`DifferentialActionModelContactFwdDynamics`.

    Fields beyond the differential data: ``pinocchio``, ``multibody``
    (``DataCollectorJointActMultibodyInContact``), ``costs``, ``constraints``, ``Kinv (nv+nc, nv+nc)``,
    ``df_dx (nc, ndx)``, ``df_du (nc, nu)``.
    """

    def __init__(self, model: DifferentialActionModelContactFwdDynamics) -> None:
        super().__init__(model)
        nv, ndx, nu, nc = model.state.nv, model.state.ndx, model.nu, model.contacts.nc
        self.pinocchio = model.pinocchio.createData()
        actuation = model.actuation.createData()
        contacts = model.contacts.createData(self.pinocchio)
        joint = JointDataAbstract(model.state, model.actuation, nu)
        joint.a, joint.da_dx, joint.da_du = self.xout, self.Fx, self.Fu
        np.fill_diagonal(joint.dtau_du, 1.0)
        self.multibody = DataCollectorJointActMultibodyInContact(self.pinocchio, actuation, joint, contacts)
        self.costs = model.costs.createData(self.multibody)
        link_cost_data(self, self.costs)
        self.constraints = None
        if model.constraints is not None:
            self.constraints = model.constraints.createData(self.multibody)
            self.constraints.shareMemory(self)
        self.Kinv = np.zeros((nv + nc, nv + nc))
        self.df_dx = np.zeros((nc, ndx))
        self.df_du = np.zeros((nc, nu))
        self.rhs = np.zeros((nv + nc, ndx))
        self.KinvRhs = np.zeros((nv + nc, ndx))
        self.no_force = np.zeros(0)
        self.zero_force = np.zeros(nc)
        self.diag = np.arange(nv)
        self.zero_a = np.zeros(nv)
        self.M = np.zeros((nv, nv))
        self.rigid = None
        self.aba = False
        self.lstsq = False
        self.lam = np.zeros(nc)
        self.prox = pin.ProximalSettings(1e-12, 0.0, 1)
