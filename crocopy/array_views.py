"""Arrays shared between data objects: sharing them, and copying or pickling them as shared.

:func:`share_arrays` makes a cost or constraint data write straight into an action data's arrays
(Crocoddyl's ``shareMemory``).  Data objects also hold views: a cost sum makes its residuals'
``r``/``Rx``/``Ru`` and activations' ``Ar``/``Arr_diag`` views into stacked arrays, a squashing
keeps a view of a Jacobian's diagonal.  ``pickle`` and ``copy.deepcopy`` copy a view as a separate
array, so the copy would stop writing where its owner reads.  :class:`KeepsViews` pickles each
view attribute as ``(owner, offset, shape, strides)``; the owner array is pickled once (pickle and
deepcopy keep object identity), and unpickling rebuilds the view on the copied owner.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import numpy as np

from .stored import bind


def share_arrays(holder: Any, data: Any, names: Iterable[str]) -> None:
    """Replace ``holder``'s arrays ``names`` by ``data``'s (same shapes), so ``holder`` writes into ``data``.

    Raises
    ------
    ValueError
        If one of ``data``'s arrays does not have ``holder``'s shape.
    """
    for name in names:
        mine, theirs = getattr(holder, name), getattr(data, name)
        if theirs.shape != mine.shape:
            raise ValueError(f"data.{name} has shape {theirs.shape}, expected {mine.shape}")
    for name in names:
        setattr(holder, name, getattr(data, name))


class ArrayView:
    """The pickled form of an array that views memory owned by the array ``owner``."""

    __slots__ = ("owner", "offset", "shape", "strides", "dtype", "kind")

    def __init__(self, view: np.ndarray, owner: np.ndarray) -> None:
        self.owner = owner
        self.offset = view.__array_interface__["data"][0] - owner.__array_interface__["data"][0]
        self.shape = view.shape
        self.strides = view.strides
        self.dtype = view.dtype
        self.kind = type(view)

    def restore(self) -> np.ndarray:
        """The view, rebuilt on ``owner``."""
        view = np.ndarray(self.shape, self.dtype, buffer=self.owner, offset=self.offset, strides=self.strides)
        return view if self.kind is np.ndarray else view.view(self.kind)


def _encode(value: Any) -> Any:
    """``value`` as an :class:`ArrayView` if it views a C-contiguous array's memory, else unchanged."""
    if not isinstance(value, np.ndarray) or not isinstance(value.base, np.ndarray):
        return value
    owner = value.base
    while isinstance(owner.base, np.ndarray):
        owner = owner.base
    if not owner.flags.c_contiguous:
        return value
    return ArrayView(value, owner)


class KeepsViews:
    """Mixin: ``pickle``/``copy``/``deepcopy`` keep the attributes that are views of other arrays as views."""

    def __getstate__(self) -> dict:
        return {name: _encode(value) for name, value in self.__dict__.items()}

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(
            {name: value.restore() if isinstance(value, ArrayView) else value for name, value in state.items()}
        )


class ShapeTolerantArray(np.ndarray):
    """An array that Python models written for Crocoddyl can index as Crocoddyl shows it.

    Crocoddyl shows an ``n×1`` or ``1×n`` matrix (e.g. ``dtau_du`` or ``Mtau`` with one control) as
    a vector of shape ``(n,)``, so models written from Python for Crocoddyl index such a matrix by
    one key (``Mtau[1] = 1.0`` sets the second entry) and write products of any of these shapes into
    its arrays.  On a matrix with a dimension of length one, a single key (not a tuple) indexes along
    the other dimension; an item assignment also takes a value of the same size whose shape differs
    only by dimensions of length one (``tau[:] = M`` with ``M`` of shape ``(n, 1)``).
    :func:`tolerate_python_model` gives the data of such models these arrays.
    """

    def _as_vector_key(self, key: Any) -> Any:
        """``key`` along the long dimension if it is one vector index (not a tuple, not a mask or index
        array of two or more dimensions) of a matrix with a dimension of length one, else ``key``."""
        if self.ndim != 2 or 1 not in self.shape or isinstance(key, tuple) or key is None:
            return key
        if not isinstance(key, (int, np.integer, slice, type(Ellipsis))) and np.ndim(key) > 1:
            return key
        return (0, key) if self.shape[0] == 1 else (key, 0)

    def __getitem__(self, key: Any) -> Any:
        return super().__getitem__(self._as_vector_key(key))

    def __setitem__(self, key: Any, value: Any) -> None:
        key = self._as_vector_key(key)
        try:
            super().__setitem__(key, value)
        except ValueError:
            target = self[key]
            value = np.asarray(value)
            if value.size != np.size(target) or _squeezed(value.shape) != _squeezed(np.shape(target)):
                raise
            super().__setitem__(key, value.reshape(np.shape(target)))


def _squeezed(shape: tuple) -> tuple:
    return tuple(n for n in shape if n != 1)


def tolerate_python_model(model: Any, data: Any, names: Iterable[str]) -> None:
    """If ``model``'s class is written outside crocopy, make ``data``'s arrays ``names``
    :class:`ShapeTolerantArray` views (same memory)."""
    if type(model).__module__.partition(".")[0] == "crocopy":
        return
    for name in names:
        bind(data, name, getattr(data, name).view(ShapeTolerantArray))
