"""Checked public calls, and the trusted path of a solve.

A class deriving :class:`Guarded` names in ``_guards`` the methods a user may call with bad
arguments (``calc``, ``calcDiff``, ``diff``, ...), each with a :class:`Guard` that converts and
checks the arguments (:mod:`crocopy.validation`).  Every class of the hierarchy that defines one of
these methods gets it wrapped once, when the class is created (``__init_subclass__``), so models
written later, in crocopy or by a user from Python, are checked as well.  Nothing changes the classes
after that.

Whether a call is checked depends only on the thread that makes it.  Each thread has its own trust
depth (a :class:`threading.local`).  At depth 0 a wrapper converts and checks its arguments, then runs
the method with the depth raised, so that the guarded methods the method calls skip their checks.  A
solve runs inside :func:`trusted_path`, which raises the depth of its own thread for its duration: its
hot path is unchecked, callbacks included, while a call made meanwhile from another thread is converted
and checked exactly as it would be alone.  (A context variable is cheaper to read, but a context copied
into another thread, by ``asyncio.to_thread`` or Python 3.14's ``thread_inherit_context``, would carry
a solve's trust with it.)

The hot path stays cheap in two ways.  A wrapper has its method's own signature (its source is
compiled once per signature), so its unchecked branch is one test of the depth and one plain call,
without packing the arguments: in a micro-benchmark (valgrind, Python 3.11), about 1,100 instructions per
call above the unwrapped call, against 2,400 for an ``(*args, **kwargs)`` wrapper.  And the composite
models of crocopy (integrators, cost sums and their stacks, residual costs, the shooting problem) call
their parts through ``_raw_<name>`` (the function without its wrapper, see :class:`Guarded`), which
costs nothing.
"""

from __future__ import annotations

import functools
import inspect
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from types import CodeType
from typing import Any, ClassVar

Converter = Callable[[Any, Any, str], Any]
"""``convert(owner, value, name) -> value``: the checked, converted argument, or a raised error."""


class _Trust(threading.local):
    """Per-thread trust depth: greater than 0 inside a checked call or a solve of this thread."""

    def __init__(self) -> None:
        self.depth = 0


_trust = _Trust()


class Guard:
    """Checks of one method's arguments.

    Parameters
    ----------
    params : tuple of (str, converter)
        The method's parameters after ``self``, in order, with the converter of each (``None``: not
        checked).  Positional and keyword arguments are both converted (defaults included: the wrapper
        has the method's signature); missing ones raise Python's own ``TypeError``.
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


def _checked_call(raw: Callable, guard: Guard) -> Callable:
    """``call(self, *args, **kwargs)``: the checked call of ``raw`` (the wrapper's branch at depth 0)."""
    def call(self, *args, **kwargs):
        args, kwargs = guard.convert(self, args, kwargs)
        _trust.depth += 1
        try:
            out = raw(self, *args, **kwargs)
        finally:
            _trust.depth -= 1
        if guard.after is not None:
            guard.after(self, args, kwargs)
        if guard.returns is not None:
            guard.returns(self, raw.__name__, out)
        return out

    return call


def _forwarding(signature: inspect.Signature) -> tuple[str, str, dict]:
    """``(parameters, arguments, defaults)``: the source of a parameter list with ``signature``'s names, kinds and
    defaults (named ``_crocopy_default_<name>`` in ``defaults``), and of the call forwarding them all."""
    params, args, defaults = [], [], {}
    P = inspect.Parameter
    kinds = [p.kind for p in signature.parameters.values()]
    for i, p in enumerate(signature.parameters.values()):
        if p.kind is P.KEYWORD_ONLY and P.VAR_POSITIONAL not in kinds and P.KEYWORD_ONLY not in kinds[:i]:
            params.append("*")
        text = {P.VAR_POSITIONAL: "*", P.VAR_KEYWORD: "**"}.get(p.kind, "") + p.name
        if p.default is not P.empty:
            defaults[f"_crocopy_default_{p.name}"] = p.default
            text += f"=_crocopy_default_{p.name}"
        params.append(text)
        if p.kind is P.POSITIONAL_ONLY and (i + 1 == len(kinds) or kinds[i + 1] is not P.POSITIONAL_ONLY):
            params.append("/")
        args.append(f"{p.name}={p.name}" if p.kind is P.KEYWORD_ONLY else text.split("=")[0])
    return ", ".join(params), ", ".join(args), defaults


@functools.cache
def _wrapper_code(params: str, args: str) -> CodeType:
    """The compiled definition of a wrapper with parameters ``params`` forwarding ``args`` (one per signature:
    methods that share a signature share it)."""
    return compile(
        f"def guarded({params}):\n"
        f"    if _crocopy_trust.depth:\n"
        f"        return _crocopy_raw({args})\n"
        f"    return _crocopy_checked({args})\n",
        "<crocopy guard>", "exec",
    )


def _wrap(raw: Callable, guard: Guard) -> Callable:
    """``raw`` with ``guard``'s checks at trust depth 0, as a function of ``raw``'s own signature."""
    params, args, namespace = _forwarding(inspect.signature(raw))
    namespace.update(_crocopy_trust=_trust, _crocopy_raw=raw, _crocopy_checked=_checked_call(raw, guard))
    exec(_wrapper_code(params, args), namespace)  # the source holds names only; the values are in the namespace
    guarded = namespace["guarded"]
    names = {"co_name": raw.__name__, "co_filename": f"<crocopy guard of {raw.__qualname__}>"}
    if hasattr(guarded.__code__, "co_qualname"):  # Python >= 3.11: argument errors name Class.method
        names["co_qualname"] = raw.__qualname__
    guarded.__code__ = guarded.__code__.replace(**names)
    functools.update_wrapper(guarded, raw)
    guarded._crocopy_raw = raw
    return guarded


class Guarded:
    """Mixin: the methods named in ``_guards`` check their arguments when a user calls them.

    Every class also gets, for each such method ``name`` it has, ``_raw_<name>``: the function its instances
    call without the wrapper (the definition found first in the method resolution order, unwrapped; a
    definition that is not a plain function, or one from a mixin that is not guarded, as it is).  A
    composite model calls its parts through these names, so that guarded methods calling each other
    inside a solve cost no wrapper.  Methods are wrapped when the class is created; a method assigned to
    the class later is neither wrapped nor seen by ``_raw_<name>``.
    """

    _guards: ClassVar[dict[str, Guard]] = {}

    def __init_subclass__(cls, **kwargs: object) -> None:
        super().__init_subclass__(**kwargs)
        for name, guard in cls._guards.items():
            f = next((k.__dict__[name] for k in cls.__mro__ if name in k.__dict__), None)
            if f is None:
                continue
            if name in cls.__dict__ and inspect.isfunction(f) and not hasattr(f, "_crocopy_raw"):
                setattr(cls, name, _wrap(f, guard))
            setattr(cls, f"_raw_{name}", getattr(f, "_crocopy_raw", f))


@contextmanager
def trusted_path() -> Iterator[None]:
    """Run the body with the checks of guarded methods skipped in this thread (a solve's hot path);
    calls from other threads are checked as usual."""
    _trust.depth += 1
    try:
        yield
    finally:
        _trust.depth -= 1


unchecked = trusted_path
"""The same context manager, under the name the checks themselves use (a check that calls a model)."""


def checking() -> bool:
    """True when a call made now from this thread would be checked (outside any checked call or solve)."""
    return not _trust.depth


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
