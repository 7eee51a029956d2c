"""Options shared by the multibody dynamics models.

* ``armature`` (shape ``(nv,)``): added to the diagonal of the mass matrix; ``_with_armature``
  tells the models whether it is non-zero.  ``nonfinite_cause()`` (crocopy extension, called by the
  solvers when they stop on NaN/inf, :mod:`crocopy.solvers.nonfinite`) names the joints that make the mass
  matrix singular at every configuration (:func:`massless_joints`: a moving joint whose subtree carries no
  mass or inertia it could move, and no armature; romeo's fingers, bravo7's gripper).  Such a model has no
  forward dynamics: Pinocchio's ABA and the compiled kernels give NaN, and a solve returns False saying so.
* ``JMinvJt_damping`` (≥ 0): damping of the contact-space inertia ``Jc M⁻¹ Jcᵀ`` in the KKT solves of
  the contact and impulse dynamics (Crocoddyl's ``inv_damping``).
* :class:`ActuationStructure`: what the bundled actuations let the dynamics skip in the chain rule
  ``Fx = ∂a/∂x + ∂a/∂τ ∂τ/∂x``, ``Fu = ∂a/∂τ ∂τ/∂u``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from crocopy.validation import as_number, as_vector
from crocopy.versioning import frozen_copy

from .actuations import (
    ActuationModelFloatingBase,
    ActuationModelFloatingBaseThrusters,
    ActuationModelFull,
    ActuationModelLinear,
)


class ArmatureMixin:
    """The ``armature`` property of a multibody dynamics model."""

    state: Any

    @property
    def armature(self) -> np.ndarray:
        """Armature added to the diagonal of the mass matrix, shape ``(nv,)`` (read-only: assign a new array)."""
        return self._armature

    @armature.setter
    def armature(self, value: np.ndarray) -> None:
        arm = frozen_copy(as_vector(value, self.state.nv, "armature"))
        self._armature = arm
        self._with_armature = bool(np.any(arm != 0.0))

    def nonfinite_cause(self) -> str | None:
        """Why this model's dynamics are NaN, if its mass matrix is singular at every configuration (else None)."""
        joints = massless_joints(self.state.pinocchio, self._armature)
        if not joints:
            return None
        names = ", ".join(repr(n) for n in joints[:6]) + (f" and {len(joints) - 6} more" if len(joints) > 6 else "")
        return (f"the mass matrix is singular: joint(s) {names} move no mass or inertia; give them an armature "
                "or lock them (pinocchio.buildReducedModel)")


def massless_joints(model: pin.Model, armature: np.ndarray, rtol: float = 1e-12) -> list[str]:
    """The names of the joints in the null space of the mass matrix ``M(q) + diag(armature)`` (``model.armature``
    included, as ``pinocchio.crba``) at a generic configuration: eigenvalues below ``rtol`` times the largest;
    ``[]`` when it is positive definite."""
    nv = model.nv
    if nv == 0:
        return []
    rng = np.random.default_rng(0)
    q = pin.integrate(model, pin.neutral(model), rng.uniform(-1.0, 1.0, nv))
    M = np.array(pin.crba(model, model.createData(), q), dtype=float).reshape(nv, nv)
    M = np.triu(M) + np.triu(M, 1).T + np.diag(np.asarray(armature, dtype=float))
    w, V = np.linalg.eigh(M)
    null = w <= rtol * max(float(w[-1]), np.finfo(float).tiny)
    if not null.any() or not np.isfinite(w).all():
        return []
    dofs = np.flatnonzero(np.abs(V[:, null]).max(axis=1) > 1e-6)
    joints = sorted({j for j in range(1, model.njoints) for k in dofs
                     if model.joints[j].idx_v <= k < model.joints[j].idx_v + model.joints[j].nv})
    return [model.names[j] for j in joints]


class KKTDampingMixin:
    """The ``JMinvJt_damping`` property of contact and impulse dynamics."""

    @property
    def JMinvJt_damping(self) -> float:
        """Damping factor of ``Jc M⁻¹ Jcᵀ`` (non-negative)."""
        return self._damping

    @JMinvJt_damping.setter
    def JMinvJt_damping(self, value: float) -> None:
        self._damping = as_number(value, "JMinvJt_damping (inv_damping)", 0.0)


class ActuationStructure:
    """Structure of an actuation's Jacobians, for the dynamics' chain rules.

    ``dtau_dx_nonzero`` is False for the bundled actuations, whose ``τ`` does not depend on ``x``;
    ``u_columns`` is the slice of joints driven one-to-one by ``u`` when ``∂τ/∂u`` is a selection
    (full and floating-base actuations), so that ``A ∂τ/∂u = A[:, u_columns]``; ``None`` otherwise.
    ``constant``: the actuation is exactly one of those two or ``ActuationModelLinear``, whose ``calcDiff``
    has nothing to do.
    """

    def __init__(self, actuation, nv: int) -> None:
        self.dtau_dx_nonzero = not isinstance(
            actuation,
            (ActuationModelFull, ActuationModelFloatingBase, ActuationModelFloatingBaseThrusters, ActuationModelLinear),
        )
        self.u_columns = None
        self.constant = type(actuation) in (ActuationModelFull, ActuationModelFloatingBase, ActuationModelLinear)
        if type(actuation) is ActuationModelFull:
            self.u_columns = slice(0, nv)
        elif type(actuation) is ActuationModelFloatingBase:
            self.u_columns = slice(nv - actuation.nu, nv)

    def times_dtau_du(self, A: np.ndarray, dtau_du: np.ndarray, out: np.ndarray) -> None:
        """``out = A ∂τ/∂u``."""
        if self.u_columns is None:
            np.dot(A, dtau_du, out=out)
        else:
            out[:] = A[:, self.u_columns]
