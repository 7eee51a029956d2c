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
from crocopy.validation import check_finite

from .cones import CoPSupport, FrictionCone, WrenchCone
from .force_base import frame_id


def _force_data(shared: DataCollectorAbstract | None, fid: int, name: str, nc: int):
    """The contact/impulse data on frame ``fid`` in the collector (``ValueError`` if there is none)."""
    group = getattr(shared, "contacts", None)
    items = getattr(group, "contacts", None)
    if items is None:
        group = getattr(shared, "impulses", None)
        items = getattr(group, "impulses", None)
    if items is None:
        raise ValueError(f"{name} needs a data collector with contacts or impulses, got {type(shared).__name__}")
    for cd in items.values():
        if cd.frame == fid:
            if cd.Jc.shape[0] < nc:
                raise ValueError(f"{name}: the contact on frame {fid} has dimension {cd.Jc.shape[0]} < nc = {nc}")
            return cd
    raise ValueError(f"{name}: no contact or impulse on frame {fid} in the data collector")


class _ForceResidual(ResidualModelAbstract):
    """Residual ``r = A f[:ncf] + b`` of the force of the contact on frame ``id``."""

    ncf = 3

    def __init__(self, state: StateAbstract, id: int | str, nr: int, nu: int | None, fwddyn: bool) -> None:
        fid = frame_id(state, id)
        super().__init__(state, nr, nu, True, True, True)
        self.id = fid
        self.fwddyn = bool(fwddyn)

    def createData(self, data: DataCollectorAbstract | None = None) -> "ResidualDataContactForce":
        return ResidualDataContactForce(self, data)

    def _matrix(self) -> np.ndarray:
        raise NotImplementedError

    def calc(self, data: "ResidualDataContactForce", x: np.ndarray, u: np.ndarray | None = None) -> None:
        f = data.contact.f.vector[: self.ncf]
        np.dot(self._matrix(), f, out=data.r)

    def calcDiff(self, data: "ResidualDataContactForce", x: np.ndarray, u: np.ndarray | None = None) -> None:
        A, cd = self._matrix(), data.contact
        np.dot(A, cd.df_dx[: self.ncf], out=data.Rx)
        if data.Ru.shape[1] and cd.df_du.shape[1] == data.Ru.shape[1]:
            np.dot(A, cd.df_du[: self.ncf], out=data.Ru)


class ResidualDataContactForce(ResidualDataAbstract):
    """Residual data with ``contact`` (the contact or impulse data on the residual's frame)."""

    def __init__(self, model: _ForceResidual, data: DataCollectorAbstract | None) -> None:
        super().__init__(model, data)
        self.contact = _force_data(data, model.id, type(model).__name__, model.ncf)
        self.impulses = getattr(data, "impulses", None)


class ResidualModelContactForce(_ForceResidual):
    """Crocoddyl's ``ResidualModelContactForce(state, id, fref, nc, nu=state.nv, fwddyn=True)``.

    Parameters
    ----------
    fref : pinocchio.Force
        Reference force in the contact coordinates.
    nc : int
        3 (linear force) or 6 (wrench).
    """

    def __init__(
        self, state: StateAbstract, id: int | str, fref: pin.Force, nc: int, nu: int | None = None, fwddyn: bool = True
    ) -> None:
        if nc not in (3, 6):
            raise ValueError(f"nc must be 3 or 6, got {nc}")
        self.ncf = int(nc)
        super().__init__(state, id, self.ncf, nu, fwddyn)
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
        self._fref_vec = value.vector[: self.ncf].copy()

    def calc(self, data: ResidualDataContactForce, x: np.ndarray, u: np.ndarray | None = None) -> None:
        if u is None and data.impulses is None:  # terminal node of contact dynamics: no force, as Crocoddyl
            data.r[:] = 0.0
            return
        np.subtract(data.contact.f.vector[: self.ncf], self._fref_vec, out=data.r)

    def calcDiff(self, data: ResidualDataContactForce, x: np.ndarray, u: np.ndarray | None = None) -> None:
        cd = data.contact
        data.Rx[:] = cd.df_dx[: self.ncf]
        if data.Ru.shape[1] and cd.df_du.shape[1] == data.Ru.shape[1]:
            data.Ru[:] = cd.df_du[: self.ncf]


class ResidualModelContactFrictionCone(_ForceResidual):
    """Crocoddyl's ``ResidualModelContactFrictionCone(state, id, fref, nu=state.nv, fwddyn=True)``
    with ``fref`` a :class:`FrictionCone`; ``r = A f`` (``nf + 1``)."""

    def __init__(
        self, state: StateAbstract, id: int | str, fref: FrictionCone, nu: int | None = None, fwddyn: bool = True
    ) -> None:
        if not isinstance(fref, FrictionCone):
            raise ValueError(f"fref must be a FrictionCone, got {type(fref).__name__}")
        super().__init__(state, id, fref.nf + 1, nu, fwddyn)
        self.reference = fref

    def _matrix(self) -> np.ndarray:
        return self.reference.A


class ResidualModelContactWrenchCone(_ForceResidual):
    """Crocoddyl's ``ResidualModelContactWrenchCone(state, id, fref, nu=state.nv, fwddyn=True)``
    with ``fref`` a :class:`WrenchCone`; ``r = A f`` (``nf + 13``, 6D contacts)."""

    ncf = 6

    def __init__(
        self, state: StateAbstract, id: int | str, fref: WrenchCone, nu: int | None = None, fwddyn: bool = True
    ) -> None:
        if not isinstance(fref, WrenchCone):
            raise ValueError(f"fref must be a WrenchCone, got {type(fref).__name__}")
        super().__init__(state, id, fref.nf + 13, nu, fwddyn)
        self.reference = fref

    def _matrix(self) -> np.ndarray:
        return self.reference.A


class ResidualModelContactCoPPosition(_ForceResidual):
    """Crocoddyl's ``ResidualModelContactCoPPosition(state, id, cref, nu=state.nv, fwddyn=True)``
    with ``cref`` a :class:`CoPSupport`; ``r = A f`` (4, 6D contacts)."""

    ncf = 6

    def __init__(
        self, state: StateAbstract, id: int | str, cref: CoPSupport, nu: int | None = None, fwddyn: bool = True
    ) -> None:
        if not isinstance(cref, CoPSupport):
            raise ValueError(f"cref must be a CoPSupport, got {type(cref).__name__}")
        super().__init__(state, id, 4, nu, fwddyn)
        self.reference = cref

    def createData(self, data: DataCollectorAbstract | None = None) -> "ResidualDataContactCoPPosition":
        return ResidualDataContactCoPPosition(self, data)

    def _matrix(self) -> np.ndarray:
        return self.reference.A


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
            nc = cd.df_dx.shape[0]
            J = pin.getFrameJacobian(model, pdi, cd.frame, pin.LOCAL)
            if cd.type == pin.LOCAL:
                Jc = J[:nc]
            else:
                R = (pdi.oMi[cd.joint] * cd.jMf).rotation
                Jc = np.vstack([R @ J[:3], R @ J[3:]])[:nc]
                turn = J[:3].T @ pin.skew(cd.f_local.linear)
                if nc == 6:
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
