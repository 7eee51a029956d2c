"""Rigid contacts: the abstract contact model and its data.

A contact of dimension ``nc`` on frame ``id`` constrains the frame acceleration,
``Jc(q) a + a0(q, v) = 0``, where ``Jc (nc, nv)`` is the contact Jacobian and ``a0 (nc,)`` the
drift (the frame acceleration at zero joint acceleration, plus Baumgarte stabilisation terms).
The contact force ``f`` (``nc`` components, in the coordinates given by ``type``:
``pinocchio.LOCAL`` or ``pinocchio.LOCAL_WORLD_ALIGNED``) enters the dynamics as ``Jcᵀ f``.  What
contacts share with impulses lives in :mod:`~crocopy.models.force_base`.

Preconditions (filled once per node by the differential action model):

- ``calc``: joint placements, velocities, bias accelerations (zero joint acceleration), joint
  Jacobians and frame placements in ``data.pinocchio`` (``computeAllTerms`` +
  ``updateFramePlacements``).
- ``calcDiff``: the kinematic derivatives at the current acceleration
  (``computeRNEADerivatives`` or ``computeForwardKinematicsDerivatives``).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from crocopy.state import StateAbstract
from crocopy.validation import as_vector

from .force_base import ForceDataAbstract, ForceModelAbstract


def check_gains(gains: np.ndarray | None) -> np.ndarray:
    """Baumgarte gains ``(kp, kd)`` as a float vector of shape ``(2,)``."""
    return np.zeros(2) if gains is None else as_vector(gains, 2, "gains")


def check_position(value: np.ndarray, size: int, name: str = "xref") -> np.ndarray:
    """A contact position as a finite float vector of shape ``(size,)`` (a column, a row or a list is
    accepted; see :func:`crocopy.validation.as_vector`)."""
    return as_vector(value, size, name)


class ContactModelAbstract(ForceModelAbstract):
    """Abstract contact model (Crocoddyl's ``ContactModelAbstract(state, type, nc, nu=state.nv)``).

    Parameters
    ----------
    state : StateMultibody
        Multibody state.
    type : pinocchio.ReferenceFrame
        Coordinates of ``Jc``, ``a0`` and ``f``: ``LOCAL`` or ``LOCAL_WORLD_ALIGNED`` (``WORLD``: the same).
    nc : int
        Contact dimension.
    nu : int, optional
        Control dimension (default ``state.nv``).
    """

    def __init__(self, state: StateAbstract, type: pin.ReferenceFrame, nc: int, nu: int | None = None) -> None:
        super().__init__(state, type, nc, getattr(state, "nv", 0) if nu is None else nu)

    def createData(self, data: pin.Data) -> "ContactDataAbstract":
        """Allocate the contact data; ``data`` is the node's ``pinocchio.Data``."""
        return ContactDataAbstract(self, data)

    def updateForce(self, data: "ContactDataAbstract", force: np.ndarray) -> None:
        """Store the contact force (shape ``(nc,)``) in ``data.f`` and its joint-frame image in ``data.fext``."""
        raise NotImplementedError(f"{type(self).__name__}.updateForce is not implemented")

    def storeForce(self, data: "ContactDataAbstract", force: np.ndarray) -> None:
        """Store the force in ``data.f``; the joint-frame image may wait for :meth:`updateJointForce`.

        The default does the whole :meth:`updateForce`.
        """
        self.updateForce(data, force)

    def updateJointForce(self, data: "ContactDataAbstract") -> None:
        """Bring ``data.fext`` up to date with ``data.f`` after :meth:`storeForce` (default: nothing left to do)."""

    def updateForceDiff(self, data: "ContactDataAbstract", df_dx: np.ndarray, df_du: np.ndarray) -> None:
        """Store the force Jacobians ``df_dx (nc, ndx)`` and ``df_du (nc, nu)``."""
        data.df_dx[:] = df_dx
        data.df_du[:] = df_du

    def addRneaDiff(self, data: "ContactDataAbstract", dtau_dq: np.ndarray) -> None:
        """Add to ``dtau_dq`` the term RNEA derivatives miss when ``f`` is not expressed in the local frame."""


class ContactDataAbstract(ForceDataAbstract):
    """Contact data: the fields of :class:`~crocopy.models.force_base.ForceDataAbstract`, the drift
    ``a0 (nc,)`` and its Jacobian ``da0_dx (nc, ndx)``, the LOCAL frame velocity ``v`` and the
    frame-acceleration derivatives ``a_partial_dq``, ``a_partial_dv``, ``a_partial_da`` (each ``(6, nv)``)."""

    def __init__(self, model: ContactModelAbstract, data: pin.Data) -> None:
        super().__init__(model, data)
        nc, nv, ndx = model.nc, model.state.nv, model.state.ndx
        self.a0 = np.zeros(nc)
        self.da0_dx = np.zeros((nc, ndx))
        self.v = pin.Motion.Zero()
        self.a_partial_dq = np.zeros((6, nv))
        self.a_partial_dv = np.zeros((6, nv))
        self.a_partial_da = np.zeros((6, nv))
