"""The lowered Pinocchio models the compiled nodes read (:mod:`.euler_node`, :mod:`.impulse_node`,
:mod:`.invdyn_node`), kept from solve to solve.

:func:`lowered` lowers a ``pinocchio.Model`` (:func:`.lowering.lower_model`) once per solve into a :class:`Lowered`:
its arrays, their addresses and dimensions (the first entries of every node's table, :mod:`.node_table`), the
workspace and the scratch shared by the model's nodes (and each extra thread's copies).  The arrays keep their
addresses: when the model changed in place (it no longer equals the copy taken when it was lowered,
:meth:`Lowered.current`), its new values are copied into them.  :func:`table_entries` gives the ``(addresses,
dimensions)`` of a list of arrays, as the tables list them.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from crocopy.kernels import checked_address

from . import node_table as table
from .joint_types import NotLowerable
from .lowering import RigidBodyModel, lower_model, make_workspace


class Lowered:
    """A lowered Pinocchio model with the addresses and dimensions of its arrays (the first entries of every
    node's table, see :mod:`.euler_node_kernel`; the armature's entry is each node's own)."""

    version = 0
    """How many times :meth:`update` rewrote the arrays (a node compares it with the one it read them at)."""
    source: tuple = ()
    """``(model, copy)``: the Pinocchio model lowered and a copy of it taken then (:meth:`current`)."""

    def __init__(self, rb: RigidBodyModel) -> None:
        self.rb = rb
        self.addresses, self.shapes = table_entries([getattr(rb, name) for name in rb._fields[4:]])
        self.workspace = make_workspace(rb)
        self.workspace_entries = table_entries(list(self.workspace))
        self._scratch: dict[tuple[int, int], tuple[dict, tuple]] = {}
        self._threads: dict[tuple[int, int, int], tuple] = {}

    def scratch(self, nu: int, nc: int) -> tuple[dict, tuple[np.ndarray, np.ndarray]]:
        """The arrays of :data:`.node_table.SCRATCH_ARRAYS` (and a ``Minv`` for a data without one) shared by
        the nodes of this model with ``nu`` controls and ``nc`` contact rows, with their table entries."""
        key = (nu, nc)
        if key not in self._scratch:
            nv = self.rb.nv
            arrays = table.make_arrays(table.SCRATCH_ARRAYS, {"nv": nv, "ndx": 2 * nv, "nu": nu, "nc": nc})
            arrays["Minv"] = np.zeros((nv, nv))
            self._scratch[key] = arrays, table_entries([arrays[e.name] for e in table.SCRATCH_ARRAYS])
        return self._scratch[key]

    def thread_entries(self, c: int, nu: int, nc: int) -> tuple[np.ndarray, np.ndarray]:
        """The addresses of the workspace and of the scratch (with ``Minv`` last) of extra thread ``c >= 1`` for the
        nodes with ``nu`` controls and ``nc`` contact rows (their own copies, kept here)."""
        key = (c, nu, nc)
        if key not in self._threads:
            nv = self.rb.nv
            workspace = make_workspace(self.rb)
            arrays = table.make_arrays(table.SCRATCH_ARRAYS, {"nv": nv, "ndx": 2 * nv, "nu": nu, "nc": nc})
            arrays["Minv"] = np.zeros((nv, nv))
            listed = [arrays[e.name] for e in table.SCRATCH_ARRAYS] + [arrays["Minv"]]
            self._threads[key] = (table_entries(list(workspace))[0], table_entries(listed)[0], workspace, arrays)
        return self._threads[key][:2]

    def update(self, rb: RigidBodyModel) -> bool:
        """Copy ``rb``'s values into this model's arrays (their addresses stay); False if a size differs."""
        names = self.rb._fields[4:]
        if tuple(self.rb[:4]) != tuple(rb[:4]) or any(getattr(self.rb, n).shape != getattr(rb, n).shape for n in names):
            return False
        for name in names:
            np.copyto(getattr(self.rb, name), getattr(rb, name))
        self.version += 1
        return True

    def current(self, memo: dict) -> bool:
        """Whether the Pinocchio model still equals the copy taken when it was lowered (Pinocchio's own ``==``, which
        compares every field in C++: about 1 µs for an arm, 4 µs for a humanoid), once per ``memo`` (one solve)."""
        key = ("current", id(self))
        if key not in memo:
            memo[key] = bool(self.source and self.source[0] == self.source[1])
        return memo[key]


_LOWERED: dict[int, tuple[pin.Model, Lowered]] = {}
"""``id(model)`` → the model and its :class:`Lowered`, whose arrays are rewritten when the model changed."""


def lowered(model: pin.Model, memo: dict) -> Lowered | None:
    """The lowered ``model``, its values read once per ``memo`` (one solve) into arrays that keep their
    addresses from solve to solve (read again only when the model no longer equals the copy kept when it was last
    lowered, :meth:`Lowered.current`); None if it does not lower."""
    key = id(model)
    if key in memo:
        return memo[key]
    cached = _LOWERED.get(key)
    if cached is not None and cached[0] is model and cached[1].current(memo):
        memo[key] = cached[1]
        return cached[1]
    try:
        rb = lower_model(model)
    except NotLowerable as exc:
        memo[key] = None
        memo[key, NotLowerable] = exc.reason
        return None
    if cached is not None and cached[0] is model and cached[1].update(rb):
        low = cached[1]
    else:
        if len(_LOWERED) > 16:
            _LOWERED.clear()
        low = Lowered(rb)
        _LOWERED[key] = (model, low)
    low.source = (model, model.copy())
    memo["current", id(low)] = True
    memo[key] = low
    return low


def table_entries(arrays: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """``(addresses, dimensions)`` of ``arrays``: shapes ``(n,)`` and ``(3 n,)`` (unused dimensions zero)."""
    shapes = np.zeros(3 * len(arrays), dtype=np.int64)
    for k, a in enumerate(arrays):
        shapes[3 * k: 3 * k + a.ndim] = a.shape
    return np.array([checked_address(a) for a in arrays], dtype=np.int64), shapes
