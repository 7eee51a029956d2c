"""One cache-invalidation scheme for model parameters.

Some data cache what they derive from model parameters: a cost sum's stack holds the weights,
activity and activation bounds of its items (:mod:`crocopy.costs.stack`), a contact set holds the
Pinocchio constraint models built from its contacts' references and gains
(``crocopy.models.ContactModelMultiple``).  Every such parameter changes through a setter that calls
:func:`touch` on the object it belongs to: one global clock, ``ParametersVersion.value``, moves on
by one, and the object is stamped with the new value (``_stamp``; 0 for an object never touched).
Registries of named items (:mod:`crocopy.named_items`) touch themselves when an item is added,
removed, activated or deactivated.

A cache keeps a :class:`ParametersSeen`: the clock value it was filled at.  It is up to date when
the clock has not moved (one comparison), or when none of the objects it was filled from carries a
newer stamp.  Parameter arrays are read-only (:func:`frozen_copy`): an in-place write would bypass
the setters, so it raises instead.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

import numpy as np


class ParametersVersion:
    """The clock: moves on at every parameter change anywhere (see :func:`touch`)."""

    value = 0


def touch(owner: object) -> None:
    """Record that a parameter of ``owner`` changed: advance the clock and stamp ``owner`` with it."""
    ParametersVersion.value += 1
    object.__setattr__(owner, "_stamp", ParametersVersion.value)


def frozen_copy(values: np.ndarray) -> np.ndarray:
    """A read-only float copy of ``values`` (parameters change through setters only)."""
    out = np.array(values, dtype=float)
    out.setflags(write=False)
    return out


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
