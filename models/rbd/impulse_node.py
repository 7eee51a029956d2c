"""Compiled impulse nodes: one numba call per evaluation of an ``ActionModelImpulseFwdDynamics`` node inside a solve.

:class:`ImpulseNode` is the evaluator (:mod:`crocopy.solvers.compiled_nodes`) of an impulse node whose whole
``calc``/``calcDiff`` the kernels of :mod:`.impulse_node_kernel` can do.  A node qualifies when, on the exact
classes (a subclass may override a step):

* the model is ``ActionModelImpulseFwdDynamics`` on a ``StateMultibody`` whose Pinocchio model lowers
  (:func:`.lowering.lower_model`), with no constraint manager or one whose active constraints
  :mod:`.constraint_rows` lowers with residuals of the kinds below (all of them when the manager has ``nu = 0``,
  else the ``T_constraint`` ones, as the Python model evaluates them);
* its active impulses are ``ImpulseModel3D``/``ImpulseModel6D`` (any reference frame; ``WORLD`` is read as
  ``LOCAL_WORLD_ALIGNED``, as the impulses do) on distinct joints, or with a positive ``JMinvJt_damping`` (else
  the Python model takes its least-squares path, which the kernels do not implement);
* every cost is a ``CostModelResidual`` in the cost stack with an activation of the quadratic-barrier family, and
  every active one's residual is of a kind the Euler node's kernels evaluate without control
  (``ResidualModelState``, ``ResidualModelFramePlacement``, ``ResidualModelFrameTranslation``,
  ``ResidualModelFrameRotation``, ``ResidualModelFrameVelocity``, ``ResidualModelCoMPosition``,
  ``ResidualModelCentroidalMomentum``, all at the state before the impulse), or a force residual
  on an active impulse (``ResidualModelContactForce``, ``ResidualModelContactFrictionCone``,
  ``ResidualModelContactWrenchCone``, ``ResidualModelContactCoPPosition``: rows of the impulses ``Λ``), or the
  centre-of-mass velocity jump ``ResidualModelImpulseCoM`` (their Jacobians follow the impulses' derivatives, as
  cost items and as constraint rows).

The costs are those of a node without control when the costs were built with ``nu > 0`` (as the Python model
evaluates them) or at the terminal node.  The node has no rollout step: the rollout calls its ``calc``, and it
stays out of the Euler nodes' horizon (whose ranges stop at it).  :meth:`ImpulseNode.refresh` (when a solve makes its
selection of compiled nodes; :meth:`ImpulseNode.refresh_live` when it reuses it) re-reads the lowered Pinocchio model,
the armature (the Pinocchio model's plus the impulse model's), ``r_coeff``, the damping, the cost stack's items,
weights and bounds, the residuals' references and the data arrays' addresses.  Evaluators are cached per node data
(weakly).
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Sequence

import numpy as np

from crocopy.not_compiled import class_reason, decline
from crocopy.versioning import ParametersVersion, parameter_owners

from ..impulses import ImpulseModel3D, ImpulseModel6D
from ..state_multibody import StateMultibody
from . import impulse_node_kernel as kernel
from . import node_table as table
from .constraint_rows import ConstraintRows
from .contact_lowering import force_item, frame_rows
from .joint_types import NotLowerable
from .live_parameters import frozen, layout_touched, read_parameters, values_touched
from .lowered_model import Lowered, lowered, table_entries
from .lowering import RigidBodyModel
from .node_kinds import residual_kind
from .stack_items import compiled_items

IMPULSES = (ImpulseModel3D, ImpulseModel6D)
"""The impulse classes compiled impulse nodes take (exact classes)."""
KINDS = (table.STATE, table.PLACEMENT, table.TRANSLATION, table.ROTATION, table.VELOCITY, table.COM, table.CENTROIDAL,
         table.CONE, table.FORCE, table.IMPULSE_COM)
"""The residual kinds of :mod:`.euler_node_kernel` an impulse node evaluates (no control; the force residuals read
its impulses, their items flagged so that the kernel keeps a contact force's value at this node without control)."""
RB_GRAVITY = RigidBodyModel._fields.index("gravity") - 4
"""Entry of the gravity (each impulse node's own zero vector: the RNEA derivatives of the impulse run without it)."""

_NODES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
"""Node data → its :class:`ImpulseNode`."""


def impulse_node(model, data, terminal: bool, memo: dict) -> ImpulseNode | None:
    """The refreshed evaluator of the impulse node ``(model, data)``, or None if it does not qualify (the reason
    recorded in ``memo``, :mod:`crocopy.not_compiled`; the caller has checked the model's own class)."""
    if type(model.state) is not StateMultibody:
        return decline(memo, class_reason(model.state, "state"))
    impulses = [m for _, m in model.impulses._active]
    other = next((m for m in impulses if type(m) not in IMPULSES), None)
    if other is not None:
        return decline(memo, class_reason(other, "impulse"))
    if impulses and model._damping == 0.0 and model.impulses._shared_joints:
        return decline(memo, "redundant impulses")
    low = lowered(model.state.pinocchio, memo)
    if low is None:
        return decline(memo, memo[id(model.state.pinocchio), NotLowerable])
    node = _NODES.get(data)
    if node is None or node.model is not model or node.terminal != terminal or node.nv != low.rb.nv \
            or node.impulses != _ints(impulses):
        node = ImpulseNode(model, data, terminal, low.rb.nv, impulses)
        _NODES[data] = node
    return node if node.refresh(low, memo) else None


def _compiled_parameters(kind: int, residual) -> Sequence[float]:
    """A residual's parameters in the layout the kernels read (every kind an impulse node takes has them)."""
    return residual.compiled_parameters()


def _ints(impulses: list) -> list[int]:
    """``(frame, rows, reference frame, first row)`` of each impulse, flat (:data:`.node_table.CONTACT_FIELDS`)."""
    ints, row = [], 0
    for m in impulses:
        reference = table.LOCAL if int(m.type) == table.LOCAL else table.LOCAL_WORLD_ALIGNED
        ints += [int(m.id), int(m.nc), reference, row]
        row += m.nc
    return ints


class ImpulseNode:
    """The compiled ``calc``/``calcDiff`` of one impulse node (see the module docstring).

    ``calc(x, u)`` writes ``data.xnext`` and ``data.cost``; ``calcDiff(x, u, synced)`` also ``Fx``, ``Lx`` and
    ``Lxx`` (``Fu``, ``Lu``, ``Lxu``, ``Luu`` have no entries) and the cost stack's residuals, Jacobians and
    activation derivatives.
    """

    refreshes = 0
    """How many times :meth:`refresh` ran (a selection of compiled nodes made before the last one is stale)."""

    def __init__(self, model, data, terminal: bool, nv: int, impulses: list) -> None:
        self.model = model
        self.terminal = terminal
        self._data = weakref.ref(data)
        self.nv = nv
        self.impulses = _ints(impulses)
        self.nc = sum(m.nc for m in impulses)
        self.armature = np.zeros(nv)
        self.gravity = np.zeros(6)
        self._model_entries = (table_entries([self.armature]), table_entries([self.gravity]))
        ndx, n = 2 * nv, len(impulses)
        self.own = {"dx": np.zeros(ndx), "a": np.zeros(nv), "dFx": np.zeros((nv, ndx)), "dFu": np.zeros((nv, 0)),
                    "Minv": np.zeros((nv, nv)), "dLx": np.zeros(ndx), "dLu": np.zeros(0),
                    "dLxx": np.zeros((ndx, ndx)), "dLxu": np.zeros((ndx, 0)), "dLuu": np.zeros((0, 0)),
                    "S": np.zeros((nv, 0)), "gains": np.zeros((n, 2)), "ref_R": np.zeros((n, 3, 3)),
                    "ref_p": np.zeros((n, 3)), "kin": np.zeros(1), "stamp": np.zeros(0),
                    "user_dims": np.zeros(5, dtype=np.int64), "user_Ru": np.zeros((1, 0))}
        """The table's entries the impulse node does not use or keeps for itself (``dFx``: ``∂v⁺/∂x``)."""
        self.rows = ConstraintRows(0, ndx)
        self.no_control = np.zeros(0)
        self._items: list | None = None
        self._residuals: list = []
        self._data_arrays: list = []
        self._data_entries = (np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64))
        self._lowered: Lowered | None = None
        self._seen = -1
        self._owners: list = []

    @property
    def stack_terminal(self) -> bool:
        """Whether the costs are evaluated without control: at the terminal node, or costs built with ``nu > 0``."""
        return self.terminal or self.model.costs.nu != 0

    def refresh(self, low: Lowered, memo: dict) -> bool:
        """Re-read the models' parameters and the data arrays' addresses; False if the node no longer qualifies (the
        reason recorded in ``memo``).  The items are read again when the layout of an object reachable from the model
        was touched since this node last read them (:func:`~crocopy.versioning.changes_since`); the references,
        ``r_coeff``, the damping and the armature at every call."""
        data, model = self._data(), self.model
        stack = data.costs.stack
        changed = stack.refresh_if_stale(self.stack_terminal) or self._items is None \
            or layout_touched(self)
        if changed:
            why = self._read_items(stack, data)
            if why is not None:
                decline(memo, why)
                return False
            self._owners = parameter_owners(model)
        self._seen = ParametersVersion.value
        par = [float(model.r_coeff), float(model._damping)]
        live = read_parameters([(0, r) for r in self._residuals], par, _compiled_parameters)
        self.par = np.array(par)
        np.add(low.rb.armature, model.armature, out=self.armature)
        self._table(low, data, stack, changed)
        self._live = (live, not frozen(model.armature))
        self._low_version = low.version
        self.refreshes += 1
        return True

    def refresh_values(self, memo: dict) -> bool:
        """After the parameter clock moved: False (the node must be refreshed) when what the node read as its layout
        was touched since (:func:`~crocopy.versioning.changes_since`); else re-read in place the live parameters
        (:meth:`refresh_live`), and if an object of the node was touched, the touched residuals' parameters,
        ``r_coeff``, the damping and the armature."""
        touched = values_touched(self, self._items is not None, memo)
        if not touched:
            return touched is not None
        data, low, model = self._data(), self._lowered, self.model
        if data is None or low.version != self._low_version or not low.current(memo):
            return False
        if data.costs.stack.refresh_if_stale(self.stack_terminal):
            self._items = None  # read the items again
            return False
        self.par[0], self.par[1] = float(model.r_coeff), float(model._damping)
        if not self._live[0].reread_since(self.par, self._seen):
            self._items = None
            return False
        np.add(low.rb.armature, model.armature, out=self.armature)
        self._seen = ParametersVersion.value
        return True

    def refresh_live(self, memo: dict) -> bool:
        """Re-read, in place, what :meth:`refresh` read that may have changed without moving the parameter clock
        (:mod:`.live_parameters`); False when the node must be refreshed instead (its Pinocchio model changed, or its
        cost stack was evaluated for the other node kind since)."""
        low = self._lowered
        if low.version != self._low_version or not low.current(memo):
            return False
        data = self._data()
        live, armature = self._live
        if data is None or data.costs.stack.refresh_if_stale(self.stack_terminal) or not live.reread(self.par):
            self._items = None  # read the items again
            return False
        if armature:
            np.add(low.rb.armature, self.model.armature, out=self.armature)
        return True

    def _read_items(self, stack, data) -> str | None:
        """Read the compiled items of the cost stack; returns None, or why the node cannot compile."""
        self._items = None
        items, residuals, offset = [], [], 2
        impulse_rows = frame_rows(self.impulses)
        for entry in compiled_items(stack, data.costs, self.model.costs):
            if isinstance(entry, str):
                return entry
            residual, _, rows = entry
            kind = residual_kind(residual)
            if kind not in KINDS:
                return class_reason(residual, "residual") + " in an impulse node"
            frame, reference, flags = getattr(residual, "id", 0), int(residual.type) if kind == table.VELOCITY else 0, 0
            if kind == table.CONE or kind == table.FORCE:
                found = force_item(residual, impulse_rows)
                if found is None:
                    return class_reason(residual, "residual") + " without its active impulse"
                (frame, reference), flags = found, 1
            items += [kind, rows.start, rows.stop - rows.start, frame, reference, offset, flags, 0, 0, 0]
            residuals.append(residual)
            offset += len(residual.compiled_parameters())
        manager = self.model.constraints
        why = ConstraintRows.sized(manager, data, data) or self.rows.read(
            manager, manager is not None and manager.nu != 0, residual_kind, offset,
            lambda kind, residual: residual.compiled_parameters() if kind in KINDS else [], impulse_rows, True)
        if why is not None:
            return why
        other = next((r for kind, r in self.rows.residuals if kind not in KINDS), None)
        if other is not None:
            return class_reason(other, "constraint residual") + " in an impulse node"
        self._items, self._residuals = items, residuals + [r for _, r in self.rows.residuals]
        return None

    def _table(self, low: Lowered, data, stack, changed: bool) -> None:
        """The addresses and dimensions of every array the kernels read or write (the Euler node's layout,
        :mod:`.node_table`), and the integer program."""
        no_u = stack.Ju.shape[1] != 0  # costs built with nu > 0: their u columns are never read
        Ju = np.zeros((stack.Ju.shape[0], 0)) if no_u else stack.Ju
        fields = {
            "xnext": data.xnext, "Fx": data.Fx, "Fu": data.Fu, "Lx": data.Lx, "Lu": data.Lu, "Lxx": data.Lxx,
            "Lxu": data.Lxu, "Luu": data.Luu, "r": stack.r, "lb": stack.lb, "ub": stack.ub,
            "act_weights": stack.act_weights, "item_costs": stack.item_costs, "item_weights": stack.item_weights,
            "weights": stack.weights, "Ar": stack.Ar, "Arr": stack.Arr, "Jx": stack.Jx, "Ju": Ju, "cols": stack.cols,
            "grad": stack.grad, "act_kinds": stack.act_kinds, "act_params": stack.act_params, **self.own,
            **self.rows.fields(data, data),
        }
        n = table.NODE + len(table.NODE_ARRAYS) + len(table.SCRATCH_ARRAYS)
        self.rows.allocate(n, table.SHAPES + 3 * n + len(self._items) + len(stack.starts) + len(self.impulses))
        fields.update(self.rows.arrays)
        scratch_entries = low.scratch(0, self.nc)[1]
        arrays = [fields[e.name] for e in table.NODE_ARRAYS]
        known = self._data_arrays
        if len(known) != len(arrays) or any(a is not b for a, b in zip(arrays, known)):
            state = self.model.state
            sizes = {"nx": state.nx, "ndx": state.ndx, "nv": state.nv, "nu": 0, "nr": stack.r.shape[0],
                     "nr_u": stack.r.shape[0] - stack.u_start, "n_stack": stack.item_costs.shape[0],
                     "n_cols": stack.cols.shape[0], "n_contacts": len(self.impulses) // table.CONTACT_FIELDS,
                     "n_kin": 1, "nr_user": 1, "n_stamp": 0, **self.rows.sizes(data)}
            table.check_arrays(table.NODE_ARRAYS, arrays, sizes)
            self._data_entries = table_entries(arrays)
            self._data_arrays = arrays
        elif not changed and low is self._lowered:
            return
        rb, items = low.rb, self._items
        (armature, armature_shape), (gravity, gravity_shape) = self._model_entries
        a, g = table.RB_ARMATURE, RB_GRAVITY
        parts = [(low.addresses[:a], low.shapes[:3 * a]), (armature, armature_shape),
                 (low.addresses[a + 1:g], low.shapes[3 * a + 3:3 * g]), (gravity, gravity_shape),
                 (low.addresses[g + 1:], low.shapes[3 * g + 3:]), low.workspace_entries, self._data_entries,
                 scratch_entries]
        addresses = np.concatenate([p[0] for p in parts])
        shapes = np.concatenate([p[1] for p in parts])
        header = np.zeros(table.SHAPES, dtype=np.int64)
        header[[table.NQ, table.NV, table.NU, table.U_START]] = rb.nq, rb.nv, 0, stack.u_start
        header[[table.N_ITEMS, table.NJOINTS, table.NFRAMES, table.N_STACK]] = (
            len(items) // table.ITEM_FIELDS, rb.njoints, rb.nframes, len(stack.starts))
        header[table.ITEMS] = table.SHAPES + 3 * addresses.shape[0]
        header[table.STARTS] = header[table.ITEMS] + len(items)
        header[table.TERMINAL] = 1
        header[table.N_CONTACTS] = len(self.impulses) // table.CONTACT_FIELDS
        header[table.CONTACTS] = header[table.STARTS] + len(stack.starts)
        header[table.NC] = self.nc
        self.ints = np.concatenate([header, shapes, np.array(items, dtype=np.int64),
                                    np.asarray(stack.starts, dtype=np.int64), np.array(self.impulses, dtype=np.int64)])
        self.tbl = addresses
        self.rows.constraint_ints(self.ints)
        self._lowered = low

    def calc(self, x: np.ndarray, u: np.ndarray | None) -> None:
        self._keep(kernel.impulse_calc(self.tbl, self.ints, self.par, x, self.no_control), x, u, False)

    def calcDiff(self, x: np.ndarray, u: np.ndarray | None, synced: bool) -> None:
        self._keep(kernel.impulse_calc_diff(self.tbl, self.ints, self.par, x, self.no_control), x, u, True)

    def _keep(self, cost: float, x: np.ndarray, u: np.ndarray | None, derivatives: bool) -> None:
        """Store the kernel's ``cost``, or, where its post-impact state is not finite (an impulse set singular at
        this state: the Python path takes least squares there, as with kernels off), evaluate the node on its Python
        path."""
        data = self._data()
        if math.isfinite(cost) and np.isfinite(data.xnext).all():
            data.cost = cost
            return
        self.model._raw_calc(data, x, u)
        if derivatives:
            self.model._raw_calcDiff(data, x, u)
