"""Attributes whose rebinding is counted, so that a reader holding their arrays knows when to look again.

The DDP solvers' compiled backward pass (:mod:`crocopy.solvers.horizon`) keeps references to every
running node's derivative arrays (``Fx, Fu, Lxx, Lxu, Luu, Lx, Lu``) and reads them there, one
compiled call per pass.  A model's ``calcDiff`` writes into those arrays in place, but a data
attribute may also be *rebound* (``data.Fx = M``, as a Python model written for Crocoddyl may do,
or a data sharing another's memory).  :class:`Watched` is the class attribute that sees it: it
stores the value in the instance ``__dict__`` like a plain attribute (reading costs what reading a
plain attribute does: the descriptor has no ``__get__``) and increments :data:`generation`, one
counter for the whole process.  A reader compares the counter with the value it saw (one integer
comparison) and looks at the arrays again only when it moved.  Writing into ``__dict__`` directly
bypasses it.
"""

from __future__ import annotations

from typing import Any

generation: list[int] = [0]
"""``generation[0]`` grows by one at every rebinding of a :class:`Watched` attribute, in any object."""


class Watched:
    """Data descriptor: ``obj.name = value`` stores ``value`` in ``obj.__dict__`` and counts a rebinding."""

    def __set_name__(self, owner: type, name: str) -> None:
        self._name = name

    def __set__(self, obj: Any, value: Any) -> None:
        obj.__dict__[self._name] = value
        generation[0] += 1

    def __delete__(self, obj: Any) -> None:
        try:
            del obj.__dict__[self._name]
        except KeyError:
            raise AttributeError(self._name) from None
        generation[0] += 1


def watches(cls: type, name: str) -> bool:
    """True when ``cls.name`` is a :class:`Watched` attribute (a subclass may replace it, e.g. by a property)."""
    for klass in cls.__mro__:
        if name in klass.__dict__:
            return isinstance(klass.__dict__[name], Watched)
    return False
