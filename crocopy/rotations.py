"""Rotation helpers of Crocoddyl's Python package.

``rotationMatrixFromTwoVectors(a, b)`` is the rotation of smallest angle that turns the direction
of ``a`` into that of ``b``: with ``u = a/|a|``, ``w = b/|b|``, ``k = u × w`` (``s = |k|``) and
``c = u·w``, Rodrigues' formula ``R = I + [k]× + [k]×² (1 - c)/s²``.  When ``k = 0`` (parallel or
opposite directions, or a zero vector) it is the identity, as Crocoddyl's (measured: for
opposite vectors too, although the identity then does not turn ``a`` into ``b``).
"""

from __future__ import annotations

import numpy as np

from .validation import as_vector


def _skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def rotationMatrixFromTwoVectors(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rotation matrix ``(3, 3)`` turning the direction of ``a (3,)`` into that of ``b (3,)``.

    Raises
    ------
    ValueError
        If ``a`` or ``b`` is not a finite vector of shape ``(3,)``.
    """
    a, b = as_vector(a, 3, "a"), as_vector(b, 3, "b")
    ma, mb = np.abs(a).max(), np.abs(b).max()
    if ma == 0.0 or mb == 0.0:
        return np.eye(3)
    a, b = a / ma, b / mb  # largest entry 1: the norms below neither underflow nor overflow
    u, w = a / np.linalg.norm(a), b / np.linalg.norm(b)
    k = np.cross(u, w)
    s2 = float(k @ k)
    if s2 == 0.0:
        return np.eye(3)
    K = _skew(k)
    return np.eye(3) + K + (K @ K) * ((1.0 - float(u @ w)) / s2)
