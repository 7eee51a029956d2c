"""Compiled Euler nodes of free or contact inverse dynamics: one numba call per node evaluation inside a solve.

:class:`InvDynNode` is the evaluator (:mod:`crocopy.solvers.compiled_nodes`) of an Euler node over a
``DifferentialActionModelFreeInvDynamics`` or a ``DifferentialActionModelContactInvDynamics`` whose whole
``calc``/``calcDiff`` the kernels of :mod:`.invdyn_node_kernel` can do.  A node qualifies when, on the exact classes:

* ``IntegratedActionModelEuler`` with the identity control parametrization over one of those models, on a
  ``StateMultibody`` whose Pinocchio model lowers (:func:`.lowering.lower_model`);
* its actuation is one the Euler node takes (``τ = S u`` with a constant ``S``, :data:`.node_kinds.ACTUATIONS`):
  the joint efforts are then ``P τ`` with a constant ``P`` (the actuation's ``Mtau``);
* its contacts (contact model) are all active ``ContactModel1D``/``ContactModel3D``/``ContactModel6D``
  (:mod:`.contact_lowering`);
* every cost is a ``CostModelResidual`` in the cost stack with an activation of the quadratic-barrier family, and
  every active one's residual, and every active constraint's (a ``ConstraintModelResidual``), is of a kind the Euler
  node evaluates (:func:`.node_kinds.residual_kind`; the cones read the forces of the control) or one of
  :data:`ITEM_KINDS`: the models' actuation residual (``"tau"``), contact-acceleration residual (``"<contact>_acc"``),
  ``ResidualModelJointEffort`` and ``ResidualModelJointAcceleration`` (the actuation and contact residuals on running
  nodes only).

It is an :class:`.euler_node.EulerNode` (the same table, refreshing and constraint rows) with its own kernels: the
inverse-dynamics residuals are items of their own (:mod:`.invdyn_node_kernel`), split from the cost stack's and
the constraint manager's items when they are read.  :meth:`InvDynNode.refresh` re-reads the lowered model, the time
step, the contacts' gains and references, the residuals' references and the actuation's ``P`` and unactuated rows;
:meth:`InvDynNode.refresh_live` what may change unannounced.  As the Euler node, it keeps its kinematics and contacts
in arrays of its own (:data:`.node_table.OWN`) and stamps each ``calc``: a ``calcDiff`` at that point skips the
values.  Its horizon (:class:`.invdyn_horizon.InvDynHorizon`) runs a range of such nodes in one compiled call.
"""

from __future__ import annotations

import weakref
from collections.abc import Callable, Sequence
from functools import partial

import numpy as np

from crocopy.not_compiled import class_reason, decline
from crocopy.versioning import ParametersVersion

from ..residuals_dynamics import ResidualModelJointAcceleration, ResidualModelJointEffort
from ..residuals_invdyn import ResidualModelActuationContact, ResidualModelActuationFree, ResidualModelContact
from ..state_multibody import StateMultibody
from . import invdyn_node_kernel as kernel
from . import node_table as table
from .constraint_rows import ConstraintRows
from .contact_lowering import CONTACTS
from .euler_node import EulerNode
from .invdyn_horizon import InvDynHorizon
from .joint_types import NotLowerable
from .live_parameters import contacts_live
from .lowered_model import Lowered, lowered
from .node_kinds import ACTUATIONS, residual_kind
from .stack_items import compiled_items

INV = 100
"""Item kinds from ``INV`` on are inverse-dynamics items (kind ``INV + k``, ``k`` of :mod:`.invdyn_node_kernel`)."""
ITEM_KINDS = {ResidualModelActuationFree: kernel.ACTUATION, ResidualModelActuationContact: kernel.ACTUATION,
              ResidualModelJointEffort: kernel.EFFORT, ResidualModelJointAcceleration: kernel.ACCELERATION,
              ResidualModelContact: kernel.CONTACT}
"""The inverse-dynamics residual classes (exact) and their item kinds."""
RUNNING_ONLY = (kernel.ACTUATION, kernel.CONTACT)
"""The item kinds a terminal node does not take (they read the torques or the contacts of a running node)."""

_NODES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
"""Node data → its :class:`InvDynNode`."""
_COMMANDS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
"""Actuation → ``(parameter clock, P, unactuated rows)`` (:func:`commands`)."""


def commands(actuation, state) -> tuple[np.ndarray, np.ndarray]:
    """``(P, rows)`` of a constant actuation: the commands ``P τ`` of the torques ``τ`` (its ``Mtau``) and the rows
    of ``τ`` it cannot set; kept while the parameter clock stands still."""
    cached = _COMMANDS.get(actuation)
    if cached is not None and cached[0] == ParametersVersion.value:
        return cached[1], cached[2]
    adata = actuation.createData()
    actuation.torqueTransform(adata, state.zero(), np.zeros(actuation.nu))
    P, rows = np.array(adata.Mtau, dtype=float), np.flatnonzero(~np.asarray(adata.tau_set, dtype=bool))
    _COMMANDS[actuation] = (ParametersVersion.value, P, rows)
    return P, rows


def invdyn_node(iam, data, terminal: bool, memo: dict) -> InvDynNode | None:
    """The refreshed evaluator of node ``(iam, data)`` over free or contact inverse dynamics, or None if it does not
    qualify (the reason recorded in ``memo``, :mod:`crocopy.not_compiled`; the caller has checked the classes of the
    integrator and of the dynamics model)."""
    dam = iam.differential
    if type(dam.state) is not StateMultibody:
        return decline(memo, class_reason(dam.state, "state"))
    if type(dam.actuation) not in ACTUATIONS:
        return decline(memo, class_reason(dam.actuation, "actuation"))
    contacts: list = []
    if hasattr(dam, "contacts"):
        dam._sync_status()
        items = list(dam.contacts.contacts.values())
        if not all(item.active for item in items):
            return decline(memo, "inactive contact in an inverse-dynamics node")
        contacts = [item.contact for item in items]
        other = next((m for m in contacts if type(m) not in CONTACTS), None)
        if other is not None:
            return decline(memo, class_reason(other, "contact"))
    low = lowered(dam.state.pinocchio, memo)
    if low is None:
        return decline(memo, memo[id(dam.state.pinocchio), NotLowerable])
    node = _NODES.get(data)
    if node is None or node.model is not iam or node.terminal != terminal or node.nv != low.rb.nv \
            or not node.contacts.same(contacts):
        node = InvDynNode(iam, data, terminal, low.rb.nv, contacts)
        _NODES[data] = node
    return node if node.refresh(low, memo) else None


class InvDynNode(EulerNode):
    """The compiled ``calc``/``calcDiff`` of one Euler node of free or contact inverse dynamics (see the module
    docstring); writes what an :class:`.euler_node.EulerNode` writes."""

    @staticmethod
    def horizon(nodes: list[InvDynNode | None], nus: list[int], nthreads: int = 1) -> InvDynHorizon:
        """The running nodes (``None`` where a node is not of this class; ``nus`` their controls) in one compiled call
        per range of nodes of this class, their evaluations on ``nthreads`` threads
        (:class:`.invdyn_horizon.InvDynHorizon`)."""
        return InvDynHorizon(nodes, nus, nthreads)

    def __init__(self, iam, data, terminal: bool, nv: int, contacts: list = ()) -> None:
        super().__init__(iam, data, terminal, nv, contacts)
        self.iints = np.zeros(kernel.HEADER, dtype=np.int64)

    @staticmethod
    def _damping(dam) -> float:
        """No KKT damping: the table's second parameter is 0."""
        return 0.0

    def _refresh_dynamics(self, low: Lowered, dam, memo: dict) -> None:
        """The model's armature (the commands read ``τ``, not ``S``)."""
        self.armature[:] = low.rb.armature

    def _live_sources(self, live, dam, memo: dict) -> tuple:
        """What :meth:`refresh_live` re-reads: the residuals' live parameters and the contacts."""
        return (live, contacts_live(self.contacts.models))

    def refresh_live(self, memo: dict) -> bool:
        """Re-read, in place, what :meth:`refresh` read that may have changed without moving the parameter clock
        (:mod:`.live_parameters`); False when the node must be refreshed instead (its Pinocchio model changed, its
        cost stack was evaluated for the other node kind since, or a residual's number of parameters changed).  Spends
        the stamp of the last values either way."""
        self.forget()
        low = self._lowered
        if low.version != self._low_version or not low.current(memo):
            return False
        data = self._data()
        live, contacts = self._live
        if data is None or data.differential.costs.stack.refresh_if_stale(self.terminal) or not live.reread(self.par):
            self._residuals = None
            return False
        if contacts:
            self.contacts.refresh()
        return True

    def _kind(self, residual) -> int | None:
        """The item kind of ``residual``: an inverse-dynamics item's (``INV + k``), the Euler node's (but the
        gravity-compensating controls', whose torques are a forward-dynamics node's ``S u``), or None."""
        kind = ITEM_KINDS.get(type(residual))
        if kind is not None:
            return INV + kind
        kind = residual_kind(residual)
        return None if kind in (table.CONTROL_GRAV, table.CONTACT_CONTROL_GRAV) else kind

    def _parameters(self, kind: int, residual) -> Sequence[float]:
        """The residual's parameters in the layout the kernels read."""
        if kind < INV:
            return EulerNode._parameters(kind, residual)
        kind -= INV
        if kind in (kernel.ACTUATION, kernel.EFFORT):
            P, rows = commands(self.model.differential.actuation, self.model.state)
            if kind == kernel.ACTUATION:
                return [float(i) for i in rows]
            return [*P.ravel().tolist(), *np.asarray(residual.reference, dtype=float).tolist()]
        if kind == kernel.ACCELERATION:
            return np.asarray(residual.reference, dtype=float).tolist()
        return []

    def _item(self, kind: int, residual, start: int, offset: int, cost: bool) -> list[int] | str:
        """The inverse-dynamics item of ``residual`` (rows from ``start``, parameters at ``offset``), or why the node
        cannot take it."""
        kind -= INV
        role = "residual" if cost else "constraint residual"
        if self.terminal and kind in RUNNING_ONLY:
            return class_reason(residual, role) + " at the terminal node"
        row, flag = 0, 0
        if kind == kernel.CONTACT:
            found = [r for f, n, _, r in zip(*[iter(self.contacts.ints)] * table.CONTACT_FIELDS)
                     if f == residual.id and n == residual.nr]
            if not found:
                return class_reason(residual, role) + " without its contact"
            row = found[0]
        elif kind == kernel.ACTUATION and residual.nr != len(commands(self.model.differential.actuation,
                                                                       self.model.state)[1]):
            return class_reason(residual, role) + " of another actuation"
        elif kind == kernel.EFFORT:
            if residual.nr != commands(self.model.differential.actuation, self.model.state)[0].shape[0]:
                return class_reason(residual, role) + " of another actuation"
            flag = int(residual.fwddyn)
        return [kind, start, residual.nr, row, offset, flag]

    def _read_items(self, stack, ddata, read: dict) -> str | None:
        """Read the cost stack's and the constraint manager's items: the Euler node's kinds into the table's items,
        the inverse-dynamics ones into :attr:`iints`; returns None, or why the node cannot compile."""

        parameters = self._reader(read)
        self._residuals = None
        items, inv, residuals, offset, rows_u = [], [], [], 2, 1
        for entry in compiled_items(stack, ddata.costs, self.model.differential.costs):
            if isinstance(entry, str):
                return entry
            residual, _, rows = entry
            kind = self._kind(residual)
            if kind is None:
                return class_reason(residual, "residual")
            if kind >= INV:
                found = self._item(kind, residual, rows.start, offset, True)
                if isinstance(found, str):
                    return found
                inv += found
            else:
                fields = self._stack_item(kind, residual, rows, offset, parameters)
                if isinstance(fields, str):
                    return fields
                if kind == table.USER:
                    rows_u = max(rows_u, rows.stop - rows.start)
                items += fields
            residuals.append((kind, residual))
            offset += len(parameters(kind, residual))
        manager = self.model.differential.constraints
        why = ConstraintRows.sized(manager, self._data(), ddata) or self.rows.read(
            manager, self.terminal, self._kind, offset, parameters, self.contacts.rows)
        if why is not None:
            return why
        general, constraint_items = [], []
        for k, (kind, residual) in enumerate(self.rows.residuals):  # one item each, in item order
            fields = self.rows.items[k * table.ITEM_FIELDS: (k + 1) * table.ITEM_FIELDS]
            if kind < INV:
                general += fields
                continue
            start, o = fields[1], fields[5]
            found = self._item(kind, residual, start, o, False)
            if isinstance(found, str):
                return found
            constraint_items += found
        self.rows.items = general
        self._items, self._residuals = items, residuals + self.rows.residuals
        self._n_parameters = offset + sum(len(parameters(*r)) for r in self.rows.residuals)
        n = kernel.ITEM_FIELDS
        self.iints = np.array([len(inv) // n, len(constraint_items) // n, *inv, *constraint_items], dtype=np.int64)
        rows_u = max(rows_u, self.rows.user_rows)
        if self.parameters["user_Ru"].shape[0] < rows_u:
            self.parameters["user_Ru"] = np.zeros((rows_u, self.model.nu))
        return None

    def calc(self, x: np.ndarray, u: np.ndarray | None) -> None:
        self._data().cost = kernel.invdyn_calc(self.tbl, self.ints, self.par, self.iints, x,
                                               self.no_control if u is None else u)

    def calcDiff(self, x: np.ndarray, u: np.ndarray | None, synced: bool) -> None:
        self._data().cost = kernel.invdyn_calc_diff(self.tbl, self.ints, self.par, self.iints, x,
                                                    self.no_control if u is None else u)

    @property
    def rollout_step(self) -> Callable:
        """One node of the DDP family's rollout (:func:`.invdyn_node_kernel.invdyn_rollout_step` on this node's
        arrays): ``rollout_step(x_ref, x, u_ref, k, K, alpha, lb, ub, u, dx, x_next, f, gap) -> cost``."""
        return partial(kernel.invdyn_rollout_step, self.tbl, self.ints, self.par, self.iints)
