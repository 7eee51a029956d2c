"""Impulses: the abstract impulse model and its data.

An impulse of dimension ``nc`` on frame ``id`` constrains the frame velocity after impact,
``Jc(q) v⁺ = -e Jc(q) v⁻``.  ``calc`` fills ``Jc (nc, nv)`` (coordinates given by ``type``:
``pinocchio.LOCAL`` or ``pinocchio.LOCAL_WORLD_ALIGNED``); ``calcDiff`` fills
``dv0_dq = ∂(Jc(q) w)/∂q (nc, nv)`` for the joint velocity ``w`` currently held by the
``pinocchio.Data`` (after ``computeForwardKinematicsDerivatives``).  The impulse ``Λ`` enters the
impact equation as ``Jcᵀ Λ``.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from crocopy.state import StateAbstract

from .contact_base import check_reference_frame


class ImpulseModelAbstract:
    """Abstract impulse model (Crocoddyl's ``ImpulseModelAbstract(state, type, nc)``; ``nu = 0``).

    Parameters
    ----------
    state : StateMultibody
        Multibody state.
    type : pinocchio.ReferenceFrame
        ``pinocchio.LOCAL`` or ``pinocchio.LOCAL_WORLD_ALIGNED``.
    nc : int
        Impulse dimension.
    """

    def __init__(self, state: StateAbstract, type: pin.ReferenceFrame, nc: int | None = None) -> None:
        if nc is None:
            type, nc = pin.LOCAL, type
        if not isinstance(getattr(state, "pinocchio", None), pin.Model):
            raise ValueError(f"state must be a StateMultibody, got {state.__class__.__name__}")
        self.state = state
        self.type = check_reference_frame(type)
        self.nc = int(nc)
        self.nu = 0
        self.id = 0

    @property
    def ni(self) -> int:
        """Impulse dimension (same as ``nc``)."""
        return self.nc

    def createData(self, data: pin.Data) -> "ImpulseDataAbstract":
        """Allocate the impulse data; ``data`` is the node's ``pinocchio.Data``."""
        return ImpulseDataAbstract(self, data)

    def calc(self, data: "ImpulseDataAbstract", x: np.ndarray) -> None:
        raise NotImplementedError(f"{self.__class__.__name__}.calc is not implemented")

    def calcDiff(self, data: "ImpulseDataAbstract", x: np.ndarray) -> None:
        raise NotImplementedError(f"{self.__class__.__name__}.calcDiff is not implemented")

    def updateForce(self, data: "ImpulseDataAbstract", force: np.ndarray) -> None:
        """Store the impulse (shape ``(nc,)``) in ``data.f`` and its joint-frame image in ``data.fext``."""
        if np.shape(force) != (self.nc,):
            raise ValueError(f"force has shape {np.shape(force)}, expected ({self.nc},)")
        f = np.zeros(6)
        f[: self.nc] = force
        data.f.vector = f
        if self.type == pin.LOCAL:
            data.f_local.vector = f
        else:
            Rt = data.pinocchio.oMf[self.id].rotation.T
            data.f_local.linear = Rt @ f[:3]
            data.f_local.angular = Rt @ f[3:]
        data.fext = data.jMf.act(data.f_local)

    def updateForceDiff(self, data: "ImpulseDataAbstract", df_dx: np.ndarray) -> None:
        """Store the impulse Jacobian ``df_dx (nc, ndx)``."""
        data.df_dx[:] = df_dx

    def setZeroForce(self, data: "ImpulseDataAbstract") -> None:
        """Zero impulse (inactive)."""
        data.f.setZero()
        data.fext.setZero()

    def setZeroForceDiff(self, data: "ImpulseDataAbstract") -> None:
        """Zero impulse Jacobian (inactive)."""
        data.df_dx[:] = 0.0

    def addRneaDiff(self, data: "ImpulseDataAbstract", dtau_dq: np.ndarray) -> None:
        """Add to ``dtau_dq`` the term RNEA derivatives miss when ``f`` is not in local coordinates:
        ``-(Jlᵀ [f_l]× + Jaᵀ [f_a]×) Ja`` with ``f_local = (f_l, f_a)``."""
        if self.type == pin.LOCAL:
            return
        Jl, Ja = data.fJf[:3], data.fJf[3:]
        fl = data.f_local
        np.dot(Jl.T @ pin.skew(fl.linear) + Ja.T @ pin.skew(fl.angular), Ja, out=data.dtau_dq)
        dtau_dq -= data.dtau_dq

    def __repr__(self) -> str:
        return f"{self.__class__.__name__}(id={self.id}, nc={self.nc}, type={self.type})"


class ImpulseDataAbstract:
    """Impulse data: ``Jc (nc, nv)``, ``dv0_dq (nc, nv)``, ``dv0_local_dq (nc, nv)``, ``f``/``f_local``/``fext``
    (``pinocchio.Force``: impulse coordinates, local frame, parent joint), ``df_dx (nc, ndx)``,
    ``df_du (nc, 0)``, ``fJf (6, nv)``, ``jMf``, ``fXj``, ``dtau_dq (nv, nv)``, ``v_partial_dq``,
    ``v_partial_dv`` (each ``(6, nv)``)."""

    def __init__(self, model: ImpulseModelAbstract, data: pin.Data) -> None:
        nc, nv, ndx = model.nc, model.state.nv, model.state.ndx
        pmodel = model.state.pinocchio
        self.pinocchio = data
        self.frame = model.id
        self.type = model.type
        self.joint = int(pmodel.frames[model.id].parentJoint)
        self.jMf = pmodel.frames[model.id].placement.copy()
        self.fXj = self.jMf.inverse().toActionMatrix()
        self.Jc = np.zeros((nc, nv))
        self.dv0_dq = np.zeros((nc, nv))
        self.dv0_local_dq = np.zeros((nc, nv))
        self.f = pin.Force.Zero()
        self.f_local = pin.Force.Zero()
        self.fext = pin.Force.Zero()
        self.df_dx = np.zeros((nc, ndx))
        self.df_du = np.zeros((nc, 0))
        self.fJf = np.zeros((6, nv))
        self.dtau_dq = np.zeros((nv, nv))
        self.v_partial_dq = np.zeros((6, nv))
        self.v_partial_dv = np.zeros((6, nv))
