"""Argument checks that raise a clear error naming the argument, the expected shape and what was given.

Vectors are accepted as 1-D arrays, ``(n, 1)``/``(1, n)`` columns or rows, and plain sequences of
numbers (converted to ``float64``); strings, booleans, complex numbers and ``None`` are refused with
an :class:`ArgumentTypeError`, wrong shapes and NaN/inf with a ``ValueError``.  The ``*_arg``
converters have the signature ``convert(owner, value, name)`` of :class:`crocopy.guards.Guard`.
"""

from __future__ import annotations

import math
import numbers
import warnings
from typing import Any

import numpy as np


class ArgumentTypeError(TypeError, ValueError):
    """An argument of the wrong type: a ``TypeError``, and a ``ValueError`` as crocopy raised before."""


class NonFiniteWarning(RuntimeWarning):
    """A direct ``calc``/``calcDiff`` call on finite inputs produced NaN or inf (e.g. overflow)."""


def _as_float_array(value: Any, name: str, expected: str) -> np.ndarray:
    if value is None or isinstance(value, (str, bytes, dict, set)):
        raise ArgumentTypeError(f"{name} must be {expected}, got {type(value).__name__} {value!r:.40}")
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be {expected}, got {type(value).__name__} ({exc})") from exc
    if arr.dtype.kind not in "fiu":
        raise ArgumentTypeError(f"{name} must be {expected} of real numbers, got dtype {arr.dtype}")
    return arr.astype(float, copy=False)


def as_vector(value: Any, size: int | None, name: str, allow_nonfinite: bool = False) -> np.ndarray:
    """Return ``value`` as a float vector of length ``size`` or raise.

    Parameters
    ----------
    value : array_like
        Input to check: shape ``(size,)``, ``(size, 1)`` or ``(1, size)``, or a sequence of numbers.
    size : int or None
        Expected length (``None``: any length, e.g. weights that set a model's dimension).
    name : str
        Argument name used in the error message.
    allow_nonfinite : bool
        Accept inf entries (used for bounds, where inf means "unbounded"); NaN is always refused.

    Raises
    ------
    ArgumentTypeError
        ``None``, strings, booleans, complex or object entries.
    ValueError
        Another shape, or NaN (inf too unless ``allow_nonfinite``).
    """
    if type(value) is np.ndarray and value.dtype == np.float64 and value.shape == (size,):
        total = value.sum()
        if total == total and (allow_nonfinite or abs(total) != np.inf):
            return value
        arr = value
    else:
        arr = _as_float_array(value, name, f"a vector of shape ({'n' if size is None else size},)")
        if arr.ndim == 2 and 1 in arr.shape:
            arr = arr.reshape(-1)
        if arr.ndim != 1 or (size is not None and arr.shape != (size,)):
            raise ValueError(f"{name} has shape {arr.shape}, expected ({'n' if size is None else size},)")
    bad = np.isnan(arr) if allow_nonfinite else ~np.isfinite(arr)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        what = "NaN" if allow_nonfinite else "NaN or inf"
        raise ValueError(f"{name} contains {what} ({name}[{i}] = {arr[i]})")
    return arr


_FLOAT64 = np.dtype(np.float64)


def plain_vectors(values: Any, shapes: list[tuple[int]]) -> bool:
    """Whether ``values`` are ``len(shapes)`` float64 arrays of exactly these shapes (what :func:`as_vector` returns
    unchanged when they are finite, :func:`finite_stack`)."""
    return len(values) == len(shapes) and all(
        type(v) is np.ndarray and v.dtype is _FLOAT64 and v.shape == s for v, s in zip(values, shapes))


def finite_stack(values: list[np.ndarray]) -> np.ndarray | None:
    """The 1-D float64 arrays ``values`` stacked (a new array), or None if an entry is NaN or inf: one sum, then an
    entry-by-entry check only where the sum is not finite (a NaN/inf entry, or finite entries that overflow)."""
    if not values:
        return np.zeros(0)
    stacked = np.concatenate(values)
    with np.errstate(over="ignore", invalid="ignore"):
        total = stacked.sum()
    return stacked if math.isfinite(total) or np.isfinite(stacked).all() else None


def as_matrix(value: Any, shape: tuple[int, int], name: str) -> np.ndarray:
    """Return ``value`` as a finite float matrix of ``shape`` or raise (``ValueError``/:class:`ArgumentTypeError`)."""
    arr = _as_float_array(value, name, f"a matrix of shape {tuple(shape)}")
    if arr.shape != tuple(shape):
        raise ValueError(f"{name} has shape {arr.shape}, expected {tuple(shape)}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} contains NaN or inf")
    return arr


def as_bound(value: Any, size: int | None, name: str, upper: bool) -> np.ndarray:
    """:func:`as_vector` of a lower (``upper`` False) or upper bound: ±inf allowed (unbounded), but not a
    lower bound of ``+inf`` nor an upper bound of ``-inf``, which no value satisfies (``ValueError``)."""
    arr = as_vector(value, size, name, allow_nonfinite=True)
    impossible = -np.inf if upper else np.inf
    bad = np.flatnonzero(arr == impossible)
    if bad.size:
        i = int(bad[0])
        kind, none = ("an upper", "inf") if upper else ("a lower", "-inf")
        raise ValueError(f"{name}[{i}] = {arr[i]}: {kind} bound of {impossible} admits no value"
                         f" (a finite bound, or {none} for none)")
    return arr


def check_bounds(lb: np.ndarray, ub: np.ndarray, lb_name: str, ub_name: str) -> None:
    """Raise ``ValueError`` if a lower bound is above its upper bound."""
    bad = np.nonzero(lb > ub)[0]
    if bad.size:
        i = int(bad[0])
        raise ValueError(
            f"{lb_name}[{i}] = {lb[i]} is above {ub_name}[{i}] = {ub[i]}: lower bound above upper bound"
        )


ROTATION_TOLERANCE = 1e-6
"""How far ``RᵀR`` may be from the identity (largest entry) for ``R`` to count as a rotation."""


def as_rotation(value: Any, name: str) -> np.ndarray:
    """Return ``value`` as a rotation matrix ``(3, 3)``: finite, orthonormal within
    :data:`ROTATION_TOLERANCE` and of determinant ``+1`` (a reflection is refused); else raise
    ``ValueError``/:class:`ArgumentTypeError` naming ``name``."""
    R = as_matrix(value, (3, 3), name)
    error = float(np.abs(R.T @ R - np.eye(3)).max())
    det = float(np.linalg.det(R))
    if error > ROTATION_TOLERANCE or det <= 0.0:
        what = "a reflection" if error <= ROTATION_TOLERANCE else f"a matrix with |RᵀR - I| = {error:.2g}"
        raise ValueError(f"{name} must be a rotation matrix (orthonormal, determinant +1), got {what}"
                         f" of determinant {det:.6g}")
    return R


def as_name(value: Any, name: str) -> str:
    """Return ``value`` if it is a ``str`` (the name of a cost, contact, frame...), else raise
    :class:`ArgumentTypeError`."""
    if not isinstance(value, str):
        raise ArgumentTypeError(f"{name} must be a str, got {type(value).__name__} {value!r:.40}")
    return value


def as_index(value: Any, name: str, size: int | None, what: str = "an int index") -> int:
    """Return ``value`` as an index in ``[0, size)``: an ``int`` or NumPy integer, not a bool or a float
    (:class:`ArgumentTypeError`, saying ``name`` must be ``what``); out of range: ``ValueError``.  With
    ``size`` None only the type is checked (the caller checks the range)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise ArgumentTypeError(f"{name} must be {what}, got {type(value).__name__} {value!r:.40}")
    if size is not None and not 0 <= value < size:
        raise ValueError(f"{name} = {value} is out of range (0 <= {name} < {size})")
    return int(value)


def check_finite(values: Any, name: str) -> None:
    """Raise ``ValueError`` if the array ``values`` (e.g. a Pinocchio SE3's ``homogeneous``) holds NaN or inf."""
    if not np.all(np.isfinite(values)):
        raise ValueError(f"{name} contains NaN or inf")


def as_number(value: Any, name: str, minimum: float | None = None, strict: bool = False,
              allow_inf: bool = False) -> float:
    """Return ``value`` as a float, refusing non-numbers, NaN, inf (unless ``allow_inf``) and values
    below ``minimum`` (or equal to it when ``strict``).

    Raises
    ------
    ArgumentTypeError
        ``value`` is not a real number (booleans and strings included).
    ValueError
        NaN, inf, or out of range.
    """
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        if not (isinstance(value, np.ndarray) and value.shape in ((), (1,)) and value.dtype.kind in "fiu"):
            raise ArgumentTypeError(f"{name} must be a real number, got {type(value).__name__}")
    out = float(np.asarray(value).reshape(()))
    if out != out or (not allow_inf and abs(out) == np.inf):
        raise ValueError(f"{name} must be a finite number, got {out}")
    if minimum is not None and (out < minimum or (strict and out == minimum)):
        relation = ">" if strict else ">="
        raise ValueError(f"{name} must be {relation} {minimum}, got {out}")
    return out


def as_count(value: Any, name: str, minimum: int = 0) -> int:
    """Return ``value`` as an int ``>= minimum`` (booleans and floats refused)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise ArgumentTypeError(f"{name} must be an integer, got {type(value).__name__}")
    if value < minimum:
        bound = "non-negative" if minimum == 0 else f">= {minimum}"
        raise ValueError(f"{name} must be {bound}, got {value}")
    return int(value)


def as_optional_count(value: Any, name: str) -> int | None:
    """``None``, or :func:`as_count` of ``value`` (e.g. a model's ``nu``, ``None`` for its default)."""
    return None if value is None else as_count(value, name)


def as_bool(value: Any, name: str) -> bool:
    """Return ``value`` as a bool; only ``bool``, ``numpy.bool_`` and the integers 0 and 1 are accepted."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)) and value in (0, 1):
        return bool(value)
    raise ArgumentTypeError(f"{name} must be a bool, got {type(value).__name__} {value!r}")


# ---------------------------------------------------------------- converters of guarded methods
def state_arg(owner: Any, value: Any, name: str) -> np.ndarray:
    """A point ``(nx,)`` of ``owner.state`` (a model's state)."""
    return as_vector(value, owner.state.nx, name)


def control_arg(owner: Any, value: Any, name: str) -> np.ndarray | None:
    """A control ``(nu,)`` of ``owner``, or ``None`` (terminal node)."""
    return None if value is None else as_vector(value, owner.nu, name)


def point_arg(owner: Any, value: Any, name: str) -> np.ndarray:
    """A point ``(nx,)`` of the state ``owner`` itself."""
    return as_vector(value, owner.nx, name)


def tangent_arg(owner: Any, value: Any, name: str) -> np.ndarray:
    """A tangent vector ``(ndx,)`` of the state ``owner`` itself."""
    return as_vector(value, owner.ndx, name)


def residual_arg(owner: Any, value: Any, name: str) -> np.ndarray:
    """A residual ``(nr,)`` of an activation ``owner``."""
    return as_vector(value, owner.nr, name)


def data_arg(expected: dict[str, tuple]) -> Any:
    """Converter of a ``data`` argument: its arrays named in ``expected`` must have the shapes
    ``expected[attr](owner)`` gives (an entry ``None`` is not checked); a data of another model is refused.
    """
    def convert(owner: Any, data: Any, name: str) -> Any:
        if data is None:
            raise ArgumentTypeError(f"{name} must be the data of {type(owner).__name__} (createData()), got None")
        for attr, shape_of in expected.items():
            arr = getattr(data, attr, None)
            shape = shape_of(owner)
            if isinstance(arr, np.ndarray) and shape is not None and arr.shape != shape:
                raise ValueError(
                    f"{name} was not created by this {type(owner).__name__}: {name}.{attr} has shape {arr.shape},"
                    f" expected {shape}; use the data returned by this model's createData()"
                )
        return data
    return convert


def warn_nonfinite_result(owner: Any, method: str, out: Any) -> None:
    """Warn (:class:`NonFiniteWarning`) if the array, or one of the arrays, ``out`` that ``owner.method``
    returned holds NaN or inf."""
    for value in out if isinstance(out, (tuple, list)) else (out,):
        if isinstance(value, np.ndarray) and not np.all(np.isfinite(value)):
            warnings.warn(f"{type(owner).__name__}.{method}: the result is not finite after a call on finite inputs"
                          " (overflow?)", NonFiniteWarning, stacklevel=4)
            return


def warn_after(*calc: str, diff: tuple[str, ...] = ()) -> dict[str, Any]:
    """``after`` hooks of :class:`crocopy.guards.Guard` for ``calc`` and ``calcDiff``: :func:`warn_nonfinite`
    on the data's quantities ``calc`` and ``diff``."""
    def make(names: tuple[str, ...]) -> Any:
        def after(owner: Any, args: list, kwargs: dict) -> None:
            warn_nonfinite(owner, args[0] if args else kwargs.get("data"), names)
        return after
    return {"calc": make(calc), "calcDiff": make(diff)}


def warn_nonfinite(owner: Any, data: Any, names: tuple[str, ...]) -> None:
    """Warn (:class:`NonFiniteWarning`) if one of ``data``'s quantities ``names`` holds NaN or inf."""
    for attr in names:
        value = getattr(data, attr, None)
        if value is None:
            continue
        try:
            finite = bool(np.all(np.isfinite(value)))
        except TypeError:
            continue
        if not finite:
            warnings.warn(
                f"{type(owner).__name__}: data.{attr} is not finite after a call on finite inputs"
                " (overflow or a singular model?)",
                NonFiniteWarning, stacklevel=4,
            )
            return
