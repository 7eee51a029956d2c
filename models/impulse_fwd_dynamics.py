"""Impulse dynamics: the velocity jump of a multibody at an impact (an action model with ``nu = 0``).

With ``M`` the inertia (plus armature), ``e`` the restitution coefficient ``r_coeff`` and the
stacked impulses ``Jc``::

    [M  Jcᵀ] [ v⁺]   [  M v⁻  ]
    [Jc  0 ] [-Λ ] = [-e Jc v⁻],     xnext = (q, v⁺)

(``inv_damping`` regularises ``Jc M⁻¹ Jcᵀ``; without it, redundant impulses, i.e. two on one body, or
a singular KKT solve are handled by least squares, :mod:`~crocopy.models.redundant_kkt`).
Differentiating ``M(q)(v⁺ - v⁻) - Jcᵀ Λ = 0``
(``∂ID/∂q``: RNEA derivatives at zero velocity and gravity with acceleration ``v⁺ - v⁻`` and the
impulses as external forces) and ``Jc(q)(v⁺ + e v⁻) = 0`` (``dv0_dq`` at velocity ``v⁺ + e v⁻``)::

    K [∂v⁺/∂q; -∂Λ/∂q] = [-∂ID/∂q; -dv0_dq],    K [∂v⁺/∂v⁻; -∂Λ/∂v⁻] = [M; -e Jc]

and ``Fx = [[I, 0], [∂v⁺/∂q, ∂v⁺/∂v⁻]]``.  As ``K⁻¹ [M; Jc] = [I; 0]`` (whatever the damped lower-right
block), the second system is ``[∂v⁺/∂v⁻; -∂Λ/∂v⁻] = [I; 0] - (1 + e) K⁻¹[:, nv:] Jc`` (not on the
least-squares path, whose ``K⁻¹`` is no inverse).

Kinematics contract with the impulses and residuals: after ``calc`` the node's ``pinocchio.Data`` holds
``M`` (upper triangle), the joint Jacobians, placements and velocities at ``x`` and the frame placements
(``crba`` in the WORLD convention, ``forwardKinematics``, ``updateFramePlacements``); after ``calcDiff``
the kinematic derivatives at ``x`` (``computeForwardKinematicsDerivatives``).  Residuals update the
centre of mass or momentum they need themselves.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from crocopy.action_base import ActionDataAbstract, ActionModelAbstract
from crocopy.array_views import share_arrays
from crocopy.constraints.manager import ConstraintModelManager
from crocopy.costs.sum import CostModelSum
from crocopy.not_compiled import class_reason, decline
from crocopy.validation import as_bool

from .contact_fwd_dynamics import all_finite, link_cost_data
from .data_collectors import DataCollectorMultibodyInImpulse
from .dynamics_options import ArmatureMixin, KKTDampingMixin
from .impulse_multiple import ImpulseModelMultiple
from .redundant_kkt import solve_redundant_kkt

_WORLD = pin.Convention.WORLD


class ActionModelImpulseFwdDynamics(ArmatureMixin, KKTDampingMixin, ActionModelAbstract):
    """Crocoddyl's ``ActionModelImpulseFwdDynamics(state, impulses, costs, constraints=None, r_coeff=0.,
    inv_damping=0., enable_force=False)``.

    Parameters
    ----------
    state : StateMultibody
        Multibody state.
    impulses : ImpulseModelMultiple
        Impulses of the impact.
    costs : CostModelSum
        Cost of the impact node.  The node has no control: costs built with ``nu > 0`` (as
        Crocoddyl accepts, e.g. ``CostModelSum(state)``) are evaluated without one, like a
        terminal node's.
    constraints : ConstraintModelManager, optional
        Constraints (the overload ``(state, impulses, costs, r_coeff, inv_damping, enable_force)`` is
        also accepted); evaluated without control if built with ``nu > 0``.
    r_coeff : float
        Restitution coefficient ``e >= 0``.
    inv_damping : float
        Damping of ``Jc M⁻¹ Jcᵀ``.
    enable_force : bool
        Compute the impulse Jacobians (written to every impulse's ``df_dx``).
    """

    def __init__(
        self,
        state,
        impulses: ImpulseModelMultiple,
        costs: CostModelSum,
        constraints: ConstraintModelManager | float | None = None,
        r_coeff: float = 0.0,
        inv_damping: float | bool = 0.0,
        enable_force: bool = False,
    ) -> None:
        if constraints is not None and not isinstance(constraints, ConstraintModelManager):
            # Crocoddyl's overload without constraints: the positional arguments come one slot earlier, and the slot
            # of ``inv_damping`` holds ``enable_force`` when it was given (else its own default, 0.0)
            sixth = inv_damping
            constraints, r_coeff, inv_damping = None, constraints, r_coeff
            enable_force = sixth if isinstance(sixth, bool) else enable_force
        if not isinstance(getattr(state, "pinocchio", None), pin.Model):
            raise ValueError(f"state must be a StateMultibody, got {type(state).__name__}")
        if not isinstance(impulses, ImpulseModelMultiple):
            raise ValueError(f"impulses must be an ImpulseModelMultiple, got {type(impulses).__name__}")
        if not isinstance(costs, CostModelSum):
            raise ValueError(f"costs must be a CostModelSum, got {type(costs).__name__}")
        for name, part in (("impulses", impulses), ("costs", costs), ("constraints", constraints)):
            if part is None:
                continue
            if part.state.nx != state.nx or part.state.ndx != state.ndx:
                raise ValueError(f"{name} was built on a state of another dimension than state")
        c = constraints
        dims = (c.ng, c.nh, c.ng_T, c.nh_T) if c is not None else (0, 0, 0, 0)
        super().__init__(state, 0, costs.nr, *dims)
        self.impulses = impulses
        self.costs = costs
        self.constraints = constraints
        self.pinocchio = state.pinocchio
        self.r_coeff = r_coeff
        self.JMinvJt_damping = inv_damping
        self.enable_force = as_bool(enable_force, "enable_force")
        self.armature = np.zeros(state.nv)
        self._model_nograv = state.pinocchio.copy()
        self._model_nograv.gravity.setZero()
        if constraints is not None:
            self._follow_constraints(constraints)

    @property
    def r_coeff(self) -> float:
        """Restitution coefficient (non-negative)."""
        return self._r_coeff

    @r_coeff.setter
    def r_coeff(self, value: float) -> None:
        value = float(value)
        if not value >= 0.0:
            raise ValueError(f"r_coeff must be non-negative, got {value}")
        self._r_coeff = value

    def createData(self) -> "ActionDataImpulseFwdDynamics":
        return ActionDataImpulseFwdDynamics(self)

    def calc(self, data: "ActionDataImpulseFwdDynamics", x: np.ndarray, u: np.ndarray | None = None) -> None:
        """Velocity after impact ``xnext = (q, v⁺)``, impulses, costs and constraints."""
        state = self.state
        nq, nc = state.nq, self.impulses.nc
        q, v = x[:nq], x[nq:]
        model, pd, idata = self.pinocchio, data.pinocchio, data.multibody.impulses
        pin.crba(model, pd, q, _WORLD)  # M and the joint Jacobians
        pin.forwardKinematics(model, pd, q, v)
        pin.updateFramePlacements(model, pd)
        if self._with_armature:
            pd.M[data.diag, data.diag] += self._armature
        self.impulses.calc(idata, x)
        data.xnext[:nq] = q
        # redundant impulses (shared body) or a singular KKT system: least squares, see redundant_kkt.py
        data.lstsq = bool(nc) and self._damping == 0.0 and self.impulses._shared_joints
        if nc and not data.lstsq:
            data.xnext[nq:] = pin.impulseDynamics(model, pd, v, idata.Jc[:nc], self._r_coeff, self._damping)
            lam = pd.impulse_c
            data.lstsq = self._damping == 0.0 and not all_finite(data.xnext[nq:])
        if data.lstsq:
            Jc = idata.Jc[:nc]
            try:
                data.xnext[nq:], lam = solve_redundant_kkt(pd.M, np.triu(pd.M) @ v + np.triu(pd.M, 1).T @ v, Jc,
                                                           self._r_coeff * (Jc @ v), data.Kinv)
            except np.linalg.LinAlgError:  # a diverged trial state (non-finite inertia)
                data.xnext[nq:] = np.nan
                lam = np.full(nc, np.nan)
        elif not nc:
            data.xnext[nq:] = v
            lam = data.no_force
        self.impulses.updateVelocity(idata, data.xnext[nq:])
        self.impulses.updateForce(idata, lam)
        self.costs.calc(data.costs, x, u if self.costs.nu == 0 else None)
        data.cost = data.costs.cost
        if self.constraints is not None:
            self.constraints.calc(data.constraints, x, u if self.constraints.nu == 0 else None)

    def calcDiff(self, data: "ActionDataImpulseFwdDynamics", x: np.ndarray, u: np.ndarray | None = None) -> None:
        """``Fx``, impulse Jacobians (``enable_force``), cost and constraint derivatives (after :meth:`calc`)."""
        state = self.state
        nq, nv, nc = state.nq, state.nv, self.impulses.nc
        q, v = x[:nq], x[nq:]
        model, pd, idata = self.pinocchio, data.pinocchio, data.multibody.impulses
        vnext = data.xnext[nq:]
        if nc:
            rhs, Jc = data.rhs, idata.Jc[:nc]
            if data.lstsq:
                M = pd.M
                np.add(np.triu(M), np.triu(M, 1).T, out=rhs[:nv, nv:])
            pin.computeForwardKinematicsDerivatives(model, pd, q, vnext + self._r_coeff * v, data.zero_v)
            self.impulses.calcDiff(idata, x)
            pin.computeRNEADerivatives(self._model_nograv, pd, q, data.zero_v, vnext - v, idata.fext)
            self.impulses.updateRneaDiff(idata, pd)
            np.negative(pd.dtau_dq, out=rhs[:nv, :nv])
            np.negative(idata.dv0_dq[:nc], out=rhs[nv:, :nv])
            if data.lstsq:
                np.multiply(Jc, -self._r_coeff, out=rhs[nv:, nv:])
                np.dot(data.Kinv, rhs, out=data.KinvRhs)
            else:  # K⁻¹ [M; -e Jc] = [I; 0] - (1 + e) K⁻¹[:, nv:] Jc, as K⁻¹ [M; Jc] = [I; 0]
                Kinv = data.Kinv
                Kinv[:] = pin.getKKTContactDynamicMatrixInverse(model, pd, Jc)
                KinvRhs = data.KinvRhs
                np.matmul(Kinv, rhs[:, :nv], out=KinvRhs[:, :nv])
                np.matmul(Kinv[:, nv:], Jc, out=KinvRhs[:, nv:])
                KinvRhs[:, nv:] *= -(1.0 + self._r_coeff)
                KinvRhs.reshape(-1)[nv: nv * (2 * nv + 1): 2 * nv + 1] += 1.0
            data.Fx[nv:] = data.KinvRhs[:nv]
            self.impulses.updateVelocityDiff(idata, data.Fx[nv:])
            if self.enable_force:
                np.negative(data.KinvRhs[nv:], out=data.df_dx)
                self.impulses.updateForceDiff(idata, data.df_dx)
            pin.computeForwardKinematicsDerivatives(model, pd, q, v, data.zero_v)
        else:
            data.Fx[nv:] = 0.0
            data.Fx[nv:, nv:][data.diag, data.diag] = 1.0
            pin.computeForwardKinematicsDerivatives(model, pd, q, v, data.zero_v)
            self.impulses.updateVelocityDiff(idata, data.Fx[nv:])
        self.costs.calcDiff(data.costs, x, u if self.costs.nu == 0 else None)
        if self.constraints is not None:
            self.constraints.calcDiff(data.constraints, x, u if self.constraints.nu == 0 else None)

    def _compiled_node(self, data: "ActionDataImpulseFwdDynamics", terminal: bool, memo: dict) -> object | None:
        """The compiled evaluator of the node ``(self, data)`` (:func:`.rbd.impulse_node.impulse_node`), or None for a
        subclass or a node it cannot compile (the reason recorded in ``memo``, :mod:`crocopy.not_compiled`)."""
        if type(self) is not ActionModelImpulseFwdDynamics:
            return decline(memo, class_reason(self, "action"))
        from .rbd.impulse_node import impulse_node

        return impulse_node(self, data, terminal, memo)

    def __repr__(self) -> str:
        return f"ActionModelImpulseFwdDynamics(nx={self.state.nx}, nc={self.impulses.nc}, r_coeff={self._r_coeff})"


class ActionDataImpulseFwdDynamics(ActionDataAbstract):
    """Data of :class:`ActionModelImpulseFwdDynamics`: ``pinocchio``, ``multibody``
    (``DataCollectorMultibodyInImpulse``), ``costs``, ``constraints``, ``Kinv (nv+nc, nv+nc)`` and
    ``df_dx (nc, ndx)``."""

    def __init__(self, model: ActionModelImpulseFwdDynamics) -> None:
        super().__init__(model)
        nv, ndx, nc = model.state.nv, model.state.ndx, model.impulses.nc
        self.pinocchio = model.pinocchio.createData()
        impulses = model.impulses.createData(self.pinocchio)
        self.multibody = DataCollectorMultibodyInImpulse(self.pinocchio, impulses)
        self.costs = model.costs.createData(self.multibody)
        if model.costs.nu == 0:
            link_cost_data(self, self.costs)
        else:
            share_arrays(self.costs, self, ("Lx", "Lxx"))
        self.constraints = None
        if model.constraints is not None:
            self.constraints = model.constraints.createData(self.multibody)
            if model.constraints.nu == 0:
                self.constraints.shareMemory(self)
            else:
                share_arrays(self.constraints, self, ("g", "Gx", "h", "Hx"))
        self.Kinv = np.zeros((nv + nc, nv + nc))
        self.lstsq = False
        self.df_dx = np.zeros((nc, ndx))
        self.rhs = np.zeros((nv + nc, ndx))
        self.KinvRhs = np.zeros((nv + nc, ndx))
        self.no_force = np.zeros(0)
        self.zero_v = np.zeros(nv)
        self.diag = np.arange(nv)
        np.fill_diagonal(self.Fx[:nv, :nv], 1.0)

