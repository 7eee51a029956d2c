"""Checked public calls and the trusted path of a solve.

A class deriving :class:`Guarded` names in ``_guards`` the methods a user may call with bad
arguments (``calc``, ``calcDiff``, ``diff``, ...), each with a :class:`Guard` that converts and
checks the arguments (:mod:`crocopy.validation`).  Every class of the hierarchy that defines one of
these methods gets it wrapped once, when the class is created (``__init_subclass__``), so models
written later, in crocopy or by a user from Python, are checked as well.

The wrapper checks only the outermost call: while a checked call runs, the calls it makes to other
guarded methods (an integrator calling its differential model, a cost sum its costs) go straight to
the raw functions behind a one-flag test.  A solve goes further: inside :func:`trusted_path` the
first call of a guarded method installs the raw functions on its class ("hot" classes) for the rest
of the solve, and later solves install them on every hot class on entry; the hot path then runs
exactly the code it ran before the checks existed, and a user's override of ``calc`` is still the
one called.  The checked wrappers are back on exit.

From Python 3.13 a class whose attributes were assigned 1000 times loses its attribute cache for
good (CPython's ``MAX_VERSIONS_PER_CLASS``), which two assignments per solve would reach in an MPC
loop; there (:data:`INSTALL_RAW` False) a solve keeps the wrappers and skips their checks behind
the flag only, which costs one extra Python call per guarded call.

While a solve runs (in any thread), calls made from its callbacks are not checked either.
"""

from __future__ import annotations

import functools
import sys
import weakref
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any, ClassVar

Converter = Callable[[Any, Any, str], Any]
"""``convert(owner, value, name) -> value``: the checked, converted argument, or a raised error."""


class _Trust:
    depth = 0
    """Greater than 0 inside a checked call or a solve: guarded methods skip their checks."""
    raw = 0
    """Greater than 0 inside a solve: the raw methods are installed on the guarded classes."""


INSTALL_RAW = sys.version_info < (3, 13)
"""Whether a solve installs the raw methods on the classes it calls (see the module docstring)."""

_HOT: weakref.WeakSet = weakref.WeakSet()
"""Guarded classes a solve has called into: their raw methods are installed during every solve."""


class Guard:
    """Checks of one method's arguments.

    Parameters
    ----------
    params : tuple of (str, converter)
        The method's parameters after ``self``, in order, with the converter of each (``None``: not
        checked).  Positional and keyword arguments are both converted; missing ones are left to
        Python's own ``TypeError``.
    check : callable, optional
        ``check(owner, args, kwargs)`` run after the converters, for checks across arguments.
    after : callable, optional
        ``after(owner, args, kwargs)`` run after the method (e.g. a warning on non-finite results).
    returns : callable, optional
        ``returns(owner, name, out)`` run on the value ``out`` the method ``name`` returned.
    """

    def __init__(self, params: tuple[tuple[str, Converter | None], ...] = (), check: Callable | None = None,
                 after: Callable | None = None, returns: Callable | None = None) -> None:
        self.params = params
        self.check = check
        self.after = after
        self.returns = returns

    def convert(self, owner: object, args: tuple, kwargs: dict) -> tuple[list, dict]:
        """The converted ``(args, kwargs)`` of a call on ``owner``."""
        args = list(args)
        for i, (name, conv) in enumerate(self.params):
            if conv is None:
                continue
            if i < len(args):
                args[i] = conv(owner, args[i], name)
            elif name in kwargs:
                kwargs[name] = conv(owner, kwargs[name], name)
        if self.check is not None:
            self.check(owner, args, kwargs)
        return args, kwargs


def _install(cls: type, raw: bool) -> None:
    for name, pair in cls.__dict__["_guard_pairs"].items():
        setattr(cls, name, pair[0] if raw else pair[1])


def _heat(cls: type) -> None:
    """Install ``cls``'s raw methods for the rest of the solve, and on entry of the next ones."""
    _HOT.add(cls)
    _install(cls, raw=True)


def _wrap(raw: Callable, guard: Guard, cls: type) -> Callable:
    @functools.wraps(raw)
    def guarded(self, *args, **kwargs):
        if _Trust.depth:
            if _Trust.raw and INSTALL_RAW and cls not in _HOT:  # (a bound method kept from before stays wrapped)
                _heat(cls)
            return raw(self, *args, **kwargs)
        args, kwargs = guard.convert(self, args, kwargs)
        _Trust.depth += 1
        try:
            out = raw(self, *args, **kwargs)
        finally:
            _Trust.depth -= 1
        if guard.after is not None:
            guard.after(self, args, kwargs)
        if guard.returns is not None:
            guard.returns(self, raw.__name__, out)
        return out

    guarded._crocopy_raw = raw
    return guarded


class Guarded:
    """Mixin: the methods named in ``_guards`` check their arguments when a user calls them."""

    _guards: ClassVar[dict[str, Guard]] = {}

    def __init_subclass__(cls, **kwargs: object) -> None:
        super().__init_subclass__(**kwargs)
        pairs = {}
        for name, guard in cls._guards.items():
            f = cls.__dict__.get(name)
            if callable(f) and not hasattr(f, "_crocopy_raw"):
                pairs[name] = (f, _wrap(f, guard, cls))
        if pairs:
            cls._guard_pairs = pairs
            _install(cls, raw=False)


@contextmanager
def trusted_path() -> Iterator[None]:
    """Run the body with every guarded method unchecked and unwrapped (a solve's hot path)."""
    install = INSTALL_RAW and not _Trust.raw
    if install:
        for cls in list(_HOT):
            _install(cls, raw=True)
    _Trust.raw += 1
    _Trust.depth += 1
    try:
        yield
    finally:
        _Trust.depth -= 1
        _Trust.raw -= 1
        if install:
            for cls in list(_HOT):
                _install(cls, raw=False)


@contextmanager
def unchecked() -> Iterator[None]:
    """Run the body with the checks of guarded methods skipped (they stay wrapped)."""
    _Trust.depth += 1
    try:
        yield
    finally:
        _Trust.depth -= 1


def checking() -> bool:
    """True when a call made now would be checked (outside any checked call or solve)."""
    return not _Trust.depth


def point_guards(**extra: Guard) -> dict[str, Guard]:
    """``calc(data, x)``/``calcDiff(data, x)`` of a model on ``owner.state`` (plus ``extra``)."""
    from .validation import state_arg

    params = (("data", None), ("x", state_arg))
    return {"calc": Guard(params), "calcDiff": Guard(params), **extra}


def point_control_guards(after: dict[str, Callable] | None = None, **extra: Guard) -> dict[str, Guard]:
    """``calc(data, x, u=None)``/``calcDiff(data, x, u=None)`` of a model with ``state`` and ``nu`` (with the
    ``after`` hooks of ``calc``/``calcDiff`` in ``after``, e.g. :func:`crocopy.validation.warn_after`)."""
    from .validation import control_arg, state_arg

    params = (("data", None), ("x", state_arg), ("u", control_arg))
    after = after or {}
    return {"calc": Guard(params, after=after.get("calc")), "calcDiff": Guard(params, after=after.get("calcDiff")),
            **extra}
