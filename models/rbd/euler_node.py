"""Compiled Euler nodes of free or contact forward dynamics: one numba call per node evaluation inside a solve.

:class:`EulerNode` is the evaluator (:mod:`crocopy.solvers.compiled_nodes`) of a node whose whole
``calc``/``calcDiff`` the kernels of :mod:`.euler_node_kernel` can do.  A node qualifies when, on the
exact classes (a subclass may override a step, so it keeps the Python path):

* ``IntegratedActionModelEuler`` with the identity control parametrization, over a
  ``DifferentialActionModelFreeFwdDynamics`` or a ``DifferentialActionModelContactFwdDynamics`` (with a constraint
  manager whose active constraints :mod:`.constraint_rows` lowers, or none), whose active contacts are
  ``ContactModel1D``/``ContactModel2D``/``ContactModel3D``/``ContactModel6D`` on distinct joints (or with a positive
  ``JMinvJt_damping``; see :mod:`.contact_lowering`);
* its ``StateMultibody``'s Pinocchio model lowers (:func:`.lowering.lower_model`);
* its actuation is ``ActuationModelFull``, ``ActuationModelFloatingBase``,
  ``ActuationModelFloatingBaseThrusters`` or ``ActuationModelLinear`` (``τ = S u`` with a constant ``S``);
* every cost is a ``CostModelResidual`` in the cost stack with an activation of the quadratic-barrier
  family (:mod:`crocopy.costs.stack`), and every active one's residual is a ``ResidualModelState``,
  ``ResidualModelControl``, ``ResidualModelFramePlacement``, ``ResidualModelFrameTranslation``,
  ``ResidualModelFrameRotation``, ``ResidualModelFrameVelocity``, ``ResidualModelCoMPosition``, or (on an
  active contact) ``ResidualModelContactFrictionCone``/``ResidualModelContactWrenchCone``, or a user's
  ``ResidualModelNumba`` (kind ``USER``: C callbacks, :mod:`crocopy.models.residual_numba`); in a node without
  active contacts, a user's Python residual runs in Python around the compiled call (:mod:`.python_residuals`).

:meth:`EulerNode.refresh` (when a solve makes its selection of compiled nodes; a solve that reuses the last one
calls :meth:`EulerNode.refresh_live` instead, :class:`crocopy.solvers.compiled_nodes.Selection`) re-reads everything
the kernels take from the models: the lowered Pinocchio model, the armature (the Pinocchio model's, which
Pinocchio's own ``crba``/``aba`` add, plus the dynamics model's ``armature``), ``S``, the time step, the damping, the
contacts' gains and references, the cost stack's weights and activation bounds, the residuals' references;
and the addresses of the data arrays the kernels write (``xnext``, ``Fx``, ... of the node's data, the
stack's arrays).  Evaluators are cached per node data
(weakly: a copied or unpickled data gets its own).
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Callable, Sequence
from functools import partial

import numpy as np

from crocopy.costs.stack_kernel import stack_values
from crocopy.not_compiled import class_reason, decline
from crocopy.versioning import ParametersVersion, parameter_owners

from ..residual_numba import kinematics_size
from ..state_multibody import StateMultibody
from . import euler_node_kernel as kernel
from . import node_table as table
from .constraint_rows import ConstraintRows
from .contact_lowering import ContactSet, force_item, force_parameters
from .euler_horizon import EulerHorizon
from .joint_types import NotLowerable
from .live_parameters import (
    actuation_live,
    contacts_live,
    frozen,
    layout_touched,
    read_parameters,
    residuals_only,
    values_touched,
)
from .lowered_model import Lowered, lowered, table_entries
from .node_kinds import ACTUATIONS, python_residual, residual_kind
from .python_residuals import PythonResiduals
from .stack_items import compiled_items

_NODES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
"""Node data → its :class:`EulerNode`."""


def euler_node(iam, data, terminal: bool, memo: dict, contacts: list = ()) -> EulerNode | None:
    """The refreshed evaluator of node ``(iam, data)`` with the active rigid ``contacts`` (1D to 6D contacts), or
    None if the node does not qualify (the reason recorded in ``memo``, :mod:`crocopy.not_compiled`; the caller,
    the free or contact dynamics model, has checked its own class, the integrator's and the contacts')."""
    dam = iam.differential
    if type(dam.state) is not StateMultibody:
        return decline(memo, class_reason(dam.state, "state"))
    if type(dam.actuation) not in ACTUATIONS:
        return decline(memo, class_reason(dam.actuation, "actuation"))
    low = lowered(dam.state.pinocchio, memo)
    if low is None:
        return decline(memo, memo[id(dam.state.pinocchio), NotLowerable])
    node = _NODES.get(data)
    if node is None or node.model is not iam or node.terminal != terminal or node.nv != low.rb.nv \
            or not node.contacts.same(contacts):
        node = EulerNode(iam, data, terminal, low.rb.nv, contacts)
        _NODES[data] = node
    return node if node.refresh(low, memo) else None


class EulerNode:
    """The compiled ``calc``/``calcDiff`` of one Euler node of free or contact forward dynamics (see the module
    docstring).

    ``calc(x, u)`` writes ``data.xnext`` and ``data.cost``; ``calcDiff(x, u, synced)`` also ``Fx``, ``Fu``,
    ``Lx``, ``Lu``, ``Lxx``, ``Lxu``, ``Luu`` (and the cost stack's residuals, Jacobians and activation
    derivatives, which the stack shares with the residual and activation datas).
    """

    refreshes = 0
    """How many times :meth:`refresh` ran (a selection of compiled nodes made before the last one is stale)."""

    def __init__(self, iam, data, terminal: bool, nv: int, contacts: list = ()) -> None:
        self.model = iam
        self.terminal = terminal
        self._data = weakref.ref(data)
        self.nv = nv
        self.nu = iam.differential.nu  # the differential model's controls (a stage's w, .rk_node)
        self.armature = np.zeros(nv)
        self.contacts = ContactSet(contacts)
        self.parameters = {"S": np.zeros((nv, self.nu)), "gains": self.contacts.gains, "ref_R": self.contacts.ref_R,
                           "ref_p": self.contacts.ref_p, "kin": np.zeros(kinematics_size(nv)),
                           "user_dims": np.zeros(5, dtype=np.int64), "user_Ru": np.zeros((1, self.nu))}
        self.no_control = np.zeros(0)
        self._armature_entry = table_entries([self.armature])
        self._data_arrays: list = []
        self._data_entries = (np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64))
        self._residuals: list | None = None
        self._items: list = []
        self.rows = ConstraintRows(self.nu, iam.state.ndx)
        self.python = PythonResiduals(iam.state.pinocchio, data.differential.pinocchio, [])
        self._lowered: Lowered | None = None
        self.stamp = np.zeros(0)
        self._own: tuple = (None, None, np.zeros(0, dtype=np.int64), [])
        self._seen = -1
        self._owners: list = []
        self._n_parameters = 0
        self.shared_minv = False

    def refresh(self, low: Lowered, memo: dict) -> bool:
        """Re-read the models' parameters and the data arrays' addresses; False if the node no longer qualifies (the
        reason recorded in ``memo``).

        The cost stack's items (kinds, frames, reference frames) are read again when the layout of an object reachable
        from the node's model was touched since this node last read them (:func:`~crocopy.versioning.changes_since`:
        every public assignment to a model touches it, except of a value attribute such as a residual's
        ``reference`` or ``dt``); the references, the time step, the armature and ``S`` at every call; the table only
        when an array it lists or the items changed."""
        data = self._data()
        iam = self.model
        dam, ddata = iam.differential, data.differential
        stack = ddata.costs.stack
        changed = stack.refresh_if_stale(self.terminal) or self._residuals is None \
            or layout_touched(self)
        read: dict | None = None
        if changed:
            read = {}
            why = self._read_items(stack, ddata, read)
            if why is not None:
                decline(memo, why)
                return False
            self._owners = parameter_owners(iam)
        self._seen = ParametersVersion.value
        self.contacts.refresh()
        par = [float(iam.dt), self._damping(dam)]
        live = read_parameters(self._residuals, par, self._node_parameters, read)
        if len(par) != self._n_parameters:  # a user residual's parameters() changed length: read the items again
            self._residuals = None
            return self.refresh(low, memo)
        self.par = np.array(par)
        self._refresh_dynamics(low, dam, memo)
        self._table(low, data, ddata, stack, changed)
        self._live = self._live_sources(live, dam, memo)
        self._low_version = low.version
        self.refreshes += 1
        return True

    @staticmethod
    def _damping(dam) -> float:
        """The dynamics' KKT damping (the table's second parameter)."""
        return float(getattr(dam, "_damping", 0.0))

    def _refresh_dynamics(self, low: Lowered, dam, memo: dict) -> None:
        """The node's armature (the model's plus the dynamics') and its actuation matrix ``S``."""
        np.add(low.rb.armature, dam.armature, out=self.armature)
        self._actuation_matrix(dam, memo)

    def _live_sources(self, live, dam, memo: dict) -> tuple:
        """What :meth:`refresh_live` re-reads: the residuals' live parameters, the contacts, a writeable armature,
        a live actuation matrix."""
        return (live, contacts_live(self.contacts.models), not frozen(dam.armature),
                not self.terminal and actuation_live(dam.actuation, memo["S", id(dam.actuation)]))

    def refresh_values(self, memo: dict) -> bool:
        """After the parameter clock moved: False (the node must be refreshed) when what the node read as its layout
        was touched since (:func:`~crocopy.versioning.changes_since`: a frame, a residual or an item replaced); else
        re-read in place what changed: nothing but the live parameters (:meth:`refresh_live`) when no object of the
        node was touched (another model's parameter was), else the parameters of the touched residuals (a value
        attribute such as ``reference``), the time step and the damping, and the contacts, the armature and ``S``:
        all of them when another object of the node was touched, their live sources only when the touched objects
        are residuals (a model-predictive loop moving references).  Spends the stamp of the last values."""
        self.forget()
        touched = values_touched(self, self._residuals is not None, memo)
        if not touched:
            return touched is not None
        data, low = self._data(), self._lowered
        if data is None or low.version != self._low_version or not low.current(memo):
            return False
        if data.differential.costs.stack.refresh_if_stale(self.terminal):
            self._residuals = None  # read the items again
            return False
        iam, dam = self.model, self.model.differential
        live = self._live[0]
        self.par[0], self.par[1] = float(iam.dt), self._damping(dam)  # in place: a horizon reads this array
        if not live.reread_since(self.par, self._seen):
            self._residuals = None
            return False
        if residuals_only(touched, live):  # the dynamics and contacts were not assigned
            self._reread_live_sources(low, memo)
        else:
            self.contacts.refresh()
            self._refresh_dynamics(low, dam, memo)
        self._seen = ParametersVersion.value
        return True

    def refresh_live(self, memo: dict) -> bool:
        """Re-read, in place, what :meth:`refresh` read that may have changed without moving the parameter clock
        (:mod:`.live_parameters`: ``pin.SE3`` references, cones, a user residual's ``parameters()``, writeable
        arrays); False when the node must be refreshed instead: its Pinocchio model changed
        (:meth:`.lowered_model.Lowered.current`), its cost stack was evaluated for the other node kind since, or a
        user residual's number of parameters changed.  Only for a node refreshed since the parameter clock last
        moved.  Spends the stamp of the last values (:meth:`forget`) either way."""
        self.forget()
        low = self._lowered
        if low.version != self._low_version or not low.current(memo):
            return False
        data = self._data()
        if data is None or data.differential.costs.stack.refresh_if_stale(self.terminal) \
                or not self._live[0].reread(self.par):
            self._residuals = None  # read the items again
            return False
        self._reread_live_sources(low, memo)
        return True

    def _reread_live_sources(self, low: Lowered, memo: dict) -> None:
        """Re-read the contacts, the armature and ``S`` where they are live (:meth:`_live_sources`)."""
        _, contacts, armature, actuation = self._live
        dam = self.model.differential
        if contacts:
            self.contacts.refresh()
        if armature:
            np.add(low.rb.armature, dam.armature, out=self.armature)
        if actuation:
            self._actuation_matrix(dam, memo)

    def _read_items(self, stack, ddata, read: dict) -> str | None:
        """Read the compiled items of the cost stack (kind, rows, frame, reference frame, parameter offset); returns
        None, or why the node cannot compile (:mod:`crocopy.not_compiled`).  ``read`` receives the parameters it read,
        by residual (``id``): each residual's are read once per refresh."""

        parameters = self._reader(read)
        self._residuals = None
        items, residuals, offset, rows_u, python = [], [], 2, 1, []
        for entry in compiled_items(stack, ddata.costs, self.model.differential.costs, item_forms=True):
            if isinstance(entry, str):
                return entry
            residual, cdata, rows = entry
            kind = residual_kind(residual)
            if kind is None:
                if not python_residual(residual):
                    return class_reason(residual, "residual")
                if self.contacts.models:
                    return class_reason(residual, "residual") + " in a contact node"
                python.append((residual, cdata.residual))
                continue
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
            manager, self.terminal, residual_kind, offset, parameters, self.contacts.rows)
        if why is not None:
            return why
        self._items, self._residuals = items, residuals + self.rows.residuals
        self._n_parameters = offset + sum(len(parameters(*r)) for r in self.rows.residuals)
        self.python = PythonResiduals(self.model.state.pinocchio, ddata.pinocchio, python)
        rows_u = max(rows_u, self.rows.user_rows)
        if self.parameters["user_Ru"].shape[0] < rows_u:
            self.parameters["user_Ru"] = np.zeros((rows_u, self.nu))
        return None

    def _reader(self, read: dict) -> Callable:
        """``parameters(kind, residual)``: the residual's parameters (:meth:`_parameters`), read once per refresh
        (kept in ``read`` by the residual's ``id``)."""

        def parameters(kind: int, residual) -> Sequence[float]:
            key = id(residual)
            if key not in read:
                read[key] = self._node_parameters(kind, residual)
            return read[key]

        return parameters

    def _stack_item(self, kind: int, residual, rows: slice, offset: int, parameters: Callable) -> list[int] | str:
        """The fields of one compiled item of the cost stack: kind, first row, rows, frame, reference frame (a cone's
        contact row and force count), parameter offset and a user residual's flags, callbacks and parameter count;
        or why it cannot compile."""
        frame, reference = getattr(residual, "id", 0), int(residual.type) if kind == table.VELOCITY else 0
        user = [0, 0, 0, 0]
        if kind == table.USER:
            frame, reference = residual.frame, int(residual.frame_reference)
            user = [residual.flags, *residual.callbacks(), len(parameters(kind, residual))]
        if kind == table.CONE or kind == table.FORCE:
            found = force_item(residual, self.contacts.rows)
            if found is None:
                return "cone without its active contact"
            frame, reference = found
        return [kind, rows.start, rows.stop - rows.start, frame, reference, offset, *user]

    def _node_parameters(self, kind: int, residual) -> Sequence[float]:
        """:meth:`_parameters`, a force residual's on a 1D or 2D contact over that contact's rows
        (:func:`.contact_lowering.force_parameters`)."""
        values = self._parameters(kind, residual)
        if kind == table.CONE or kind == table.FORCE:
            nc = self.contacts.rows.get(residual.id, (0, 0))[1]
            if nc in (1, 2):
                return force_parameters(values, residual.nr, residual.ncf, nc)
        return values

    @staticmethod
    def _parameters(kind: int, residual) -> Sequence[float]:
        """The residual's parameters in the layout :mod:`.euler_node_kernel` reads (its ``compiled_parameters()``,
        a user residual's ``parameters()``)."""
        return list(residual.checked_parameters()) if kind == table.USER else residual.compiled_parameters()

    def _actuation_matrix(self, dam, memo: dict) -> None:
        """``S = ∂τ/∂u`` of the (linear, state-independent) actuation, as it declares it (once per actuation and
        ``memo``, one solve)."""
        if not self.terminal:
            key = ("S", id(dam.actuation))
            if key not in memo:
                memo[key] = dam.actuation.compiled_matrix()
            self.parameters["S"][:] = memo[key]

    def _table(self, low: Lowered, data, ddata, stack, changed: bool) -> None:
        """The addresses and dimensions of every array the kernels read or write, and the integer program.

        Entries: the lowered model's arrays (the armature is this node's, model's plus dynamics'), its shared
        workspace, then :data:`.node_table.NODE_ARRAYS` (the node's own) and ``SCRATCH_ARRAYS`` (shared by the
        model's nodes of the same sizes, :meth:`.lowered_model.Lowered.scratch`), except the workspace and scratch
        entries the node keeps of its own (:data:`.node_table.OWN`, :meth:`_own_addresses`).  Made again only when
        the items changed (``changed``) or the lowered model is another one: the arrays a data or a stack owns never
        move (:mod:`crocopy.stored`), and a new data gets a new node."""
        self.forget()
        if not changed and low is self._lowered and self._data_arrays:
            return
        state = self.model.state
        n_stamp = state.nx + self.nu + 2
        if self.stamp.shape[0] != n_stamp:
            self.stamp = np.zeros(n_stamp)
        data.compiled_stamp = self.stamp
        fields = {
            "xnext": data.xnext, "dx": data.dx, "Fx": data.Fx, "Fu": data.Fu, "Lx": data.Lx, "Lu": data.Lu,
            "Lxx": data.Lxx, "Lxu": data.Lxu, "Luu": data.Luu,
            "a": ddata.xout, "dFx": ddata.Fx, "dFu": ddata.Fu, "dLx": ddata.Lx, "dLu": ddata.Lu,
            "dLxx": ddata.Lxx, "dLxu": ddata.Lxu, "dLuu": ddata.Luu,
            "r": stack.r, "lb": stack.lb, "ub": stack.ub, "act_weights": stack.act_weights,
            "item_costs": stack.item_costs, "item_weights": stack.item_weights, "weights": stack.weights,
            "Ar": stack.Ar, "Arr": stack.Arr, "Jx": stack.Jx, "Ju": stack.Ju, "cols": stack.cols, "grad": stack.grad,
            "act_kinds": stack.act_kinds, "act_params": stack.act_params, "stamp": self.stamp, **self.parameters,
            **self.rows.fields(data, ddata),
        }
        n = table.NODE + len(table.NODE_ARRAYS) + len(table.SCRATCH_ARRAYS)
        self.rows.allocate(n, table.SHAPES + 3 * n + len(self._items) + len(stack.starts) + len(self.contacts.ints))
        fields.update(self.rows.arrays)
        scratch, scratch_entries = low.scratch(self.nu, self.contacts.nc)
        self.shared_minv = not hasattr(ddata, "Minv")
        fields["Minv"] = scratch["Minv"] if self.shared_minv else ddata.Minv
        arrays = [fields[e.name] for e in table.NODE_ARRAYS]
        known = self._data_arrays
        if len(known) != len(arrays) or any(a is not b for a, b in zip(arrays, known)):
            sizes = {"nx": state.nx, "ndx": state.ndx, "nv": state.nv, "nu": self.nu, "nr": stack.r.shape[0],
                     "nr_u": stack.r.shape[0] - stack.u_start, "n_stack": stack.item_costs.shape[0],
                     "n_cols": stack.cols.shape[0], "n_contacts": len(self.contacts.models),
                     "n_kin": kinematics_size(state.nv), "nr_user": self.parameters["user_Ru"].shape[0],
                     "n_stamp": n_stamp, **self.rows.sizes(data)}
            table.check_arrays(table.NODE_ARRAYS, arrays, sizes)
            self._data_entries = table_entries(arrays)
            self._data_arrays = arrays
        elif not changed and low is self._lowered:
            return
        items = self._items
        rb = low.rb
        armature = table.RB_ARMATURE
        parts = [(low.addresses[:armature], low.shapes[:3 * armature]), self._armature_entry,
                 (low.addresses[armature + 1:], low.shapes[3 * armature + 3:]), low.workspace_entries,
                 self._data_entries, scratch_entries]
        addresses = np.concatenate([p[0] for p in parts])
        addresses[table.OWN] = self._own_addresses(low, scratch)
        shapes = np.concatenate([p[1] for p in parts])
        n = addresses.shape[0]
        header = np.zeros(table.SHAPES, dtype=np.int64)
        header[[table.NQ, table.NV, table.NU, table.U_START]] = rb.nq, rb.nv, self.nu, stack.u_start
        header[[table.N_ITEMS, table.EUCLIDEAN, table.NJOINTS, table.NFRAMES, table.N_STACK]] = (
            len(items) // table.ITEM_FIELDS, self.model._euclidean, rb.njoints, rb.nframes, len(stack.starts))
        header[table.ITEMS] = table.SHAPES + 3 * n
        header[table.STARTS] = header[table.ITEMS] + len(items)
        header[table.TERMINAL] = self.terminal
        header[table.N_CONTACTS] = len(self.contacts.models)
        header[table.CONTACTS] = header[table.STARTS] + len(stack.starts)
        header[table.NC] = self.contacts.nc
        self.ints = np.concatenate([header, shapes, np.array(items, dtype=np.int64),
                                    np.asarray(stack.starts, dtype=np.int64),
                                    np.array(self.contacts.ints, dtype=np.int64)])
        self.tbl = addresses
        self.rows.constraint_ints(self.ints)
        self._lowered = low

    def _own_addresses(self, low: Lowered, scratch: dict) -> np.ndarray:
        """The addresses of this node's own workspace and scratch arrays (:data:`.node_table.OWN`), shaped as the
        model's shared ones (made again for another lowered model or other sizes)."""
        key = (self.nu, self.contacts.nc)
        owner, sizes, addresses, _ = self._own
        if owner is not low or sizes != key:
            arrays = ([np.zeros_like(getattr(low.workspace, name)) for name in table.OWN_WORKSPACE]
                      + [np.zeros_like(scratch[name]) for name in table.OWN_SCRATCH])
            addresses = table_entries(arrays)[0]
            self._own = (low, key, addresses, arrays)
        return addresses

    def forget(self) -> None:
        """Spend the stamp of the last values (:func:`.euler_node_kernel.node_calc_diff` evaluates them again): at
        every refresh (a solve's start: parameters may have changed since) and after the Python path wrote the
        data."""
        if self.stamp.shape[0]:
            self.stamp[0] = 0.0

    def calc(self, x: np.ndarray, u: np.ndarray | None) -> None:
        if self.python.items:
            self.python.evaluate(x, u, False)
        cost = kernel.node_calc(self.tbl, self.ints, self.par, x, self.no_control if u is None else u)
        if math.isfinite(cost):
            self._data().cost = cost
        else:
            self.python_path(x, u, False)

    def fill(self, x: np.ndarray, u: np.ndarray | None) -> None:
        """The node's data at ``(x, u)`` as its model's ``calc`` leaves it, at the end of a solve
        (:meth:`crocopy.solvers.compiled_nodes.CompiledNodes.fill`).  A node of free dynamics without Python residuals
        keeps the compiled values (evaluated again unless its data holds those of ``(x, u)``,
        :func:`.euler_node_kernel.values_current`) and its dynamics model writes the
        rest (``_fill_after_kernel``: Pinocchio data, torques, residual datas, constraints); any other node runs its
        model's ``calc``."""
        model, data = self.model, self._data()
        dam = model.differential
        fill = type(dam).__dict__.get("_fill_after_kernel")  # its own class's, not a subclass's
        if fill is None or self.python.items:
            model._raw_calc(data, x, u)
            return
        if not kernel.values_current(self.stamp, x, self.no_control if u is None else u):
            self.calc(x, u)
            if self.stamp[0] != 1.0:  # not finite: the Python path evaluated the node
                return
        value = self.stamp[1]
        data.cost = value if self.terminal else self.par[0] * value
        fill(dam, data.differential, x, u, value)

    def integrate(self, x: np.ndarray, step: np.ndarray, out: np.ndarray) -> None:
        """``out = x ⊕ step`` by the node's compiled state integration (as the compiled trial points integrate)."""
        kernel.node_integrate(self.tbl, self.ints, x, step, out)

    def diff(self, x0: np.ndarray, x1: np.ndarray, out: np.ndarray) -> None:
        """``out = x1 ⊖ x0`` by the node's compiled state difference (as the compiled gaps are taken)."""
        kernel.node_diff(self.tbl, self.ints, x0, x1, out)

    def python_path(self, x: np.ndarray, u: np.ndarray | None, derivatives: bool) -> float:
        """Evaluate the node on its Python path (where the kernel's acceleration is not finite: a contact set whose
        KKT system is singular at this state takes least squares there, as with kernels off); returns its cost."""
        model, data = self.model, self._data()
        self.forget()
        model._raw_calc(data, x, u)
        if derivatives:
            model._raw_calcDiff(data, x, u)
        return data.cost

    @property
    def rollout_step(self) -> Callable:
        """One node of the DDP family's rollout (:func:`.euler_node_kernel.node_rollout_step` on this node's
        arrays): ``rollout_step(x_ref, x, u_ref, k, K, alpha, lb, ub, u, dx, x_next, f, gap) -> cost``
        (the caller stores the cost in the node's data); with Python residuals, their rows and the cost are
        evaluated after the compiled step (:meth:`python_cost`)."""
        step = partial(kernel.node_rollout_step, self.tbl, self.ints, self.par)
        if not self.python.items:
            return step

        def step_and_python_rows(x_ref, x, u_ref, k, K, alpha, lb, ub, u, dx, x_next, f, gap):
            step(x_ref, x, u_ref, k, K, alpha, lb, ub, u, dx, x_next, f, gap)
            return self.python_cost(x, u)

        return step_and_python_rows

    def python_cost(self, x: np.ndarray, u: np.ndarray) -> float:
        """The running node's cost at ``(x, u)`` after a compiled evaluation there that left the Python residuals'
        rows stale: those rows, then the stack's activations and sum again (:mod:`.python_residuals`)."""
        self.python.evaluate(x, u, False)
        stack = self._data().differential.costs.stack
        value = stack_values(stack.r, stack.lb, stack.ub, stack.act_weights, stack.starts, stack.act_kinds,
                             stack.act_params, stack.item_costs, stack.item_weights)
        if self.stamp[0] == 1.0:
            self.stamp[1] = value
        return self.par[0] * value

    def python_derivatives(self, x: np.ndarray, u: np.ndarray | None) -> None:
        """Before a compiled ``calcDiff`` at ``(x, u)``: the Python residuals' Jacobians, and their rows again unless
        the stamp is at ``(x, u)`` (every compiled evaluation that stamps a point has their rows at that point: they
        are evaluated before it, or after it by the rollout)."""
        if kernel.stamp_current(self.stamp, x, self.no_control if u is None else u):
            self.python.jacobians(x, u)
        else:
            self.python.evaluate(x, u, True)

    def calcDiff(self, x: np.ndarray, u: np.ndarray | None, synced: bool) -> None:
        if self.python.items:
            self.python_derivatives(x, u)
        cost = kernel.node_calc_diff(self.tbl, self.ints, self.par, x, self.no_control if u is None else u)
        if math.isfinite(cost):
            self._data().cost = cost
        else:
            self.python_path(x, u, True)

    @staticmethod
    def horizon(nodes: list[EulerNode | None], nus: list[int], nthreads: int = 1) -> EulerHorizon:
        """The rollout of the running nodes (``None`` where a node is not of this class; ``nus`` their controls) in
        one compiled call per range of nodes of this class, their evaluations on ``nthreads`` threads
        (:class:`.euler_horizon.EulerHorizon`)."""
        return EulerHorizon(nodes, nus, nthreads)
