"""Data fields that own their storage: assigning one copies into the array ``createData`` made.

Crocoddyl's bindings copy an assigned matrix into the data's existing one (``data.Fx = M`` writes
``M``'s values where ``data.Fx`` already was).  :class:`Stored` gives a data class that semantics:
the first assignment (in the data's constructor) binds the array, every later one copies into it, so
the address of a data array never changes after ``createData`` and anything holding it (the solvers'
compiled passes, a compiled node's table) never needs to look again.  Reading costs what reading a
plain attribute does (the descriptor has no ``__get__``).  A value of another shape raises
``ValueError`` naming the field, unless it only differs by unit dimensions (a column vector for a
vector).  :func:`bind` is the constructors' way to make a field share another data's memory.
"""

from __future__ import annotations

from typing import Any

import numpy as np


class Stored:
    """Data descriptor: ``data.name = value`` copies ``value`` into ``data.name`` once it exists."""

    def __set_name__(self, owner: type, name: str) -> None:
        self._name = name

    def __set__(self, obj: Any, value: Any) -> None:
        held = obj.__dict__.get(self._name)
        if held is None:
            obj.__dict__[self._name] = value
        else:
            copy_into(held, value, f"data.{self._name}")

    def __delete__(self, obj: Any) -> None:
        raise AttributeError(f"data.{self._name} cannot be deleted: the data owns it")


def copy_into(held: np.ndarray, value: Any, name: str) -> None:
    """Copy ``value`` into ``held`` (same shape, or the same entries with unit dimensions added or dropped).

    Raises
    ------
    ValueError
        If ``value`` does not have ``held``'s shape.
    """
    values = np.asarray(value, dtype=held.dtype)
    if values.shape != held.shape:
        if values.size != held.size or _squeezed(values.shape) != _squeezed(held.shape):
            raise ValueError(f"{name} has shape {held.shape}: cannot assign a value of shape {values.shape}")
        values = values.reshape(held.shape)
    np.copyto(held, values)


def _squeezed(shape: tuple) -> tuple:
    return tuple(n for n in shape if n != 1)


def bind(data: Any, name: str, array: np.ndarray) -> None:
    """Make ``data.name`` the array ``array`` itself (a constructor sharing memory between datas)."""
    data.__dict__[name] = array
