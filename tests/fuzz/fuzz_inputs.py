"""Hypothesis strategies of good and bad arguments, and the outcome every public call must have.

A drawn argument is an :class:`Arg`: the value handed to crocopy, the array it stands for when it
is valid (``None`` when crocopy must refuse it), and the parameter name an error has to quote.
:func:`outcome` runs a call and asserts the contract of issue 14: either a ``ValueError``,
``TypeError`` or ``KeyError`` whose message names one of the bad arguments, or (all arguments
valid) a finite, shape-correct result.

Examples per property: the ``crocopy-fuzz`` Hypothesis profile (25, the default run), or
``crocopy-fuzz-slow`` (500) with ``CROCOPY_FUZZ_PROFILE=slow``.
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from hypothesis import HealthCheck, settings
from hypothesis import strategies as st

settings.register_profile(
    "crocopy-fuzz", max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow]
)
settings.register_profile(
    "crocopy-fuzz-slow", max_examples=500, deadline=None, suppress_health_check=[HealthCheck.too_slow]
)
FUZZ = settings.get_profile("crocopy-fuzz-slow" if os.environ.get("CROCOPY_FUZZ_PROFILE") == "slow" else "crocopy-fuzz")
"""Settings of every fuzz property (select the slow profile with ``CROCOPY_FUZZ_PROFILE=slow``)."""

VALID_KINDS = ("ok", "list", "column", "row", "int")
BAD_KINDS = ("short", "long", "matrix", "nan", "inf", "string", "complex", "bool", "none", "scalar")
CONTROL_KINDS = tuple(k for k in VALID_KINDS + BAD_KINDS if k != "none")
"""Forms of a control ``u``: ``None`` is not bad there, it asks for the terminal evaluation."""


@dataclass
class Arg:
    """A drawn argument: ``value`` is passed, ``array`` is its float meaning (``None``: must be refused)."""

    name: str
    kind: str
    value: Any
    array: np.ndarray | None

    @property
    def valid(self) -> bool:
        return self.array is not None


def finite_values(size: int, bound: float = 2.0) -> st.SearchStrategy[np.ndarray]:
    """Finite float vectors of ``size`` entries in ``[-bound, bound]``."""
    return st.lists(st.floats(-bound, bound, allow_nan=False), min_size=size, max_size=size).map(
        lambda v: np.array(v, dtype=float).reshape(size)
    )


@st.composite
def vector_arg(draw, name: str, size: int, base: np.ndarray | None = None, kinds: tuple | None = None) -> Arg:
    """A vector argument of length ``size``: valid forms (1-D, list, ``(n, 1)``, ``(1, n)``, integers)
    or bad ones (wrong length or rank, NaN, inf, strings, complex, booleans, ``None``, a scalar).
    ``base`` (if given) is the valid point the drawn one is built from."""
    v = draw(finite_values(size)) if base is None else np.asarray(base, dtype=float)
    if kinds is None:
        kinds = VALID_KINDS + BAD_KINDS if size else ("ok", "list", "long", "none")
    kind = draw(st.sampled_from(kinds))
    if kind == "ok":
        return Arg(name, kind, v.copy(), v)
    if kind == "list":
        return Arg(name, kind, v.tolist(), v)
    if kind == "column":
        return Arg(name, kind, v.reshape(size, 1), v)
    if kind == "row":
        return Arg(name, kind, v.reshape(1, size), v)
    if kind == "int":
        w = np.round(v).astype(int)
        return Arg(name, kind, w, w.astype(float))
    bad: dict[str, Callable[[], Any]] = {
        "short": lambda: v[:-1],
        "long": lambda: np.append(v, 0.0),
        "matrix": lambda: np.tile(v, (2, 1)).T,
        "nan": lambda: np.where(np.arange(size) == draw(st.integers(0, size - 1)), np.nan, v),
        "inf": lambda: np.where(np.arange(size) == draw(st.integers(0, size - 1)), -np.inf, v),
        "string": lambda: [str(e) for e in v],
        "complex": lambda: v + 1j,
        "bool": lambda: v > 0,
        "none": lambda: None,
        "scalar": lambda: float(v[0]),
    }
    return Arg(name, kind, bad[kind](), None)


def names_argument(message: str, names: list[str]) -> bool:
    """True if ``message`` quotes one of ``names`` as a word (``x`` in ``"x has shape"``, not in ``"expected"``)."""
    return any(re.search(rf"(?<![A-Za-z_]){re.escape(n)}(?![A-Za-z_])", message) for n in names)


def outcome(call: Callable[[], Any], args: list[Arg], check_result: Callable[[], None]) -> None:
    """Run ``call`` and assert the contract: bad arguments give a clear error naming one of them;
    valid ones give a result that ``check_result`` accepts (finite and shape-correct)."""
    bad = [a.name for a in args if not a.valid]
    if bad:
        try:
            call()
        except (ValueError, TypeError, KeyError) as exc:
            assert names_argument(str(exc), bad), f"error does not name {bad}: {exc!r}"
            return
        raise AssertionError(f"bad argument(s) {[(a.name, a.kind) for a in args if not a.valid]} accepted")
    call()
    check_result()


def assert_finite(obj: Any, shapes: dict[str, tuple]) -> None:
    """Every attribute in ``shapes`` of ``obj`` is finite and has its shape (``()``: a scalar)."""
    for attr, shape in shapes.items():
        value = np.asarray(getattr(obj, attr))
        assert value.shape == shape, f"{attr} has shape {value.shape}, expected {shape}"
        assert np.all(np.isfinite(value)), f"{attr} is not finite: {value}"


def calls_in_drawn_order(data: st.DataObject, model: Any, md: Any, args: list[Arg],
                         shapes_of: Callable[[str], dict]) -> None:
    """``calc``/``calcDiff`` of ``model`` on ``md`` with ``args``, 1 to 3 calls in a drawn order, each
    meeting :func:`outcome` with the shapes ``shapes_of(method)``."""
    values = [a.value for a in args]
    for method in data.draw(st.lists(st.sampled_from(["calc", "calcDiff"]), min_size=1, max_size=3)):
        shapes = shapes_of(method)
        outcome(lambda m=method: getattr(model, m)(md, *values), args, lambda s=shapes: assert_finite(md, s))


def assert_matches_numdiff(model: Any, x: np.ndarray, u: np.ndarray, tol: float) -> None:
    """Cost and ``Fx, Fu, Lx, Lu`` of ``model`` at ``(x, u)`` agree with its numerical differentiation
    (``tol`` relative to the largest entry of each numerical derivative, at least 1)."""
    import crocopy

    differential = isinstance(model, crocopy.DifferentialActionModelAbstract)
    nd = (crocopy.DifferentialActionModelNumDiff if differential else crocopy.ActionModelNumDiff)(model)
    md, ndd = model.createData(), nd.createData()
    for m, d in ((model, md), (nd, ndd)):
        m.calc(d, x, u)
        m.calcDiff(d, x, u)
    assert abs(md.cost - ndd.cost) <= 1e-9 * max(1.0, abs(ndd.cost))
    for f in ("Fx", "Fu", "Lx", "Lu"):
        ref = getattr(ndd, f)
        np.testing.assert_allclose(getattr(md, f), ref, atol=tol * max(1.0, np.abs(ref).max()), err_msg=f)
