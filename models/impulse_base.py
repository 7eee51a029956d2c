"""Impulses: the abstract impulse model and its data.

An impulse of dimension ``nc`` on frame ``id`` constrains the frame velocity after impact,
``Jc(q) v⁺ = -e Jc(q) v⁻``.  ``calc`` fills ``Jc (nc, nv)`` (coordinates given by ``type``:
``pinocchio.LOCAL`` or ``pinocchio.LOCAL_WORLD_ALIGNED``); ``calcDiff`` fills
``dv0_dq = ∂(Jc(q) w)/∂q (nc, nv)`` for the joint velocity ``w`` currently held by the
``pinocchio.Data`` (after ``computeForwardKinematicsDerivatives``).  The impulse ``Λ`` enters the
impact equation as ``Jcᵀ Λ``; its maps to the joint frame and the RNEA correction are those of
:class:`~crocopy.models.force_base.FrameForce`.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from crocopy.state import StateAbstract

from .force_base import ForceDataAbstract, ForceModelAbstract, FrameForce

_FRAME_UPDATE = FrameForce.updateForce


class ImpulseModelAbstract(FrameForce, ForceModelAbstract):
    """Abstract impulse model (Crocoddyl's ``ImpulseModelAbstract(state, type, nc)`` or
    ``ImpulseModelAbstract(state, nc)`` with ``type = pinocchio.LOCAL``; ``nu = 0``).

    Parameters
    ----------
    state : StateMultibody
        Multibody state.
    type : pinocchio.ReferenceFrame
        ``pinocchio.LOCAL`` or ``pinocchio.LOCAL_WORLD_ALIGNED``.
    nc : int
        Impulse dimension (3 or 6 for the force maps of :class:`~crocopy.models.force_base.FrameForce`).
    """

    def __init__(self, state: StateAbstract, type: pin.ReferenceFrame, nc: int | None = None) -> None:
        if nc is None:
            type, nc = pin.LOCAL, type
        super().__init__(state, type, nc, 0)

    @property
    def ni(self) -> int:
        """Impulse dimension (same as ``nc``)."""
        return self.nc

    def createData(self, data: pin.Data) -> "ImpulseDataAbstract":
        """Allocate the impulse data; ``data`` is the node's ``pinocchio.Data``."""
        return ImpulseDataAbstract(self, data)

    def storeForce(self, data: "ImpulseDataAbstract", force: np.ndarray) -> None:
        """Store ``force (nc,)`` in ``data.f`` (``f_local``/``fext`` wait for :meth:`updateJointForce`); a
        subclass with an ``updateForce`` of its own gets that called instead."""
        if type(self).updateForce is _FRAME_UPDATE:
            FrameForce.storeForce(self, data, force)
        else:
            self.updateForce(data, force)

    def updateJointForce(self, data: "ImpulseDataAbstract") -> None:
        """``f_local`` and ``fext`` from ``data.f`` (nothing left to do after a subclass's own ``updateForce``)."""
        if type(self).updateForce is _FRAME_UPDATE:
            FrameForce.updateJointForce(self, data)

    def updateForceDiff(self, data: "ImpulseDataAbstract", df_dx: np.ndarray) -> None:
        """Store the impulse Jacobian ``df_dx (nc, ndx)``."""
        data.df_dx[:] = df_dx


class ImpulseDataAbstract(ForceDataAbstract):
    """Impulse data: the fields of :class:`~crocopy.models.force_base.ForceDataAbstract` (``df_du`` has
    shape ``(nc, 0)``), ``dv0_dq (nc, nv)``, ``dv0_local_dq (nc, nv)`` and ``v_partial_dv (6, nv)``."""

    def __init__(self, model: ImpulseModelAbstract, data: pin.Data) -> None:
        super().__init__(model, data)
        nc, nv = model.nc, model.state.nv
        self.dv0_dq = np.zeros((nc, nv))
        self.dv0_local_dq = np.zeros((nc, nv))
        self.v_partial_dv = np.zeros((6, nv))
