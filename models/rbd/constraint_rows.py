"""A compiled node's constraint manager, lowered to residual items and a program of rows.

A ``ConstraintModelManager`` on a compiled node (:mod:`.euler_node`) stacks its active constraints, ordered by name,
into the inequality rows ``g (ng,)``, ``Gx (ng, ndx)``, ``Gu (ng, nu)`` and the equality rows ``h (nh,)``,
``Hx (nh, ndx)``, ``Hu (nh, nu)`` (Crocoddyl's semantics, :mod:`crocopy.constraints`): at the terminal node only the
constraints with ``T_constraint`` count, they fill the first rows, the rows after them are zero and so are ``Gu``,
``Hu``.  :class:`ConstraintRows` reads such a manager into what :mod:`.constraint_rows_kernel` evaluates: one
residual item per constraint (the cost items' kinds and fields, :mod:`.node_table`; rows in the node's own ``cr``,
``cJx``, ``cJu``), their parameters after the cost items' in ``par``, and the program ``(equality, first row, rows)``
per constraint.  The bounds ``lb``/``ub`` are not the node's: the solvers read them from the models.

A constraint qualifies when it is a ``ConstraintModelResidual`` (exact class: a subclass may override ``calc``) whose
residual is of a compiled kind: state, control, frame placement, translation, rotation, velocity, centre of mass, the
friction and wrench cones of an active contact, a user's ``ResidualModelNumba``; at the terminal node its residual
must not read the control (a user's gets an empty ``u``) or the contact forces.  A manager whose data was made for
another active set (the Python path raises there, naming it) keeps the node on the Python path.
"""

from __future__ import annotations

import numpy as np

from crocopy.constraints.base import ConstraintModelResidual
from crocopy.not_compiled import class_reason

from . import node_table as table
from .contact_lowering import force_item

TERMINAL_KINDS = (table.STATE, table.PLACEMENT, table.TRANSLATION, table.ROTATION, table.VELOCITY, table.COM,
                  table.USER)
"""The residual kinds a terminal node's constraints may have (neither the control nor the contact forces; a user's
residual is called with an empty ``u``, as in a terminal cost)."""


_EMPTY: dict[tuple[int, int], dict[str, np.ndarray]] = {}
"""The constraint arrays without rows of the nodes of ``(nu, ndx)`` (empty, so shared: nothing is ever written)."""


def _empty(nu: int, ndx: int) -> dict[str, np.ndarray]:
    """The node's constraint arrays without rows (a new dict of the shared empty arrays)."""
    key = (nu, ndx)
    if key not in _EMPTY:
        _EMPTY[key] = {"c_tbl": np.zeros(0, dtype=np.int64), "c_ints": np.zeros(0, dtype=np.int64),
                       "c_rows": np.zeros(0, dtype=np.int64), "cr": np.zeros(0), "cJx": np.zeros((0, ndx)),
                       "cJu": np.zeros((0, nu))}
    return dict(_EMPTY[key])


class ConstraintRows:
    """The lowered constraint manager of one compiled node (see the module docstring).

    Parameters
    ----------
    nu, ndx : int
        The node's control and tangent dimensions.
    """

    def __init__(self, nu: int, ndx: int) -> None:
        self.nu, self.ndx = nu, ndx
        self.arrays = _empty(nu, ndx)
        """The node's own arrays of the table (``c_tbl``, ``c_ints``, ``c_rows``, ``cr``, ``cJx``, ``cJu``)."""
        self.items: list[int] = []
        self.residuals: list = []
        """``(kind, residual)`` of each item, in item order (their parameters follow the cost items')."""
        self.user_rows = 0
        """The rows of the largest user residual (``ResidualModelNumba``): the node's ``user_Ru`` holds as many."""

    def read(self, manager, terminal: bool, kind_of, offset: int, parameters, contact_rows: dict,
             impulses: bool = False) -> str | None:
        """Read ``manager`` (or None) of a node (``terminal`` or not): items, parameters from ``offset`` on in ``par``
        (``parameters(kind, residual)`` their values, ``kind_of(residual)`` the kernel's kind or None; a cone's
        contact by its frame in ``contact_rows``: ``frame -> (first row, rows)`` of the active contacts, or of the
        impulses, ``impulses``: their force items flagged, as an impulse node's cost items); returns None, or why the
        node cannot compile (:mod:`crocopy.not_compiled`)."""
        items, residuals, program, row, control_rows, self.user_rows = [], [], [], 0, [], 0
        for item in ([] if manager is None else manager.constraints.values()):
            constraint = item.constraint
            if not item.active or (terminal and not constraint.T_constraint):
                continue
            if type(constraint) is not ConstraintModelResidual:
                return class_reason(constraint, "constraint")
            residual = constraint.residual
            kind = kind_of(residual)
            if kind is None:
                return class_reason(residual, "constraint residual")
            if terminal and kind not in TERMINAL_KINDS:
                return class_reason(residual, "constraint residual") + " at the terminal node"
            nr = residual.nr
            frame, reference = getattr(residual, "id", 0), int(residual.type) if kind == table.VELOCITY else 0
            user = [0, 0, 0, 0]
            if kind == table.USER:
                frame, reference = residual.frame, int(residual.frame_reference)
                user = [residual.flags, *residual.callbacks(), len(parameters(kind, residual))]
                self.user_rows = max(self.user_rows, nr)
            if kind == table.CONE or kind == table.FORCE:
                found = force_item(residual, contact_rows)
                if found is None:
                    return "cone constraint without its active contact"
                frame, reference = found
                user[0] = int(impulses)
            items += [kind, row, nr, frame, reference, offset, *user]
            residuals.append((kind, residual))
            program += [int(constraint.nh > 0), row, nr]
            if kind == table.CONTROL:
                control_rows.append(row)
            offset += len(parameters(kind, residual))
            row += nr
        self.items, self.residuals = items, residuals
        if row != self.arrays["cr"].shape[0] or len(program) != self.arrays["c_rows"].shape[0]:
            self.arrays = {**_empty(self.nu, self.ndx), "c_rows": np.zeros(len(program), dtype=np.int64),
                           "cr": np.zeros(row), "cJx": np.zeros((row, self.ndx)), "cJu": np.zeros((row, self.nu))}
        self.arrays["c_rows"][:] = program
        cJu = self.arrays["cJu"]
        cJu[:] = 0.0
        for start in control_rows:
            cJu[start:start + self.nu] = np.eye(self.nu)
        return None

    @staticmethod
    def sized(manager, data, ddata) -> str | None:
        """None when the datas hold the manager's rows, else why the node keeps its Python path (which raises)."""
        if manager is None:
            return None
        if ddata.g.shape[0] != manager.ng or ddata.h.shape[0] != manager.nh or data.g.shape[0] != manager.ng \
                or data.h.shape[0] != manager.nh:
            return "constraint data made for another active set"
        return None

    def fields(self, data, ddata) -> dict[str, np.ndarray]:
        """The table's constraint entries of the node (action data ``data``, differential data ``ddata``)."""
        return {**self.arrays, "g": data.g, "Gx": data.Gx, "Gu": data.Gu, "h": data.h, "Hx": data.Hx,
                "Hu": data.Hu, "dg": ddata.g, "dGx": ddata.Gx, "dGu": ddata.Gu, "dh": ddata.h, "dHx": ddata.Hx,
                "dHu": ddata.Hu}

    def sizes(self, data) -> dict[str, int]:
        """The sizes the constraint entries are declared over (:func:`.node_table.entry_shapes`)."""
        a = self.arrays
        return {"ng": data.g.shape[0], "nh": data.h.shape[0], "nrc": a["cr"].shape[0], "n_tbl": a["c_tbl"].shape[0],
                "n_c_ints": a["c_ints"].shape[0], "n_c_rows": a["c_rows"].shape[0]}

    def allocate(self, n_tbl: int, n_ints: int) -> None:
        """Make the buffer ``c_tbl`` and the integers ``c_ints`` for a node table of ``n_tbl`` entries and ``n_ints``
        integers (none without rows; kept while their lengths do not change)."""
        rows = self.arrays["c_rows"].shape[0] > 0
        for name, n in (("c_tbl", n_tbl if rows else 0), ("c_ints", n_ints + len(self.items) if rows else 0)):
            if self.arrays[name].shape[0] != n:
                self.arrays[name] = np.zeros(n, dtype=np.int64)

    def constraint_ints(self, ints: np.ndarray) -> None:
        """Fill ``c_ints`` from the node's integers ``ints``: its items, ``U_START = 0``, and the dimensions of
        ``cr``, ``cJx``, ``cJu`` at the entries ``E_R``, ``E_JX``, ``E_JU``."""
        cints = self.arrays["c_ints"]
        if not cints.shape[0]:
            return
        n = ints.shape[0]
        cints[:n] = ints
        cints[n:] = self.items
        cints[table.ITEMS], cints[table.N_ITEMS], cints[table.U_START] = n, len(self.items) // table.ITEM_FIELDS, 0
        for entry, name in ((table.E_R, "cr"), (table.E_JX, "cJx"), (table.E_JU, "cJu")):
            shape = self.arrays[name].shape
            cints[table.SHAPES + 3 * entry: table.SHAPES + 3 * entry + 3] = (*shape, 0, 0)[:3]
