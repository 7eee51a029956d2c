"""Rigid contacts: the abstract contact model and its data.

A contact of dimension ``nc`` on frame ``id`` constrains the frame acceleration,
``Jc(q) a + a0(q, v) = 0``, where ``Jc (nc, nv)`` is the contact Jacobian and ``a0 (nc,)`` the
drift (the frame acceleration at zero joint acceleration, plus Baumgarte stabilisation terms).
The contact force ``f`` (``nc`` components, in the coordinates given by ``type``:
``pinocchio.LOCAL`` or ``pinocchio.LOCAL_WORLD_ALIGNED``) enters the dynamics as ``Jcᵀ f``.

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

REFERENCE_FRAMES = (pin.LOCAL, pin.LOCAL_WORLD_ALIGNED)


def frame_id(state: StateAbstract, id: int | str, name: str = "id") -> int:
    """Return a valid frame index of ``state.pinocchio`` from an index or a frame name.

    Raises
    ------
    ValueError
        If the model has no such frame.
    """
    model = getattr(state, "pinocchio", None)
    if not isinstance(model, pin.Model):
        raise ValueError(f"state must be a StateMultibody (with a pinocchio model), got {type(state).__name__}")
    if isinstance(id, str):
        if not model.existFrame(id):
            raise ValueError(f"{name}: the model has no frame named {id!r}")
        return int(model.getFrameId(id))
    try:
        fid = int(id)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a frame index or a frame name, got {id!r}") from exc
    if fid != id or not 0 <= fid < model.nframes:
        raise ValueError(f"{name} = {id!r} is not a frame index of the model (0 <= id < {model.nframes})")
    return fid


def check_reference_frame(type: pin.ReferenceFrame) -> pin.ReferenceFrame:
    """Accept ``pinocchio.LOCAL`` and ``pinocchio.LOCAL_WORLD_ALIGNED`` only."""
    if type not in REFERENCE_FRAMES:
        raise ValueError(f"type must be pinocchio.LOCAL or pinocchio.LOCAL_WORLD_ALIGNED, got {type!r}")
    return type


def check_gains(gains: np.ndarray | None) -> np.ndarray:
    """Baumgarte gains ``(kp, kd)`` as a float vector of shape ``(2,)``."""
    g = np.zeros(2) if gains is None else np.asarray(gains, dtype=float).reshape(-1)
    if g.shape != (2,) or not np.all(np.isfinite(g)):
        raise ValueError(f"gains must be a finite vector of shape (2,), got {np.asarray(gains).shape}")
    return g


class ContactModelAbstract:
    """Abstract contact model (Crocoddyl's ``ContactModelAbstract(state, type, nc, nu=state.nv)``).

    Parameters
    ----------
    state : StateMultibody
        Multibody state.
    type : pinocchio.ReferenceFrame
        Coordinates of ``Jc``, ``a0`` and ``f``: ``LOCAL`` or ``LOCAL_WORLD_ALIGNED``.
    nc : int
        Contact dimension.
    nu : int, optional
        Control dimension (default ``state.nv``).
    """

    def __init__(self, state: StateAbstract, type: pin.ReferenceFrame, nc: int, nu: int | None = None) -> None:
        if not isinstance(getattr(state, "pinocchio", None), pin.Model):
            raise ValueError(f"state must be a StateMultibody, got {state.__class__.__name__}")
        self.state = state
        self.type = check_reference_frame(type)
        self.nc = int(nc)
        self.nu = state.nv if nu is None else int(nu)
        if self.nu < 0:
            raise ValueError(f"nu must be non-negative, got {self.nu}")
        self.id = 0

    def createData(self, data: pin.Data) -> "ContactDataAbstract":
        """Allocate the contact data; ``data`` is the node's ``pinocchio.Data``."""
        return ContactDataAbstract(self, data)

    def calc(self, data: "ContactDataAbstract", x: np.ndarray) -> None:
        raise NotImplementedError(f"{type(self).__name__}.calc is not implemented")

    def calcDiff(self, data: "ContactDataAbstract", x: np.ndarray) -> None:
        raise NotImplementedError(f"{type(self).__name__}.calcDiff is not implemented")

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

    def setZeroForce(self, data: "ContactDataAbstract") -> None:
        """Zero force (inactive contact)."""
        data.f.setZero()
        data.fext.setZero()

    def setZeroForceDiff(self, data: "ContactDataAbstract") -> None:
        """Zero force Jacobians (inactive contact)."""
        data.df_dx[:] = 0.0
        data.df_du[:] = 0.0

    def addRneaDiff(self, data: "ContactDataAbstract", dtau_dq: np.ndarray) -> None:
        """Add to ``dtau_dq`` the term RNEA derivatives miss when ``f`` is not expressed in the local frame."""

    def __repr__(self) -> str:
        return f"{self.__class__.__name__}(id={self.id}, nc={self.nc}, type={self.type})"


class ContactDataAbstract:
    """Contact data: ``Jc (nc, nv)``, ``a0 (nc,)``, ``da0_dx (nc, ndx)``, ``f``/``fext`` (``pinocchio.Force``,
    contact and parent-joint coordinates), ``df_dx (nc, ndx)``, ``df_du (nc, nu)``, ``fJf (6, nv)`` (local
    frame Jacobian), ``jMf``/``fXj`` (frame placement in its joint and its inverse action matrix),
    ``dtau_dq (nv, nv)`` and the frame-acceleration derivatives ``v_partial_dq``, ``a_partial_dq``,
    ``a_partial_dv``, ``a_partial_da`` (each ``(6, nv)``)."""

    def __init__(self, model: ContactModelAbstract, data: pin.Data) -> None:
        nc, nv, ndx, nu = model.nc, model.state.nv, model.state.ndx, model.nu
        pmodel = model.state.pinocchio
        self.pinocchio = data
        self.frame = model.id
        self.type = model.type
        self.joint = int(pmodel.frames[model.id].parentJoint)
        self.jMf = pmodel.frames[model.id].placement.copy()
        self.fXj = self.jMf.inverse().toActionMatrix()
        self.Jc = np.zeros((nc, nv))
        self.a0 = np.zeros(nc)
        self.da0_dx = np.zeros((nc, ndx))
        self.f = pin.Force.Zero()
        self.fext = pin.Force.Zero()
        self.df_dx = np.zeros((nc, ndx))
        self.df_du = np.zeros((nc, nu))
        self.fJf = np.zeros((6, nv))
        self.v = pin.Motion.Zero()
        self.dtau_dq = np.zeros((nv, nv))
        self.v_partial_dq = np.zeros((6, nv))
        self.a_partial_dq = np.zeros((6, nv))
        self.a_partial_dv = np.zeros((6, nv))
        self.a_partial_da = np.zeros((6, nv))
