"""The equality residuals of the inverse-dynamics action models (Crocoddyl's nested classes).

Under inverse dynamics the control is ``u = (a, f)``: the joint acceleration ``a (nv,)`` then the
forces of every contact (``nc_total`` rows, contacts in name order; no forces in the free case).
The action model computes the generalized torques with Pinocchio's RNEA,

    τ(x, u) = M(q) a + b(q, v) - Σ Jcᵢ(q)ᵀ fᵢ     (active contacts only),

into the node's ``pinocchio.Data`` (``tau``; after ``calcDiff`` also ``dtau_dq``, ``dtau_dv`` and
``M``), and these residuals read them from the data collector:

- ``ResidualModelActuation``: ``r = τ[~tau_set]`` (``nv - na`` rows), the torques the actuation
  cannot produce (``tau_set`` comes from the actuation data), with ``Rx = (∂τ/∂q, ∂τ/∂v)[~tau_set]``
  and ``Ru = (M, -Jc₁ᵀ, ..., -Jcₖᵀ)[~tau_set]`` (zero columns for the inactive contacts' forces).
  :class:`ResidualModelActuationFree` is ``DifferentialActionModelFreeInvDynamics.ResidualModelActuation``
  (``nu = nv``), :class:`ResidualModelActuationContact`
  ``DifferentialActionModelContactInvDynamics.ResidualModelActuation`` (``nu = nv + nc``).
- ``ResidualModelContact``: ``r = a0`` of the contact on frame ``id``, the contact acceleration
  ``Jc a + a0(x)`` (Baumgarte terms included) computed by the contact at the node's acceleration;
  ``Rx = da0_dx``, ``Ru = (Jc, 0)``.
"""

from __future__ import annotations

import numpy as np

from crocopy.data_collector import DataCollectorAbstract
from crocopy.residuals.base import ResidualDataAbstract, ResidualModelAbstract

from .force_base import frame_id
from .residuals_frame import check_state, shared_pinocchio
from .state_multibody import StateMultibody


def _unactuated(shared: DataCollectorAbstract | None, nr: int, name: str) -> np.ndarray:
    """Indices of the rows of ``τ`` the actuation cannot set (from ``shared.actuation.tau_set``)."""
    actuation = getattr(shared, "actuation", None)
    if actuation is None:
        raise ValueError(f"{name} needs a data collector with actuation data, got {type(shared).__name__}")
    rows = np.flatnonzero(~np.asarray(actuation.tau_set, dtype=bool))
    if rows.size != nr:
        raise ValueError(f"{name}: the actuation leaves {rows.size} torques unset, the residual has nr = {nr}")
    return rows


def contact_layout(contacts) -> list[tuple[str, int, int, bool]]:
    """``(name, offset, nc, active)`` of every contact of a ``ContactModelMultiple`` in name order;
    ``offset`` is the first row of its force in ``u[nv:]``."""
    out, offset = [], 0
    for name, item in contacts.contacts.items():
        out.append((name, offset, item.contact.nc, bool(item.active)))
        offset += item.contact.nc
    return out


class _ResidualModelActuation(ResidualModelAbstract):
    """``r = τ[~tau_set]`` read from the node's ``pinocchio.Data`` (see the module docstring)."""

    def __init__(self, state: StateMultibody, nu: int, nc: int) -> None:
        state = check_state(state)
        na, nc = int(nu), int(nc)
        if not 0 <= na <= state.nv:
            raise ValueError(f"nu (the actuation dimension) must be in [0, {state.nv}], got {nu}")
        if nc < 0:
            raise ValueError(f"nc must be non-negative, got {nc}")
        super().__init__(state, state.nv - na, state.nv + nc, True, True, True)
        self.na = na
        self.nc = nc

    def createData(self, data: DataCollectorAbstract | None = None) -> "ResidualDataActuation":
        return ResidualDataActuation(self, data)

    def calc(self, data: "ResidualDataActuation", x: np.ndarray, u: np.ndarray | None = None) -> None:
        data.r[:] = data.pinocchio.tau[data.rows]

    def calcDiff(self, data: "ResidualDataActuation", x: np.ndarray, u: np.ndarray | None = None) -> None:
        nv, pd, rows = self.state.nv, data.pinocchio, data.rows
        data.Rx[:, :nv] = pd.dtau_dq[rows]
        data.Rx[:, nv:] = pd.dtau_dv[rows]
        data.Ru[:, :nv] = pd.M[rows]
        if data.contact is None:
            return
        items = data.contact.contacts
        for name, offset, nc, active in data.layout:
            block = data.Ru[:, nv + offset : nv + offset + nc]
            if active:
                np.negative(items[name].Jc[:, rows].T, out=block)
            else:
                block[:] = 0.0

    def __repr__(self) -> str:
        s = self.state
        return f"ResidualModelActuation {{nx={s.nx}, ndx={s.ndx}, nu={self.nu}, na={self.na}}}"


class ResidualModelActuationFree(_ResidualModelActuation):
    """Crocoddyl's ``DifferentialActionModelFreeInvDynamics.ResidualModelActuation(state, nu)``.

    Parameters
    ----------
    state : StateMultibody
        Multibody state.
    nu : int
        Dimension of the actuation (``na``); the residual has ``nv - na`` rows and takes ``u = a (nv,)``.
    """

    def __init__(self, state: StateMultibody, nu: int) -> None:
        super().__init__(state, nu, 0)


class ResidualModelActuationContact(_ResidualModelActuation):
    """Crocoddyl's ``DifferentialActionModelContactInvDynamics.ResidualModelActuation(state, nu, nc)``.

    Parameters
    ----------
    state : StateMultibody
        Multibody state.
    nu : int
        Dimension of the actuation (``na``); the residual has ``nv - na`` rows.
    nc : int
        Dimension of all the contact forces; the residual takes ``u = (a, f) (nv + nc,)``.
    """


class ResidualDataActuation(ResidualDataAbstract):
    """Data of the actuation residual: ``pinocchio``, ``actuation`` and ``contact`` (the contact data,
    None in the free case) from the collector, ``rows`` (the unactuated rows of ``τ``) and ``layout``
    (:func:`contact_layout`)."""

    def __init__(self, model: _ResidualModelActuation, data: DataCollectorAbstract | None) -> None:
        super().__init__(model, data)
        name = type(model).__name__
        self.pinocchio = shared_pinocchio(data, model.state, name)
        self.actuation = data.actuation if hasattr(data, "actuation") else None
        self.rows = _unactuated(data, model.nr, name)
        self.contact = getattr(data, "contacts", None) if model.nc else None
        self.layout: list[tuple[str, int, int, bool]] = []
        if model.nc:
            if self.contact is None:
                raise ValueError(f"{name} with nc = {model.nc} needs a data collector with contacts")
            self.layout = contact_layout(self.contact._model)
            total = sum(nc for _, _, nc, _ in self.layout)
            if total != model.nc:
                raise ValueError(f"{name}: the contacts have {total} force components, the residual nc = {model.nc}")


class ResidualModelContact(ResidualModelAbstract):
    """Crocoddyl's ``DifferentialActionModelContactInvDynamics.ResidualModelContact(state, id, nr, nc)``.

    Parameters
    ----------
    state : StateMultibody
        Multibody state.
    id : int or str
        Frame of the contact.
    nr : int
        Dimension of the contact (rows of the residual).
    nc : int
        Dimension of all the contact forces; the residual takes ``u = (a, f) (nv + nc,)``.
    """

    def __init__(self, state: StateMultibody, id: int | str, nr: int, nc: int) -> None:
        state = check_state(state)
        fid = frame_id(state, id)
        if int(nc) < 0:
            raise ValueError(f"nc must be non-negative, got {nc}")
        super().__init__(state, int(nr), state.nv + int(nc), True, True, True)
        self.id = fid
        self.nc = int(nc)

    def createData(self, data: DataCollectorAbstract | None = None) -> "ResidualDataContact":
        return ResidualDataContact(self, data)

    def calc(self, data: "ResidualDataContact", x: np.ndarray, u: np.ndarray | None = None) -> None:
        data.r[:] = data.contact.a0

    def calcDiff(self, data: "ResidualDataContact", x: np.ndarray, u: np.ndarray | None = None) -> None:
        data.Rx[:] = data.contact.da0_dx
        data.Ru[:, : self.state.nv] = data.contact.Jc

    def __repr__(self) -> str:
        return f"ResidualModelContact {{frame={self.state.pinocchio.frames[self.id].name}, nr={self.nr}}}"


class ResidualDataContact(ResidualDataAbstract):
    """Data of :class:`~crocopy.models.residuals_invdyn.ResidualModelContact`: ``contact`` (the data of the
    contact on the residual's frame)."""

    def __init__(self, model: ResidualModelContact, data: DataCollectorAbstract | None) -> None:
        super().__init__(model, data)
        items = getattr(getattr(data, "contacts", None), "contacts", None)
        if items is None:
            raise ValueError(f"ResidualModelContact needs a data collector with contacts, got {type(data).__name__}")
        found = [cd for cd in items.values() if cd.frame == model.id and cd.Jc.shape[0] == model.nr]
        if not found:
            raise ValueError(f"ResidualModelContact: no contact of dimension {model.nr} on frame {model.id}")
        self.contact = found[0]
