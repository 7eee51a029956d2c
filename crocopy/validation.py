"""Argument checks that raise a clear ``ValueError`` naming the argument and expected shape."""

from __future__ import annotations

from typing import Any

import numpy as np


def as_vector(value: Any, size: int, name: str, allow_nonfinite: bool = False) -> np.ndarray:
    """Return ``value`` as a float vector of length ``size`` or raise ``ValueError``.

    Parameters
    ----------
    value : array_like
        Input to check.
    size : int
        Expected length.
    name : str
        Argument name used in the error message.
    allow_nonfinite : bool
        Accept NaN/inf entries (used for bounds, where inf means "unbounded").
    """
    if type(value) is np.ndarray and value.dtype == np.float64 and value.shape == (size,):
        total = value.sum()
        if total == total and (allow_nonfinite or abs(total) != np.inf):
            return value
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a numeric vector of shape ({size},)") from exc
    if arr.ndim == 2 and 1 in arr.shape:
        arr = arr.reshape(-1)
    if arr.shape != (size,):
        raise ValueError(f"{name} has shape {arr.shape}, expected ({size},)")
    if not allow_nonfinite and not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} contains NaN or inf")
    if allow_nonfinite and np.any(np.isnan(arr)):
        raise ValueError(f"{name} contains NaN")
    return arr


def as_matrix(value: Any, shape: tuple[int, int], name: str) -> np.ndarray:
    """Return ``value`` as a finite float matrix of ``shape`` or raise ``ValueError``."""
    arr = np.asarray(value, dtype=float)
    if arr.shape != tuple(shape):
        raise ValueError(f"{name} has shape {arr.shape}, expected {tuple(shape)}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} contains NaN or inf")
    return arr


def check_bounds(lb: np.ndarray, ub: np.ndarray, lb_name: str, ub_name: str) -> None:
    """Raise ``ValueError`` if a lower bound is above its upper bound."""
    bad = np.nonzero(lb > ub)[0]
    if bad.size:
        i = int(bad[0])
        raise ValueError(
            f"{lb_name}[{i}] = {lb[i]} is above {ub_name}[{i}] = {ub[i]}: lower bound above upper bound"
        )
