"""One cache-invalidation scheme for model parameters.

Some data cache what they derive from model parameters: a cost sum's stack holds the weights,
activity and activation bounds of its items (:mod:`crocopy.costs.stack`), a contact set holds the
Pinocchio constraint models built from its contacts' references and gains
(``crocopy.models.ContactModelMultiple``).  Every such parameter changes through a setter that calls
:func:`touch` on the object it belongs to: one global clock, ``ParametersVersion.value``, moves on
by one, and the object is stamped with the new value (``_stamp``; 0 for an object never touched), and with it its
layout (``_layout_stamp``) unless only values of a fixed length changed (a class's ``_value_attributes``: what
compiled nodes re-read at every solve; :func:`changes_since` tells the two apart over a node's objects).
Registries of named items (:mod:`crocopy.named_items`) touch themselves when an item is added,
removed, activated or deactivated.  The model classes derive :class:`Parametrized`: assigning any public
attribute of a model (a property setter such as ``residual.id`` or ``dam.armature``, or a plain attribute)
touches it, so no setter can be forgotten; the attributes Crocoddyl makes read-only (``state``,
``actuation``, ``differential``, ``costs``, ...) raise ``AttributeError`` once set.

A cache keeps a :class:`ParametersSeen`: the clock value it was filled at.  It is up to date when
the clock has not moved (one comparison), or when none of the objects it was filled from carries a
newer stamp.  Parameter arrays are read-only (:func:`frozen_copy`): an in-place write would bypass
the setters, so it raises instead.
"""

from __future__ import annotations

import weakref
from collections.abc import Callable, Iterable, Iterator

import numpy as np


class ParametersVersion:
    """The clock: moves on at every parameter change anywhere (see :func:`touch`)."""

    value = 0


def touch(owner: object, layout: bool = True) -> None:
    """Record that a parameter of ``owner`` changed: advance the clock and stamp ``owner`` with it (``_stamp``).
    ``layout=False``: only parameter values changed, in number as before (a reference, a time step:
    :attr:`Parametrized._value_attributes`); the layout stamp (``_layout_stamp``, :func:`changes_since`) stays."""
    ParametersVersion.value += 1
    object.__setattr__(owner, "_stamp", ParametersVersion.value)
    if layout:
        object.__setattr__(owner, "_layout_stamp", ParametersVersion.value)


def frozen_copy(values: np.ndarray) -> np.ndarray:
    """A read-only float copy of ``values`` (parameters change through setters only)."""
    out = np.array(values, dtype=float)
    out.setflags(write=False)
    return out


STRUCTURE = [0]
"""``STRUCTURE[0]`` moves on at every change of a registry's item set (a cost, constraint, contact or impulse added or
removed, a contact, impulse or constraint switched on or off): the changes that leave the datas made before them
with the wrong shape (:func:`structure_changed`)."""

_MADE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
"""Registry model → the datas it made (weakly)."""

_STALE: weakref.WeakSet = weakref.WeakSet()
"""The datas made stale by :func:`structure_changed` that are still alive (weakly): while it is empty no node data
can hold a stale one (:func:`any_stale`)."""


def made_from(model: object, data: object) -> None:
    """Record that ``model`` (a registry of named items) made ``data``; ``data.structure_stale`` starts False."""
    data.structure_stale = False
    _MADE.setdefault(model, weakref.WeakSet()).add(data)


def structure_changed(model: object) -> None:
    """``model``'s item set changed: every data it made so far is stale (``structure_stale``), and the clock
    :data:`STRUCTURE` moves on so that a problem looks for such datas before its next evaluation."""
    STRUCTURE[0] += 1
    for data in _MADE.get(model, ()):
        data.structure_stale = True
        _STALE.add(data)


def any_stale() -> bool:
    """Whether a data made stale by :func:`structure_changed` is still alive (a building step that adds items to
    models whose datas are not made yet moves :data:`STRUCTURE` without making any)."""
    return len(_STALE) > 0


def _reachable(root: object) -> Iterator[object]:
    """The objects of crocopy's classes reachable from ``root`` through their attributes, lists, tuples and dicts,
    once each (``root`` first when it is one)."""
    seen: set[int] = set()
    stack = [root]
    while stack:
        obj = stack.pop()
        if id(obj) in seen:
            continue
        seen.add(id(obj))
        if isinstance(obj, dict):
            stack.extend(obj.values())
        elif isinstance(obj, list | tuple):
            stack.extend(obj)
        elif type(obj).__module__.startswith("crocopy") and hasattr(obj, "__dict__"):
            yield obj
            stack.extend(obj.__dict__.values())


def holds_stale_data(data: object) -> bool:
    """Whether ``data`` (a node's data) or a data nested in it (attributes, lists and dicts of crocopy's data
    classes) was made by a registry whose item set changed since (:func:`structure_changed`)."""
    return any(obj.__dict__.get("structure_stale", False) for obj in _reachable(data))


def parameter_owners(root: object) -> list[object]:
    """Every object reachable from ``root`` (a node's model) through the attributes, lists, tuples and dicts of
    crocopy's classes, once each: the objects whose layout stamps tell whether something a compiled node read from
    ``root`` as its layout (items, frames, rows) may have changed (:func:`changes_since`).  A nested object replaced
    by another is an assignment to its owner, which is in the list: the list holds until one of its stamps moves."""
    return list(_reachable(root))


VALUES, LAYOUT = 1, 2
"""What :func:`changes_since` found: value attributes only were assigned, or something else (0: nothing)."""


def touched_since(owners: Iterable[object], value: int) -> list[object] | None:
    """The ``owners`` (:func:`parameter_owners`) touched after the clock read ``value``, in order, or None if one of
    them was touched other than by a value attribute (its layout)."""
    touched = []
    for owner in owners:
        stamps = owner.__dict__
        if stamps.get("_layout_stamp", 0) > value:
            return None
        if stamps.get("_stamp", 0) > value:
            touched.append(owner)
    return touched


def changes_since(owners: Iterable[object], value: int) -> int:
    """What changed among ``owners`` after the clock read ``value`` (:func:`touched_since`): :data:`LAYOUT` if one
    was touched other than by a value attribute, else :data:`VALUES` if one was touched, else 0."""
    touched = touched_since(owners, value)
    return LAYOUT if touched is None else VALUES if touched else 0


class Parametrized:
    """Mixin of model classes: assigning a public attribute touches the model (:func:`touch`), and the names in
    ``_read_only`` can be assigned once (by the constructor), as in Crocoddyl's bindings.  The names in
    ``_value_attributes`` hold parameter values only (an array of fixed length, a number), which compiled nodes
    re-read at every solve: assigning one touches the model without moving its layout stamp."""

    __slots__ = ()
    _read_only: frozenset[str] = frozenset()
    _value_attributes: frozenset[str] = frozenset()

    def __setattr__(self, name: str, value: object) -> None:
        if name[0] == "_":
            object.__setattr__(self, name, value)
            return
        if name in self._read_only and name in self.__dict__:
            raise AttributeError(
                f"{type(self).__name__}.{name} is read-only (as in Crocoddyl): build a new model with the new {name}"
            )
        object.__setattr__(self, name, value)
        touch(self, name not in self._value_attributes)

    def __getstate__(self) -> dict:
        """Copy and pickle without the stamps: a clock value means nothing in another process or object (a copy is
        a model never touched, as :class:`ParametersSeen` copies as never filled)."""
        state = self.__dict__.copy()
        state.pop("_stamp", None)
        state.pop("_layout_stamp", None)
        return state


class ParametersSeen:
    """The clock value a cache was filled at (``-1``: never filled)."""

    __slots__ = ("value",)

    def __init__(self) -> None:
        self.value = -1

    def __reduce__(self) -> tuple:
        """Copy and pickle as never filled: a clock value means nothing in another process or object."""
        return ParametersSeen, ()

    def stale(self, sources: Callable[[], Iterable[object]]) -> bool:
        """True if the cache must be filled again: never filled, or one of ``sources()`` was touched since.

        ``sources`` is called only when the clock has moved since the cache was filled.
        """
        now = ParametersVersion.value
        if self.value == now:
            return False
        if self.value < 0 or any(getattr(s, "_stamp", 0) > self.value for s in sources()):
            return True
        self.value = now
        return False

    def filled(self) -> None:
        """Mark the cache as filled from the current parameters."""
        self.value = ParametersVersion.value
