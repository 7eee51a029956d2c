"""Rotation helpers of Crocoddyl's Python package.

``rotationMatrixFromTwoVectors(a, b)`` is the rotation of smallest angle that turns the direction
``u = a/|a|`` into ``w = b/|b|``: the turn by ``θ = atan2(|u × w|, u·w)`` about the unit axis ``n``
along ``u × w``, by Rodrigues' formula ``R = I + sin θ [n]× + (1 - cos θ) [n]×²``.  It is right for
every pair of non-zero vectors, whatever their scale (tiny, huge or subnormal components):

* the directions are taken after scaling each vector by its largest entry, so no norm under- or
  overflows;
* the axis is made exactly perpendicular to ``u`` (near opposite directions ``u × w`` is the
  difference of nearly equal products and its direction is lost; any axis perpendicular to ``u``
  then turns ``u`` into ``w`` to round-off);
* for exactly opposite directions (``u × w = 0``, ``u·w < 0``) it is the half-turn about an axis
  perpendicular to ``u`` (Crocoddyl returns the identity there, which does not turn ``a`` into ``b``).

Parallel directions, or a zero vector, give the identity.
"""

from __future__ import annotations

import math

import numpy as np

from .validation import as_vector


def _skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def _direction(v: np.ndarray) -> np.ndarray:
    """``v / |v|`` for a non-zero ``v (3,)``, scaled first by its largest entry (no under- or overflow)."""
    v = v / np.abs(v).max()
    return v / math.sqrt(float(v @ v))


def _perpendicular(u: np.ndarray) -> np.ndarray:
    """A unit vector perpendicular to the unit vector ``u``: ``u ×`` the basis vector least aligned with it."""
    return _direction(np.cross(u, np.eye(3)[np.argmin(np.abs(u))]))


def rotationMatrixFromTwoVectors(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rotation matrix ``(3, 3)`` of smallest angle turning the direction of ``a (3,)`` into that of ``b (3,)``.

    Raises
    ------
    ValueError
        If ``a`` or ``b`` is not a finite vector of shape ``(3,)``.
    """
    a, b = as_vector(a, 3, "a"), as_vector(b, 3, "b")
    if not a.any() or not b.any():
        return np.eye(3)
    u, w = _direction(a), _direction(b)
    k = np.cross(u, w)
    c = float(u @ w)
    if not k.any():
        if c > 0.0:
            return np.eye(3)
        n, s = _perpendicular(u), 0.0
    else:
        n, s = _direction(k), math.hypot(*k)
        n = n - (n @ u) * u  # exactly perpendicular to u (near opposite directions u × w lost its direction)
        n = _direction(n) if np.abs(n).max() > 0.5 else _perpendicular(u)
    r = math.hypot(s, c)
    sin, cos = s / r, c / r
    one_minus_cos = sin * sin / (1.0 + cos) if cos > 0.0 else 1.0 - cos
    N = _skew(n)
    return np.eye(3) + sin * N + one_minus_cos * (N @ N)
