"""Crocoddyl's list of vectors (``StdVec_VectorXs``) as a Python list.

Crocoddyl's solvers return ``xs``, ``us`` and ``fs`` as ``StdVec_VectorXs``, a list-like
container whose ``tolist()`` gives a plain list of array copies; scripts call it, e.g. to save
or plot a trajectory.  :class:`StdVec_VectorXs` is a ``list`` (indexing, slicing, ``len``,
assignment of any sequence keep working) with that ``tolist()``.  A solver's own trajectories are
:class:`Trajectory` lists of fixed length and fixed arrays: as in Crocoddyl's bindings, ``solver.xs``
is the solver's storage (live: the next solve overwrites it; copy what you keep), and assigning
``solver.xs = ...`` or ``solver.xs[t] = ...`` copies into it (:class:`StdVecAttribute`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..stored import copy_into
from .trajectories import TrajectoryAddresses


class StdVec_VectorXs(list):
    """List of arrays with Crocoddyl's ``tolist()`` and ``copy()``."""

    def tolist(self) -> list[np.ndarray]:
        """A plain list of copies of the arrays."""
        return [np.array(v, dtype=float) for v in self]

    def copy(self) -> StdVec_VectorXs:
        """A shallow copy (same arrays), of the same type."""
        return StdVec_VectorXs(self)


class Trajectory(StdVec_VectorXs):
    """A solver's own trajectory (``xs``, ``us``, ``fs``, ``xs_try``, ``us_try``): one array per node, made when
    the solver is (or when the problem's dimensions change), whose addresses never change after.

    Assigning an entry (``solver.xs[t] = x``) copies ``x`` into the solver's array, as Crocoddyl's bindings do,
    and the length is fixed: ``append``, ``pop``, ``del`` ... raise ``TypeError``.  :meth:`copy` and
    :meth:`tolist` give lists of one's own.
    """

    def __init__(self, arrays, name: str) -> None:
        super().__init__(arrays)
        self.name = name

    def __setitem__(self, key, value) -> None:
        if isinstance(key, slice):
            nodes = range(*key.indices(len(self)))
            values = [np.array(v, dtype=float) for v in value]
            if len(values) != len(nodes):
                raise ValueError(f"solver.{self.name}[{key.start}:{key.stop}] has {len(nodes)} entries: cannot "
                                 f"assign {len(values)} (its length is fixed)")
            for t, v in zip(nodes, values):
                copy_into(list.__getitem__(self, t), v, f"solver.{self.name}[{t}]")
        else:
            copy_into(list.__getitem__(self, key), value, f"solver.{self.name}[{key}]")

    def assign(self, values) -> None:
        """Copy ``values`` (as many arrays as entries, of their shapes) into the entries."""
        values = [np.array(v, dtype=float) for v in values]
        if len(values) != len(self):
            raise ValueError(f"solver.{self.name} has {len(self)} entries: cannot assign {len(values)}")
        for t, v in enumerate(values):
            copy_into(list.__getitem__(self, t), v, f"solver.{self.name}[{t}]")

    def _fixed_length(self, *args, **kwargs):
        raise TypeError(f"solver.{self.name} has a fixed length ({len(self)} entries): assign entries or a whole "
                        f"list of the same length, or copy it first (solver.{self.name}.tolist())")

    append = extend = insert = pop = remove = clear = sort = reverse = __delitem__ = _fixed_length
    __iadd__ = __imul__ = _fixed_length

    def copy(self) -> StdVec_VectorXs:
        """A shallow copy (same arrays) of one's own (a plain :class:`StdVec_VectorXs`)."""
        return StdVec_VectorXs(self)

    def __reduce__(self) -> tuple:
        return Trajectory, (list(self), self.name)


class StdVecAttribute:
    """Descriptor of a solver's :class:`Trajectory`: the first assignment (the solver's constructor) makes it,
    every later one copies the assigned arrays into it (same length and shapes, else ``ValueError`` naming the
    attribute), so that the solver's arrays never move.  :func:`allocate` makes a new one (new dimensions).

    It has no ``__get__``: reading the attribute costs what reading a plain attribute does.
    """

    def __set_name__(self, owner: type, name: str) -> None:
        self._name = name

    def __set__(self, obj: Any, value: Any) -> None:
        held = obj.__dict__.get(self._name)
        if held is None:
            allocate(obj, self._name, value)
        else:
            held.assign(value)


def allocate(obj: Any, name: str, arrays) -> Trajectory:
    """Give ``obj`` a new :class:`Trajectory` ``name`` holding ``arrays`` themselves (the solver's storage)."""
    held = obj.__dict__[name] = Trajectory(arrays, name)
    if name in TrajectoryAddresses.names:  # new arrays whose addresses the solver holds: read them again
        obj.__dict__["_trajectory_addresses"] = None
    return held
