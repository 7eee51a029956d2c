"""Frame residuals of multibody systems (frame ``f``, joint Jacobian read from the shared data).

With ``oMf`` the frame placement, ``fJf (6, nv)`` its Jacobian in the LOCAL frame and
``Rx = (∂r/∂q, ∂r/∂v)``:

- placement:   ``r = log6(pref⁻¹ oMf)`` (6), ``∂r/∂q = Jlog6(pref⁻¹ oMf) fJf``;
- translation: ``r = oMf.p - xref`` (3), ``∂r/∂q = oMf.R fJf[:3]``;
- rotation:    ``r = log3(Rrefᵀ oMf.R)`` (3), ``∂r/∂q = Jlog3(Rrefᵀ oMf.R) fJf[3:]``;
- velocity:    ``r = v_f - vref`` (6) in frame ``type``, ``Rx`` from ``getFrameVelocityDerivatives``
  (see :class:`ResidualModelFrameVelocity` for LOCAL_WORLD_ALIGNED).

Residuals read the node's ``pinocchio.Data`` from the data collector (``shared.pinocchio``): the
differential action model has computed the joint placements and velocities (``calc``) and joint
Jacobians (``calcDiff``); these residuals update only their own frame.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from crocopy.data_collector import DataCollectorAbstract
from crocopy.residuals.base import ResidualDataAbstract, ResidualModelAbstract
from crocopy.validation import as_optional_count, as_rotation, as_vector, check_finite
from crocopy.versioning import frozen_copy

from .state_multibody import StateMultibody


def check_state(state: object) -> StateMultibody:
    """Return ``state`` if it is a :class:`StateMultibody`, else raise ``ValueError``."""
    if not isinstance(state, StateMultibody):
        raise ValueError(f"state must be a StateMultibody, got {type(state).__name__}")
    return state


def check_same_robot(state: StateMultibody, other: object, name: str) -> None:
    """Raise ``ValueError`` if ``other`` (a state, or an object with ``.state``) is not ``state``'s robot."""
    other_state = getattr(other, "state", other)
    model = getattr(other_state, "pinocchio", None)
    if model is state.pinocchio:
        return
    if model is None or model.nq != state.nq or model.nv != state.nv or list(model.names) != list(
        state.pinocchio.names
    ):
        raise ValueError(f"{name} was built on a different robot than state")


def frame_id(state: StateMultibody, id: int | str) -> int:
    """Frame index of ``id`` (an index or a frame name) in ``state.pinocchio``, checked."""
    model = state.pinocchio
    if isinstance(id, str):
        if not model.existFrame(id):
            raise KeyError(f"frame {id!r} does not exist in model {model.name!r}")
        return int(model.getFrameId(id))
    if isinstance(id, bool) or not isinstance(id, int | np.integer) or not 0 <= id < model.nframes:
        raise KeyError(f"frame id {id!r} does not exist in model {model.name!r} (nframes = {model.nframes})")
    return int(id)


def shared_pinocchio(shared: DataCollectorAbstract | None, state: StateMultibody, name: str) -> pin.Data:
    """The ``pinocchio.Data`` of a multibody data collector, checked against ``state``'s model."""
    pdata = getattr(shared, "pinocchio", None)
    if not isinstance(pdata, pin.Data):
        raise ValueError(f"{name} needs a multibody data collector (with .pinocchio), got {type(shared).__name__}")
    if pdata.M.shape != (state.nv, state.nv) or len(pdata.oMf) != state.pinocchio.nframes:
        raise ValueError(f"{name}: the data collector's pinocchio data belongs to a different robot than state")
    return pdata


def frame_jacobian(model: pin.Model, data: pin.Data, fid: int, reference: pin.ReferenceFrame) -> np.ndarray:
    """Pinocchio's ``getFrameJacobian`` as a ``(6, nv)`` array (the binding returns a vector when ``nv = 1``)."""
    return np.reshape(pin.getFrameJacobian(model, data, fid, reference), (6, model.nv))


class _FrameResidual(ResidualModelAbstract):
    """Shared construction of the frame residuals (``_data_class``: the data's class, by Crocoddyl's name)."""

    _value_attributes = frozenset({"reference"})

    _data_class: type

    def __init__(self, state: StateMultibody, id: int | str, nr: int, nu: int | None, v_dependent: bool) -> None:
        check_state(state)
        fid = frame_id(state, id)
        super().__init__(state, nr, as_optional_count(nu, "nu"), True, v_dependent, False)
        self._id = fid

    @property
    def id(self) -> int:
        """Index of the frame."""
        return self._id

    @id.setter
    def id(self, value: int | str) -> None:
        self._id = frame_id(self.state, value)

    def createData(self, data: DataCollectorAbstract | None = None) -> ResidualDataAbstract:
        d = self._data_class(self, data)
        d.pinocchio = shared_pinocchio(data, self.state, type(self).__name__)
        d.fJf = np.zeros((6, self.state.nv))
        return d


class ResidualDataFramePlacement(ResidualDataAbstract):
    """Data of :class:`ResidualModelFramePlacement`: ``pinocchio`` (the collector's) and ``fJf (6, nv)``."""


class ResidualDataFrameRotation(ResidualDataAbstract):
    """Data of :class:`ResidualModelFrameRotation`: ``pinocchio`` (the collector's) and ``fJf (6, nv)``."""


class ResidualDataFrameTranslation(ResidualDataAbstract):
    """Data of :class:`ResidualModelFrameTranslation`: ``pinocchio`` (the collector's)."""


class ResidualDataFrameVelocity(ResidualDataAbstract):
    """Data of :class:`ResidualModelFrameVelocity`: ``pinocchio`` (the collector's) and ``fJf (6, nv)``."""


class ResidualModelFramePlacement(_FrameResidual):
    """``ResidualModelFramePlacement(state, id, pref, nu=state.nv)``: ``r = log6(pref⁻¹ oMf)``."""

    compiled_kind = "placement"
    """The kind compiled nodes evaluate this class as (:mod:`crocopy.models.rbd.euler_node_kernel`)."""

    def compiled_parameters(self) -> np.ndarray:
        """The parameters compiled nodes read: ``pref⁻¹`` (rotation row-major, translation)."""
        inverse = self._pref.inverse()
        return np.concatenate((inverse.rotation.reshape(-1), inverse.translation))


    _data_class = ResidualDataFramePlacement

    def __init__(self, state: StateMultibody, id: int | str, pref: pin.SE3, nu: int | None = None) -> None:
        super().__init__(state, id, 6, nu, False)
        self.reference = pref

    @property
    def reference(self) -> pin.SE3:
        """Reference placement ``pref`` (live: a change made in place is seen by the next evaluation)."""
        return self._pref

    @reference.setter
    def reference(self, value: pin.SE3) -> None:
        if not isinstance(value, pin.SE3):
            raise ValueError(f"pref must be a pinocchio.SE3, got {type(value).__name__}")
        check_finite(value.homogeneous, "pref")
        as_rotation(value.rotation, "pref.rotation")
        self._pref = value.copy()

    def calc(self, data: ResidualDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        oMf = pin.updateFramePlacement(self.state.pinocchio, data.pinocchio, self._id)
        data.rMf = self._pref.actInv(oMf)
        data.r[:] = pin.log6(data.rMf).vector

    def calcDiff(self, data: ResidualDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        nv = self.state.nv
        data.fJf[:] = frame_jacobian(self.state.pinocchio, data.pinocchio, self._id, pin.LOCAL)
        data.rJf = pin.Jlog6(data.rMf)
        data.Rx[:, :nv] = data.rJf @ data.fJf


class ResidualModelFrameTranslation(_FrameResidual):
    """``ResidualModelFrameTranslation(state, id, xref, nu=state.nv)``: ``r = oMf.translation - xref``."""

    compiled_kind = "translation"
    """The kind compiled nodes evaluate this class as (:mod:`crocopy.models.rbd.euler_node_kernel`)."""

    def compiled_parameters(self) -> np.ndarray:
        """The parameters compiled nodes read: ``xref`` (the read-only array itself)."""
        return self._xref


    def __init__(self, state: StateMultibody, id: int | str, xref: np.ndarray, nu: int | None = None) -> None:
        super().__init__(state, id, 3, nu, False)
        self.reference = xref

    @property
    def reference(self) -> np.ndarray:
        """Reference translation ``xref``, shape ``(3,)`` (a read-only copy: assign a new array to change it)."""
        return self._xref

    @reference.setter
    def reference(self, value: np.ndarray) -> None:
        self._xref = frozen_copy(as_vector(value, 3, "xref"))

    def createData(self, data: DataCollectorAbstract | None = None) -> "ResidualDataFrameTranslation":
        d = ResidualDataFrameTranslation(self, data)
        d.pinocchio = shared_pinocchio(data, self.state, type(self).__name__)
        return d

    def calc(self, data: ResidualDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        oMf = pin.updateFramePlacement(self.state.pinocchio, data.pinocchio, self._id)
        np.subtract(oMf.translation, self._xref, out=data.r)

    def calcDiff(self, data: ResidualDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        """``∂r/∂q`` is the linear part of the LOCAL_WORLD_ALIGNED frame Jacobian (``oMf.R fJf[:3]``)."""
        J = frame_jacobian(self.state.pinocchio, data.pinocchio, self._id, pin.LOCAL_WORLD_ALIGNED)
        data.Rx[:, : self.state.nv] = J[:3]


class ResidualModelFrameRotation(_FrameResidual):
    """``ResidualModelFrameRotation(state, id, Rref, nu=state.nv)``: ``r = log3(Rrefᵀ oMf.rotation)``."""

    compiled_kind = "rotation"
    """The kind compiled nodes evaluate this class as (:mod:`crocopy.models.rbd.euler_node_kernel`)."""

    def compiled_parameters(self) -> np.ndarray:
        """The parameters compiled nodes read: ``Rrefᵀ`` row-major."""
        return self._Rref.T.reshape(-1)


    _data_class = ResidualDataFrameRotation

    def __init__(self, state: StateMultibody, id: int | str, Rref: np.ndarray, nu: int | None = None) -> None:
        super().__init__(state, id, 3, nu, False)
        self.reference = Rref

    @property
    def reference(self) -> np.ndarray:
        """Reference rotation ``Rref``, shape ``(3, 3)`` (read-only: assign a new matrix)."""
        return self._Rref

    @reference.setter
    def reference(self, value: np.ndarray) -> None:
        self._Rref = frozen_copy(as_rotation(value, "Rref"))

    def calc(self, data: ResidualDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        oMf = pin.updateFramePlacement(self.state.pinocchio, data.pinocchio, self._id)
        data.rRf = self._Rref.T @ oMf.rotation
        data.r[:] = pin.log3(data.rRf)

    def calcDiff(self, data: ResidualDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        nv = self.state.nv
        data.fJf[:] = frame_jacobian(self.state.pinocchio, data.pinocchio, self._id, pin.LOCAL)
        data.rJf = pin.Jlog3(data.rRf)
        data.Rx[:, :nv] = data.rJf @ data.fJf[3:]


class ResidualModelFrameVelocity(_FrameResidual):
    """``ResidualModelFrameVelocity(state, id, vref, type, nu=state.nv)``: ``r = v_f - vref`` in frame ``type``.

    ``vref`` is a ``pinocchio.Motion`` and ``type`` a ``pinocchio.ReferenceFrame`` (LOCAL, WORLD or
    LOCAL_WORLD_ALIGNED).  The Jacobians come from ``getFrameVelocityDerivatives``, which reads the
    kinematic derivatives the differential action model computed in ``calcDiff``.  For
    LOCAL_WORLD_ALIGNED they are rebuilt from the LOCAL ones as ``R (∂v_l/∂q - [v_l]× J_ω)`` so that
    the derivative of the frame rotation is included (Pinocchio's LOCAL_WORLD_ALIGNED output, used
    as is by Crocoddyl 3.2, omits it from the linear rows).
    """

    compiled_kind = "velocity"
    """The kind compiled nodes evaluate this class as (:mod:`crocopy.models.rbd.euler_node_kernel`)."""

    def compiled_parameters(self) -> np.ndarray:
        """The parameters compiled nodes read: ``vref`` (linear, angular); ``type`` is the item's reference frame."""
        return self._vref.vector


    _data_class = ResidualDataFrameVelocity

    def __init__(
        self, state: StateMultibody, id: int | str, vref: pin.Motion, type: pin.ReferenceFrame, nu: int | None = None
    ) -> None:
        super().__init__(state, id, 6, nu, True)
        self.reference = vref
        self.type = type

    @property
    def reference(self) -> pin.Motion:
        """Reference velocity ``vref`` (live: a change made in place is seen by the next evaluation)."""
        return self._vref

    @reference.setter
    def reference(self, value: pin.Motion) -> None:
        if not isinstance(value, pin.Motion):
            raise ValueError(f"vref must be a pinocchio.Motion, got {type(value).__name__}")
        check_finite(value.vector, "vref")
        self._vref = value.copy()

    @property
    def type(self) -> pin.ReferenceFrame:
        """Frame in which the velocity is expressed."""
        return self._type

    @type.setter
    def type(self, value: pin.ReferenceFrame) -> None:
        if not isinstance(value, pin.ReferenceFrame):
            raise ValueError(f"type must be a pinocchio.ReferenceFrame, got {type(value).__name__}")
        self._type = value

    def calc(self, data: ResidualDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        model, pd = self.state.pinocchio, data.pinocchio
        if self._type != pin.LOCAL:
            pin.updateFramePlacement(model, pd, self._id)
        v = pin.getFrameVelocity(model, pd, self._id, self._type)
        np.subtract(v.vector, self._vref.vector, out=data.r)

    def calcDiff(self, data: ResidualDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        nv = self.state.nv
        model, pd, fid = self.state.pinocchio, data.pinocchio, self._id
        if self._type != pin.LOCAL_WORLD_ALIGNED:
            dv_dq, dv_dv = pin.getFrameVelocityDerivatives(model, pd, fid, self._type)
            data.Rx[:, :nv] = np.reshape(dv_dq, (6, nv))
            data.Rx[:, nv:] = np.reshape(dv_dv, (6, nv))
            return
        # v = (R v_l, R w_l): ∂v/∂q = R (∂v_l/∂q - [v_l]x Jw), with Jw the LOCAL angular Jacobian
        dv_dq, dv_dv = (np.reshape(d, (6, nv)) for d in pin.getFrameVelocityDerivatives(model, pd, fid, pin.LOCAL))
        Jw = frame_jacobian(model, pd, fid, pin.LOCAL)[3:]
        vl = pin.getFrameVelocity(model, pd, fid, pin.LOCAL)
        R = pd.oMf[fid].rotation
        data.Rx[:3, :nv] = R @ (dv_dq[:3] - pin.skew(vl.linear) @ Jw)
        data.Rx[3:, :nv] = R @ (dv_dq[3:] - pin.skew(vl.angular) @ Jw)
        data.Rx[:3, nv:] = R @ dv_dv[:3]
        data.Rx[3:, nv:] = R @ dv_dv[3:]

