"""Crocoddyl's list of vectors (``StdVec_VectorXs``) as a Python list.

Crocoddyl's solvers return ``xs``, ``us`` and ``fs`` as ``StdVec_VectorXs``, a list-like
container whose ``tolist()`` gives a plain list of array copies; scripts call it, e.g. to save
or plot a trajectory.  :class:`StdVec_VectorXs` is a ``list`` (indexing, slicing, ``len``,
assignment of any sequence keep working) with that ``tolist()``; :class:`StdVecAttribute` makes a
solver attribute hold one whatever sequence is assigned to it.
"""

from __future__ import annotations

from typing import Any

import numpy as np


class StdVec_VectorXs(list):
    """List of arrays with Crocoddyl's ``tolist()`` and ``copy()``."""

    def tolist(self) -> list[np.ndarray]:
        """A plain list of copies of the arrays."""
        return [np.array(v, dtype=float) for v in self]

    def copy(self) -> StdVec_VectorXs:
        """A shallow copy (same arrays), of the same type."""
        return StdVec_VectorXs(self)


class StdVecAttribute:
    """Descriptor: the attribute always holds a :class:`StdVec_VectorXs` (assigned sequences are wrapped).

    It only intercepts assignment and stores the value in the instance's ``__dict__`` under the
    same name, so reading the attribute costs what reading a plain attribute does.
    """

    def __set_name__(self, owner: type, name: str) -> None:
        self._name = name

    def __set__(self, obj: Any, value: Any) -> None:
        obj.__dict__[self._name] = value if type(value) is StdVec_VectorXs else StdVec_VectorXs(value)
