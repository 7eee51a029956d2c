"""Residuals on contact forces and impulses, read from the node's data collector.

The contact (or impulse) on frame ``id`` is looked up in ``shared.contacts.contacts`` (contact
dynamics) or ``shared.impulses.impulses`` (impulse dynamics) when the residual data is created.
Its force ``f`` is in the contact's coordinates (``LOCAL`` or ``LOCAL_WORLD_ALIGNED``), with the
Jacobians ``df_dx``/``df_du`` that the action model writes when ``enable_force=True``.

- ``ResidualModelContactForce``:        ``r = (f - fref)[:nc]``, ``Rx = df_dx``, ``Ru = df_du`` (``r = 0`` on
  the terminal node of contact dynamics, which has no force; the other force residuals vanish there
  because the action model zeroes the forces).
- ``ResidualModelContactFrictionCone``: ``r = A f_linear`` (``nf + 1``).
- ``ResidualModelContactWrenchCone``:   ``r = A f`` (``nf + 13``).
- ``ResidualModelContactCoPPosition``:  ``r = A f`` (4).
- ``ResidualModelContactControlGrav``:  ``r = τ - (g(q) - Σ Jcᵀ f)`` (``nv``, ``rnea(q, 0, 0, fext)`` in
  brackets); the forces move with ``x`` and ``u``: ``Rx = ∂τ/∂x - (∂rnea/∂q|f, 0) + Σ Jcᵀ df_dx``,
  ``Ru = ∂τ/∂u + Σ Jcᵀ df_du`` (``Jc`` in each contact's coordinates; ``∂rnea/∂q|f`` holds ``f``
  fixed in those coordinates, which for ``LOCAL_WORLD_ALIGNED`` adds ``-Jlᵀ[f_l]×Ja`` (+ ``-Jaᵀ[f_a]×Ja``
  for 6D contacts) to Pinocchio's joint-frame derivative).
- ``ResidualModelImpulseCoM``:          ``r = Jcom(q) (v⁺ - v)`` (3), the CoM velocity jump.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from crocopy.data_collector import DataCollectorAbstract
from crocopy.residuals.base import ResidualDataAbstract, ResidualModelAbstract
from crocopy.state import StateAbstract
from crocopy.validation import as_bool, as_optional_count, check_finite

from .cones import CoPSupport, FrictionCone, WrenchCone
from .force_base import frame_id


def _force_data(shared: DataCollectorAbstract | None, fid: int, name: str, nc: int, exact: bool = False):
    """The contact/impulse data on frame ``fid`` in the collector, of dimension at least ``nc`` (exactly
    ``nc`` if ``exact``); ``ValueError`` if there is none."""
    group = getattr(shared, "contacts", None)
    items = getattr(group, "contacts", None)
    if items is None:
        group = getattr(shared, "impulses", None)
        items = getattr(group, "impulses", None)
    if items is None:
        raise ValueError(f"{name} needs a data collector with contacts or impulses, got {type(shared).__name__}")
    for cd in items.values():
        if cd.frame == fid:
            size = cd.Jc.shape[0]
            if size < nc or (exact and size != nc):
                expected = f"= {nc}" if exact else f">= {nc}"
                raise ValueError(f"{name}: the contact on frame {fid} has dimension {size}, expected {expected}")
            return cd
    raise ValueError(f"{name}: no contact or impulse on frame {fid} in the data collector")


def _force_blocks(cd, ncf: int) -> tuple:
    """``(cols, rows)``: the components ``cols`` of ``f[:ncf]`` that the contact's force rows ``rows`` are
    (slices when they are the first ``ncf`` of both, as for 3D and 6D contacts)."""
    pairs = [(c, i) for i, c in enumerate(cd.force_rows) if c < ncf]
    if [c for c, _ in pairs] == list(range(ncf)) and [i for _, i in pairs] == list(range(ncf)):
        return slice(0, ncf), slice(0, ncf)
    return np.array([c for c, _ in pairs]), np.array([i for _, i in pairs])


class _ForceResidual(ResidualModelAbstract):
    """Residual ``r = A f[:ncf]`` (``A = reference.A``) of the force of the contact on frame ``id`` (a
    contact of dimension at least ``min_nc``; a 1D or 2D contact fills only some components of ``f``, its
    ``force_rows``)."""

    ncf = 3
    min_nc = 3

    def __init__(self, state: StateAbstract, id: int | str, nr: int, nu: int | None, fwddyn: bool) -> None:
        fid = frame_id(state, id)
        super().__init__(state, nr, as_optional_count(nu, "nu"), True, True, True)
        self.id = fid
        self.fwddyn = as_bool(fwddyn, "fwddyn")

    def createData(self, data: DataCollectorAbstract | None = None) -> "ResidualDataContactForce":
        return ResidualDataContactForce(self, data)

    def calc(self, data: "ResidualDataContactForce", x: np.ndarray, u: np.ndarray | None = None) -> None:
        """``r = A f[:ncf]`` with ``A = reference.A`` (the cone's matrix)."""
        np.dot(self.reference.A, data.contact.f.vector[: self.ncf], out=data.r)

    def calcDiff(self, data: "ResidualDataContactForce", x: np.ndarray, u: np.ndarray | None = None) -> None:
        cd, rows = data.contact, data.rows
        A = self.reference.A if data.all_cols else self.reference.A[:, data.cols]
        np.dot(A, cd.df_dx[rows], out=data.Rx)
        if data.Ru.shape[1] and cd.df_du.shape[1] == data.Ru.shape[1]:
            np.dot(A, cd.df_du[rows], out=data.Ru)


class ResidualDataContactForce(ResidualDataAbstract):
    """Residual data with ``contact`` (the contact or impulse data on the residual's frame) and, from
    its ``force_rows``, the components ``cols`` of ``f[:ncf]`` that its force rows ``rows`` are."""

    def __init__(self, model: _ForceResidual, data: DataCollectorAbstract | None) -> None:
        super().__init__(model, data)
        self.contact = _force_data(data, model.id, type(model).__name__, model.min_nc, model.min_nc == 1)
        self.cols, self.rows = _force_blocks(self.contact, model.ncf)
        self.all_cols = isinstance(self.cols, slice) and self.cols == slice(0, model.ncf)
        self.impulses = getattr(data, "impulses", None)


class ResidualDataContactFrictionCone(ResidualDataContactForce):
    """Data of :class:`ResidualModelContactFrictionCone` (the fields of :class:`ResidualDataContactForce`)."""


class ResidualDataContactWrenchCone(ResidualDataContactForce):
    """Data of :class:`ResidualModelContactWrenchCone` (the fields of :class:`ResidualDataContactForce`)."""


class ResidualModelContactForce(_ForceResidual):
    """Crocoddyl's ``ResidualModelContactForce(state, id, fref, nc, nu=state.nv, fwddyn=True)``.

    Compiled nodes evaluate it as ``r = A f - fref`` (kind ``"force"``: ``A`` the rows of ``I`` that select its
    components, as a cone's matrix, then ``fref``; 0 at a terminal node).

    Parameters
    ----------
    fref : pinocchio.Force
        Reference force in the contact coordinates.
    nc : int
        3 (linear force of a 3D or 6D contact), 6 (wrench of a 6D contact) or 1 (the force of a 1D
        contact, which it stores as the z component: ``r = f_z - fref_z``, as Crocoddyl).
    """

    def __init__(
        self, state: StateAbstract, id: int | str, fref: pin.Force, nc: int, nu: int | None = None, fwddyn: bool = True
    ) -> None:
        if nc not in (1, 3, 6):
            raise ValueError(f"nc must be 1, 3 or 6, got {nc}")
        self.min_nc = int(nc)
        self.ncf = 3 if nc == 1 else int(nc)
        self._components = slice(2, 3) if nc == 1 else slice(0, self.ncf)
        super().__init__(state, id, self.min_nc, nu, fwddyn)
        self.reference = fref

    @property
    def reference(self) -> pin.Force:
        """Reference force ``fref``."""
        return self._fref

    @reference.setter
    def reference(self, value: pin.Force) -> None:
        if not isinstance(value, pin.Force):
            raise ValueError(f"fref must be a pinocchio.Force, got {type(value).__name__}")
        check_finite(value.vector, "fref")
        self._fref = value.copy()
        self._fref_vec = value.vector[self._components].copy()

    compiled_kind = "force"
    """The kind compiled nodes evaluate this class as (:mod:`crocopy.models.rbd.residual_kernel`)."""

    def compiled_parameters(self) -> np.ndarray:
        """The parameters compiled nodes read: the selection ``A (nr, ncf)`` row-major, then ``fref``'s components."""
        return np.concatenate([np.eye(self.ncf)[self._components].reshape(-1), self._fref_vec])

    def calc(self, data: ResidualDataContactForce, x: np.ndarray, u: np.ndarray | None = None) -> None:
        if u is None and data.impulses is None:  # terminal node of contact dynamics: no force, as Crocoddyl
            data.r[:] = 0.0
            return
        np.subtract(data.contact.f.vector[self._components], self._fref_vec, out=data.r)

    def calcDiff(self, data: ResidualDataContactForce, x: np.ndarray, u: np.ndarray | None = None) -> None:
        cd, nr = data.contact, self.nr
        data.Rx[:] = cd.df_dx[:nr]
        if data.Ru.shape[1] and cd.df_du.shape[1] == data.Ru.shape[1]:
            data.Ru[:] = cd.df_du[:nr]


class ResidualModelContactFrictionCone(_ForceResidual):
    """Crocoddyl's ``ResidualModelContactFrictionCone(state, id, fref, nu=state.nv, fwddyn=True)``
    with ``fref`` a :class:`FrictionCone`; ``r = A f_linear`` (``nf + 1``; a contact of dimension 2 or more)."""

    compiled_kind = "cone"
    """The kind compiled nodes evaluate this class as (:mod:`crocopy.models.rbd.euler_node_kernel`)."""

    def compiled_parameters(self) -> np.ndarray:
        """The parameters compiled nodes read: the cone matrix ``A`` row-major."""
        return np.asarray(self.reference.A, dtype=float).reshape(-1)


    min_nc = 2

    def createData(self, data: DataCollectorAbstract | None = None) -> "ResidualDataContactFrictionCone":
        return ResidualDataContactFrictionCone(self, data)

    def __init__(
        self, state: StateAbstract, id: int | str, fref: FrictionCone, nu: int | None = None, fwddyn: bool = True
    ) -> None:
        if not isinstance(fref, FrictionCone):
            raise ValueError(f"fref must be a FrictionCone, got {type(fref).__name__}")
        super().__init__(state, id, fref.nf + 1, nu, fwddyn)
        self.reference = fref


class ResidualModelContactWrenchCone(_ForceResidual):
    """Crocoddyl's ``ResidualModelContactWrenchCone(state, id, fref, nu=state.nv, fwddyn=True)``
    with ``fref`` a :class:`WrenchCone`; ``r = A f`` (``nf + 13``, 6D contacts)."""

    compiled_kind = "cone"
    """The kind compiled nodes evaluate this class as (:mod:`crocopy.models.rbd.euler_node_kernel`)."""

    def compiled_parameters(self) -> np.ndarray:
        """The parameters compiled nodes read: the cone matrix ``A`` row-major."""
        return np.asarray(self.reference.A, dtype=float).reshape(-1)


    ncf = min_nc = 6

    def createData(self, data: DataCollectorAbstract | None = None) -> "ResidualDataContactWrenchCone":
        return ResidualDataContactWrenchCone(self, data)

    def __init__(
        self, state: StateAbstract, id: int | str, fref: WrenchCone, nu: int | None = None, fwddyn: bool = True
    ) -> None:
        if not isinstance(fref, WrenchCone):
            raise ValueError(f"fref must be a WrenchCone, got {type(fref).__name__}")
        super().__init__(state, id, fref.nf + 13, nu, fwddyn)
        self.reference = fref


class ResidualModelContactCoPPosition(_ForceResidual):
    """Crocoddyl's ``ResidualModelContactCoPPosition(state, id, cref, nu=state.nv, fwddyn=True)``
    with ``cref`` a :class:`CoPSupport`; ``r = A f`` (4, 6D contacts)."""

    compiled_kind = "cone"
    """The kind compiled nodes evaluate this class as (``r = A f``, as the cones:
    :mod:`crocopy.models.rbd.residual_kernel`)."""

    def compiled_parameters(self) -> np.ndarray:
        """The parameters compiled nodes read: the support's matrix ``A`` row-major."""
        return np.asarray(self.reference.A, dtype=float).reshape(-1)

    ncf = min_nc = 6

    def __init__(
        self, state: StateAbstract, id: int | str, cref: CoPSupport, nu: int | None = None, fwddyn: bool = True
    ) -> None:
        if not isinstance(cref, CoPSupport):
            raise ValueError(f"cref must be a CoPSupport, got {type(cref).__name__}")
        super().__init__(state, id, 4, nu, fwddyn)
        self.reference = cref

    def createData(self, data: DataCollectorAbstract | None = None) -> "ResidualDataContactCoPPosition":
        return ResidualDataContactCoPPosition(self, data)


class ResidualDataContactCoPPosition(ResidualDataContactForce):
    """Data of :class:`ResidualModelContactCoPPosition`: ``contact`` (the 6D contact or impulse data
    on the residual's frame) and ``pinocchio`` (the node's Pinocchio data)."""

    def __init__(self, model: ResidualModelContactCoPPosition, data: DataCollectorAbstract | None) -> None:
        super().__init__(model, data)
        self.pinocchio = self.contact.pinocchio


class ResidualModelContactControlGrav(ResidualModelAbstract):
    """Crocoddyl's ``ResidualModelContactControlGrav(state, nu=state.nv)``: ``r = τ - rnea(q, 0, 0, fext)``.

    Reads ``shared.actuation`` (``tau``, ``dtau_dx``, ``dtau_du``) and ``shared.contacts.fext``.
    """

    compiled_kind = "contact_control_grav"
    """The kind compiled contact-dynamics nodes evaluate this class as (:mod:`crocopy.models.rbd.residual_kernel`)."""

    def compiled_parameters(self) -> np.ndarray:
        """The parameters compiled nodes read: none."""
        return np.zeros(0)

    def __init__(self, state: StateAbstract, nu: int | None = None) -> None:
        if not isinstance(getattr(state, "pinocchio", None), pin.Model):
            raise ValueError(f"state must be a StateMultibody, got {type(state).__name__}")
        super().__init__(state, state.nv, nu, True, False, True)

    def createData(self, data: DataCollectorAbstract | None = None) -> "ResidualDataContactControlGrav":
        return ResidualDataContactControlGrav(self, data)

    def calc(self, data: "ResidualDataContactControlGrav", x: np.ndarray, u: np.ndarray | None = None) -> None:
        q = x[: self.state.nq]
        model = self.state.pinocchio
        st = pin.computeStaticTorque(model, data.pinocchio, q, data.contacts.fext)
        if u is None:
            np.negative(st, out=data.r)
        else:
            np.subtract(data.actuation.tau, st, out=data.r)

    def calcDiff(self, data: "ResidualDataContactControlGrav", x: np.ndarray, u: np.ndarray | None = None) -> None:
        nq, nv = self.state.nq, self.state.nv
        dst = pin.computeStaticTorqueDerivatives(self.state.pinocchio, data.pinocchio, x[:nq], data.contacts.fext)
        if u is None:
            np.negative(dst, out=data.Rx[:, :nv])
            return
        act = data.actuation
        np.subtract(act.dtau_dx[:, :nv], dst, out=data.Rx[:, :nv])
        data.Rx[:, nv:] = act.dtau_dx[:, nv:]
        data.Ru[:] = act.dtau_du
        self._add_force_terms(data, x[:nq])

    def _add_force_terms(self, data: "ResidualDataContactControlGrav", q: np.ndarray) -> None:
        """``Rx += Σ Jcᵀ df_dx`` (plus the rotation term of world-aligned forces), ``Ru += Σ Jcᵀ df_du``."""
        model, pdi, nv = self.state.pinocchio, data.pinocchio, self.state.nv
        pin.computeJointJacobians(model, pdi, q)
        for cd in data.contacts.contacts.values():
            J = pin.getFrameJacobian(model, pdi, cd.frame, pin.LOCAL)
            R = (pdi.oMi[cd.joint] * cd.jMf).rotation
            Jc = cd.contact_jacobian(J, R)
            if cd.type != pin.LOCAL:
                turn = J[:3].T @ pin.skew(cd.f_local.linear)
                if cd.Jc.shape[0] == 6:
                    turn += J[3:].T @ pin.skew(cd.f_local.angular)
                data.Rx[:, :nv] += turn @ J[3:]
            data.Rx += Jc.T @ cd.df_dx
            data.Ru += Jc.T @ cd.df_du


class ResidualDataContactControlGrav(ResidualDataAbstract):
    """Data of :class:`ResidualModelContactControlGrav`: a private ``pinocchio`` data, ``actuation``, ``contacts``."""

    def __init__(self, model: ResidualModelContactControlGrav, data: DataCollectorAbstract | None) -> None:
        super().__init__(model, data)
        self.actuation = getattr(data, "actuation", None)
        contacts = getattr(data, "contacts", None)
        if self.actuation is None or contacts is None:
            raise ValueError(
                f"ResidualModelContactControlGrav needs a data collector with actuation and contacts, "
                f"got {type(data).__name__}"
            )
        self.contacts = contacts
        self.pinocchio = model.state.pinocchio.createData()


class ResidualModelImpulseCoM(ResidualModelAbstract):
    """Crocoddyl's ``ResidualModelImpulseCoM(state)``: ``r = Jcom(q) (v⁺ - v)`` (``nu = 0``).

    ``Rx = (∂(Jcom Δv)/∂q|Δv + Jcom ∂v⁺/∂q, Jcom (∂v⁺/∂v - I))``, with ``∂v⁺/∂x`` read from
    ``shared.impulses.dvnext_dx``.
    """

    compiled_kind = "impulse_com"
    """The kind compiled impulse nodes evaluate this class as (:mod:`crocopy.models.rbd.residual_kernel`)."""

    def compiled_parameters(self) -> np.ndarray:
        """The parameters compiled nodes read: none."""
        return np.zeros(0)

    def __init__(self, state: StateAbstract) -> None:
        if not isinstance(getattr(state, "pinocchio", None), pin.Model):
            raise ValueError(f"state must be a StateMultibody, got {type(state).__name__}")
        super().__init__(state, 3, 0, True, True, False)

    def createData(self, data: DataCollectorAbstract | None = None) -> "ResidualDataImpulseCoM":
        return ResidualDataImpulseCoM(self, data)

    def calc(self, data: "ResidualDataImpulseCoM", x: np.ndarray, u: np.ndarray | None = None) -> None:
        nq = self.state.nq
        model, pdi = self.state.pinocchio, data.pinocchio_internal
        np.subtract(data.impulses.vnext, x[nq:], out=data.dv)
        data.Jcom[:] = pin.jacobianCenterOfMass(model, pdi, x[:nq])
        np.dot(data.Jcom, data.dv, out=data.r)

    def calcDiff(self, data: "ResidualDataImpulseCoM", x: np.ndarray, u: np.ndarray | None = None) -> None:
        nq, nv = self.state.nq, self.state.nv
        model, pdi = self.state.pinocchio, data.pinocchio_internal
        pin.centerOfMass(model, pdi, x[:nq], data.dv)
        data.dvc_dq[:] = pin.getCenterOfMassVelocityDerivatives(model, pdi)
        np.dot(data.Jcom, data.impulses.dvnext_dx, out=data.Rx)
        data.Rx[:, :nv] += data.dvc_dq
        data.Rx[:, nv:] -= data.Jcom


class ResidualDataImpulseCoM(ResidualDataAbstract):
    """Data of :class:`ResidualModelImpulseCoM`: ``impulses``, ``pinocchio_internal``, ``Jcom``, ``dvc_dq``."""

    def __init__(self, model: ResidualModelImpulseCoM, data: DataCollectorAbstract | None) -> None:
        super().__init__(model, data)
        self.impulses = getattr(data, "impulses", None)
        if self.impulses is None or not hasattr(self.impulses, "vnext"):
            raise ValueError(f"ResidualModelImpulseCoM needs an impulse data collector, got {type(data).__name__}")
        nv = model.state.nv
        self.pinocchio = getattr(data, "pinocchio", None)
        self.pinocchio_internal = model.state.pinocchio.createData()
        self.Jcom = np.zeros((3, nv))
        self.dvc_dq = np.zeros((3, nv))
        self.dv = np.zeros(nv)
