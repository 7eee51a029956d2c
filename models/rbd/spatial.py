"""6-vector helpers of the compiled rigid-body kernels: spatial motions and forces as tuples ``[linear; angular]``.

``m × n = [m_ω × n_v + m_v × n_ω; m_ω × n_ω]`` (motion cross product) and ``m ×* f = [m_ω × f_v; m_ω × f_ω + m_v ×
f_v]`` (its dual on forces).  Tuples stay in registers and numba inlines these small functions, where a helper
taking arrays would cost a reference count of every array it receives (see :mod:`.dynamics_kernel`).
"""

from __future__ import annotations

import numpy as np

from crocopy.kernels import uncounted


@uncounted
def get6(A: np.ndarray, i: int) -> tuple:
    """Row ``i`` of an ``(n, 6)`` array as a tuple."""
    return A[i, 0], A[i, 1], A[i, 2], A[i, 3], A[i, 4], A[i, 5]


@uncounted
def set6(A: np.ndarray, i: int, m: tuple) -> None:
    """``A[i] = m``."""
    A[i, 0], A[i, 1], A[i, 2], A[i, 3], A[i, 4], A[i, 5] = m


@uncounted
def plus(m: tuple, n: tuple) -> tuple:
    """``m + n`` of two 6-tuples."""
    return m[0] + n[0], m[1] + n[1], m[2] + n[2], m[3] + n[3], m[4] + n[4], m[5] + n[5]


@uncounted
def minus(m: tuple, n: tuple) -> tuple:
    """``m - n`` of two 6-tuples."""
    return m[0] - n[0], m[1] - n[1], m[2] - n[2], m[3] - n[3], m[4] - n[4], m[5] - n[5]


@uncounted
def times(m: tuple, x: float) -> tuple:
    """``x m`` of a 6-tuple and a scalar."""
    return m[0] * x, m[1] * x, m[2] * x, m[3] * x, m[4] * x, m[5] * x


@uncounted
def unit(c: int) -> tuple:
    """The ``c``-th unit 6-tuple."""
    return (1.0 if c == 0 else 0.0, 1.0 if c == 1 else 0.0, 1.0 if c == 2 else 0.0,
            1.0 if c == 3 else 0.0, 1.0 if c == 4 else 0.0, 1.0 if c == 5 else 0.0)


@uncounted
def dot(m: tuple, n: tuple) -> float:
    """``mᵀ n`` of two 6-tuples."""
    return m[0] * n[0] + m[1] * n[1] + m[2] * n[2] + m[3] * n[3] + m[4] * n[4] + m[5] * n[5]


@uncounted
def mcross(m: tuple, n: tuple) -> tuple:
    """``m × n`` of two motions (6-tuples)."""
    return (
        m[4] * n[2] - m[5] * n[1] + m[1] * n[5] - m[2] * n[4],
        m[5] * n[0] - m[3] * n[2] + m[2] * n[3] - m[0] * n[5],
        m[3] * n[1] - m[4] * n[0] + m[0] * n[4] - m[1] * n[3],
        m[4] * n[5] - m[5] * n[4],
        m[5] * n[3] - m[3] * n[5],
        m[3] * n[4] - m[4] * n[3],
    )


@uncounted
def fcross(m: tuple, f: tuple) -> tuple:
    """``m ×* f`` of a motion and a force (6-tuples)."""
    return (
        m[4] * f[2] - m[5] * f[1],
        m[5] * f[0] - m[3] * f[2],
        m[3] * f[1] - m[4] * f[0],
        m[4] * f[5] - m[5] * f[4] + m[1] * f[2] - m[2] * f[1],
        m[5] * f[3] - m[3] * f[5] + m[2] * f[0] - m[0] * f[2],
        m[3] * f[4] - m[4] * f[3] + m[0] * f[1] - m[1] * f[0],
    )
