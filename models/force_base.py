"""What contacts and impulses share: a force of dimension ``nc`` on a frame, its data, and named sets.

A contact (:mod:`~crocopy.models.contact_base`) or an impulse (:mod:`~crocopy.models.impulse_base`)
acts on frame ``id`` through the Jacobian ``Jc (nc, nv)``; its force ``f`` (``nc`` components in the
coordinates given by ``type``: ``pinocchio.LOCAL`` or ``pinocchio.LOCAL_WORLD_ALIGNED``) enters the
dynamics as ``Jcᵀ f``.  ``pinocchio.WORLD`` is accepted as Crocoddyl accepts it, and means what it
means there (measured): the same Jacobian, drift and force coordinates as ``LOCAL_WORLD_ALIGNED``.
With ``R`` the frame orientation, ``J = (Jl; Ja)`` the LOCAL frame Jacobian and ``jMf`` the frame
placement in its parent joint:

- ``f_local = f`` (LOCAL) or ``Rᵀ f`` per 3-block (LOCAL_WORLD_ALIGNED), and the joint-frame force
  ``fext = jMf.act(f_local)`` (the input of Pinocchio's RNEA);
- as ``Rᵀ f`` turns with ``q``, the RNEA derivative misses ``-(Jlᵀ [f_l]× + Jaᵀ [f_a]×) Ja`` in
  LOCAL_WORLD_ALIGNED (``f_local = (f_l, f_a)``, ``f_a = 0`` for a 3D force): ``addRneaDiff``.

:class:`ForceModelAbstract`/:class:`ForceDataAbstract` (Crocoddyl's name for the shared data) hold the
constructor, the zero-force calls and the common fields; :class:`FrameForce` the force maps above for
``nc = 3`` (a linear force) and ``nc = 6`` (a wrench); :class:`ForceModelMultiple` and
:class:`ForceDataMultiple` the bookkeeping of ``ContactModelMultiple``/``ImpulseModelMultiple``:
active items stacked in name order into the first ``nc`` rows of ``Jc (nc_total, nv)``.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from crocopy.guards import Guarded, point_guards
from crocopy.named_items import ModelItems
from crocopy.state import StateAbstract
from crocopy.validation import as_count, as_index
from crocopy.versioning import Parametrized, made_from

REFERENCE_FRAMES = (pin.LOCAL, pin.WORLD, pin.LOCAL_WORLD_ALIGNED)
_LOCAL = pin.LOCAL
_skew = pin.skew


def check_state_multibody(state: StateAbstract) -> StateAbstract:
    """Accept a state with a ``pinocchio.Model`` (a ``StateMultibody``); ``ValueError`` otherwise."""
    if not isinstance(getattr(state, "pinocchio", None), pin.Model):
        raise ValueError(f"state must be a StateMultibody, got {type(state).__name__}")
    return state


def frame_id(state: StateAbstract, id: int | str, name: str = "id") -> int:
    """Return a valid frame index of ``state.pinocchio`` from an index or a frame name.

    Raises
    ------
    ValueError
        If the model has no such frame.
    TypeError
        If ``id`` is neither an int (a bool is not) nor a str.
    """
    model = getattr(state, "pinocchio", None)
    if not isinstance(model, pin.Model):
        raise ValueError(f"state must be a StateMultibody (with a pinocchio model), got {type(state).__name__}")
    if isinstance(id, str):
        if not model.existFrame(id):
            raise ValueError(f"{name}: the model has no frame named {id!r}")
        return int(model.getFrameId(id))
    fid = as_index(id, name, None, "a frame index (int) or a frame name (str)")
    if not 0 <= fid < model.nframes:
        raise ValueError(f"{name} = {id!r} is not a frame index of the model (0 <= id < {model.nframes})")
    return fid


def check_reference_frame(type: pin.ReferenceFrame) -> pin.ReferenceFrame:
    """Accept ``pinocchio.LOCAL``, ``pinocchio.WORLD`` and ``pinocchio.LOCAL_WORLD_ALIGNED``."""
    if not isinstance(type, pin.ReferenceFrame) or type not in REFERENCE_FRAMES:
        raise ValueError(
            f"type must be pinocchio.LOCAL, pinocchio.WORLD or pinocchio.LOCAL_WORLD_ALIGNED, got {type!r}"
        )
    return type


def world_aligned(type: pin.ReferenceFrame) -> pin.ReferenceFrame:
    """The coordinates ``type`` stands for: ``LOCAL`` or ``LOCAL_WORLD_ALIGNED`` (``WORLD``, as in Crocoddyl)."""
    return pin.LOCAL if type == pin.LOCAL else pin.LOCAL_WORLD_ALIGNED


class ForceModelAbstract(Parametrized, Guarded):
    """Common base of ``ContactModelAbstract`` and ``ImpulseModelAbstract``.

    Parameters
    ----------
    state : StateMultibody
        Multibody state.
    type : pinocchio.ReferenceFrame
        Coordinates of ``Jc`` and ``f``: ``LOCAL``, ``LOCAL_WORLD_ALIGNED`` or ``WORLD`` (the same as
        ``LOCAL_WORLD_ALIGNED``).
    nc : int
        Force dimension.
    nu : int
        Control dimension.

    Notes
    -----
    A user's ``calc(data, x)``/``calcDiff(data, x)`` is checked (``x (nx,)``, finite).
    """

    _read_only = frozenset({"state"})

    _guards = point_guards()

    def __init__(self, state: StateAbstract, type: pin.ReferenceFrame, nc: int, nu: int) -> None:
        self.state = check_state_multibody(state)
        self.type = check_reference_frame(type)
        self.nc = as_count(nc, "nc")
        self.nu = as_count(nu, "nu")
        self.id = 0

    def calc(self, data: "ForceDataAbstract", x: np.ndarray) -> None:
        raise NotImplementedError(f"{type(self).__name__}.calc is not implemented")

    def calcDiff(self, data: "ForceDataAbstract", x: np.ndarray) -> None:
        raise NotImplementedError(f"{type(self).__name__}.calcDiff is not implemented")

    def setZeroForce(self, data: "ForceDataAbstract") -> None:
        """Zero force (inactive)."""
        data.f.setZero()
        data.fext.setZero()

    def setZeroForceDiff(self, data: "ForceDataAbstract") -> None:
        """Zero force Jacobians (inactive)."""
        data.df_dx[:] = 0.0
        data.df_du[:] = 0.0

    def __repr__(self) -> str:
        return f"{type(self).__name__}(id={self.id}, nc={self.nc}, type={self.type})"


class FrameForce:
    """Force maps of a 3D (linear) or 6D (wrench) force on frame ``id`` (see the module docstring).

    ``updateForce`` is ``storeForce`` (``data.f`` only) then ``updateJointForce`` (``f_local``, ``fext``).
    """

    nc: int
    type: pin.ReferenceFrame
    id: int

    def updateForce(self, data: "ForceDataAbstract", force: np.ndarray) -> None:
        """Store ``force (nc,)`` in ``data.f`` and its joint-frame image in ``data.fext``.

        Raises
        ------
        ValueError
            If ``force`` does not have shape ``(nc,)``.
        """
        if np.shape(force) != (self.nc,):
            raise ValueError(f"force has shape {np.shape(force)}, expected ({self.nc},)")
        self.storeForce(data, force)
        self.updateJointForce(data)

    def storeForce(self, data: "ForceDataAbstract", force: np.ndarray) -> None:
        """Store ``force (nc,)`` in ``data.f`` only (``f_local``/``fext`` wait for :meth:`updateJointForce`)."""
        if self.nc == 3:
            data.f.linear = force
        else:
            data.f.vector = force

    def updateJointForce(self, data: "ForceDataAbstract") -> None:
        """``f_local`` and ``fext`` (the force at the parent joint) from ``data.f``."""
        if self.type == _LOCAL:
            data.f_local.vector = data.f.vector
        else:
            R = data.pinocchio.oMf[self.id].rotation
            data.f_local.linear = data.f.linear @ R
            if self.nc == 6:
                data.f_local.angular = data.f.angular @ R
        data.fext = data.jMf.act(data.f_local)

    def addRneaDiff(self, data: "ForceDataAbstract", dtau_dq: np.ndarray) -> None:
        """Subtract ``(Jlᵀ [f_l]× + Jaᵀ [f_a]×) Ja`` from ``dtau_dq`` (LOCAL_WORLD_ALIGNED only)."""
        if self.type == _LOCAL:
            return
        Jl, Ja = data.fJf[:3], data.fJf[3:]
        fl = data.f_local
        if self.nc != 6:
            np.dot(Jl.T, _skew(fl.linear) @ Ja, out=data.dtau_dq)
        else:
            np.dot(Jl.T @ _skew(fl.linear) + Ja.T @ _skew(fl.angular), Ja, out=data.dtau_dq)
        dtau_dq -= data.dtau_dq


class ForceDataAbstract:
    """Crocoddyl's ``ForceDataAbstract(model, data)``: what contact and impulse data share.

    Fields: ``pinocchio`` (the node's ``pinocchio.Data``), ``frame``, ``type``, ``joint`` (parent joint),
    ``jMf``/``fXj`` (frame placement in its joint and its inverse action matrix), ``Jc (nc, nv)``,
    ``f``/``f_local``/``fext`` (``pinocchio.Force``: force coordinates, local frame, parent joint),
    ``df_dx (nc, ndx)``, ``df_du (nc, nu)``, ``fJf (6, nv)`` (LOCAL frame Jacobian), ``dtau_dq (nv, nv)``
    and ``v_partial_dq (6, nv)``; ``force_rows`` (crocopy's): the components of ``f.vector`` that the ``nc``
    force rows are (``0..nc-1`` here; ``(2,)`` for a 1D contact, ``(0, 2)`` for a 2D one).
    """

    force_rows: tuple[int, ...] = ()

    def __init__(self, model: ForceModelAbstract, data: pin.Data) -> None:
        nc, nv, ndx = model.nc, model.state.nv, model.state.ndx
        frame = model.state.pinocchio.frames[model.id]
        self.pinocchio = data
        self.frame = model.id
        self.type = model.type
        self.joint = int(frame.parentJoint)
        self.jMf = frame.placement.copy()
        self.fXj = self.jMf.inverse().toActionMatrix()
        self.Jc = np.zeros((nc, nv))
        self.f = pin.Force.Zero()
        self.f_local = pin.Force.Zero()
        self.fext = pin.Force.Zero()
        self.df_dx = np.zeros((nc, ndx))
        self.df_du = np.zeros((nc, model.nu))
        self.fJf = np.zeros((6, nv))
        self.dtau_dq = np.zeros((nv, nv))
        self.v_partial_dq = np.zeros((6, nv))
        self.force_rows = self.force_rows or tuple(range(nc))

    def contact_jacobian(self, J: np.ndarray, R: np.ndarray) -> np.ndarray:
        """``Jc (nc, nv)`` from the LOCAL frame Jacobian ``J (6, nv)`` and the frame rotation ``R``."""
        nc = self.Jc.shape[0]
        if self.type == _LOCAL:
            return J[:nc]
        return np.vstack([R @ J[:3], R @ J[3:]])[:nc]


class ForceModelMultiple(ModelItems, Guarded):
    """Bookkeeping of ``ContactModelMultiple``/``ImpulseModelMultiple``: named forces of one robot.

    ``_kind`` (``"contact"``/``"impulse"``) names the items; an item holds its model under that
    attribute.  ``_active``/``_inactive`` list ``(name, model)`` in name order, ``_lwa`` the active
    ones in LOCAL_WORLD_ALIGNED coordinates.
    """

    _model_type: type = ForceModelAbstract
    _guards = point_guards()
    _check_state = staticmethod(check_state_multibody)

    def _state_mismatch(self, state: StateAbstract) -> str | None:
        mine = self.state
        if state.pinocchio is not mine.pinocchio and (
            state.nx != mine.nx or state.pinocchio.nframes != mine.pinocchio.nframes
        ):
            return "the model of another robot"
        return None

    def _recount(self) -> None:
        kind = self._kind
        models = [(name, getattr(item, kind), item.active) for name, item in self._items.items()]
        self.nc = sum(m.nc for _, m, active in models if active)
        self.nc_total = sum(m.nc for _, m, _ in models)
        self._active = [(name, m) for name, m, active in models if active]
        self._inactive = [(name, m) for name, m, active in models if not active]
        self._lwa = [(name, m) for name, m in self._active if m.type != _LOCAL]
        frames = self.state.pinocchio.frames
        joints = [int(frames[m.id].parentJoint) for _, m in self._active]
        self._shared_joints = len(set(joints)) != len(joints)
        self._idle_joints = sorted({int(frames[m.id].parentJoint) for _, m in self._inactive} - set(joints))

    def _add(self, name: str, model: ForceModelAbstract, item: object) -> None:
        """Insert ``item`` (holding ``model``) under ``name`` once ``_check_model`` accepts ``model``."""
        self._check_model(name, model)
        self._insert(name, item)

    def _stack(self, datas: dict, x: np.ndarray, diff: bool, fields: tuple) -> None:
        """Evaluate the active items (``calc``, or ``calcDiff`` if ``diff``) and copy each one's
        ``(stacked, name)`` fields into its rows of ``stacked``."""
        i = 0
        for name, m in self._active:
            md = datas[name]
            if diff:
                m.calcDiff(md, x)
            else:
                m.calc(md, x)
            for stacked, field in fields:
                stacked[i:i + m.nc] = getattr(md, field)
            i += m.nc

    def _split(self, datas: dict, method: str, blocks: tuple, zero: str) -> None:
        """Hand each active item its rows of the one or two arrays in ``blocks`` through ``method``; call
        ``zero`` on the inactive ones."""
        i = 0
        first, second = blocks if len(blocks) == 2 else (blocks[0], None)
        for name, m in self._active:
            j = i + m.nc
            if second is None:
                getattr(m, method)(datas[name], first[i:j])
            else:
                getattr(m, method)(datas[name], first[i:j], second[i:j])
            i = j
        for name, m in self._inactive:
            getattr(m, zero)(datas[name])

    def _store_forces(self, data: "ForceDataMultiple", force: np.ndarray) -> None:
        """Hand each active item its rows of ``force (nc,)`` (``storeForce``), zero the inactive ones; the
        joint forces wait for :meth:`updateJointForces` (when ``data.fext`` is read)."""
        if getattr(force, "shape", None) != (self.nc,):
            force = np.asarray(force, dtype=float)
            if force.shape != (self.nc,):
                raise ValueError(f"force has shape {force.shape}, expected ({self.nc},)")
        self._split(data.items, "storeForce", (force,), "setZeroForce")
        data.joint_forces_pending = True

    def updateJointForces(self, data: "ForceDataMultiple") -> None:
        """Refresh every active item's ``f_local``/``fext`` and the per-joint sums ``data.fext``.

        ``updateForce`` defers this work until ``data.fext`` is read.
        """
        fext, shared = data.fext_by_joint, self._shared_joints
        for j in data.touched if shared else self._idle_joints:
            fext[j] = data.zero_force
        datas = data.items
        for name, m in self._active:
            md = datas[name]
            m.updateJointForce(md)
            fext[md.joint] = fext[md.joint] + md.fext if shared else md.fext
        data.joint_forces_pending = False

    def updateRneaDiff(self, data: "ForceDataMultiple", pinocchio: pin.Data) -> None:
        """Add to ``pinocchio.dtau_dq`` the terms of the forces not expressed in local coordinates."""
        if self._lwa:
            datas, dtau_dq = data.items, pinocchio.dtau_dq
            for name, m in self._lwa:
                m.addRneaDiff(datas[name], dtau_dq)

    def __repr__(self) -> str:
        kind = self._kind
        inner = ", ".join(f"{name}: {getattr(item, kind)!r}" for name, item in self._items.items())
        return f"{type(self).__name__}({inner})"


class ForceDataMultiple:
    """Data of a :class:`ForceModelMultiple`: ``items`` (name → data, also under Crocoddyl's name
    ``contacts``/``impulses``), ``Jc (nc_total, nv)``, one ``pinocchio.Force`` per joint in
    ``fext_by_joint``, and ``touched`` (the joints some item acts on)."""

    def __init__(self, model: ForceModelMultiple, data: pin.Data) -> None:
        made_from(model, self)
        kind = model._kind
        self.items: dict[str, ForceDataAbstract] = {
            name: getattr(item, kind).createData(data) for name, item in model._items.items()
        }
        self.Jc = np.zeros((model.nc_total, model.state.nv))
        self.fext_by_joint = pin.StdVec_Force()
        for _ in range(model.state.pinocchio.njoints):
            self.fext_by_joint.append(pin.Force.Zero())
        self.zero_force = pin.Force.Zero()
        self.touched = sorted({md.joint for md in self.items.values()})
        self.joint_forces_pending = False
        self._model = model

    @property
    def fext(self) -> pin.StdVec_Force:
        """External force at each joint (``njoints`` ``pinocchio.Force``, the same object every time),
        brought up to date with the forces when read."""
        if self.joint_forces_pending:
            self._model.updateJointForces(self)
        return self.fext_by_joint
