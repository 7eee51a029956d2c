"""Process-wide switches of Crocoddyl's Python module: the random seed and the memory sharing.

- ``seed(seed_value)``: seeds the generator behind ``state.rand()`` and the other random draws of
  crocopy (NumPy's global generator, ``numpy.random.seed``).
- ``sharedMemory()``: Crocoddyl's switch between sharing an Eigen matrix with NumPy or copying it.
  crocopy's data hold NumPy arrays, so the memory is always shared: ``sharedMemory()`` is True,
  ``sharedMemory(True)`` keeps it so and ``sharedMemory(False)`` raises ``ValueError``.
"""

from __future__ import annotations

import numpy as np


def seed(seed_value: int) -> None:
    """Seed NumPy's global generator (used by ``state.rand()``) with ``seed_value``.

    Raises
    ------
    ValueError
        If ``seed_value`` is not a non-negative integer.
    """
    if isinstance(seed_value, bool) or not isinstance(seed_value, (int, np.integer)) or seed_value < 0:
        raise ValueError(f"seed_value must be a non-negative integer, got {seed_value!r}")
    np.random.seed(int(seed_value) % 2**32)


def sharedMemory(value: bool | None = None) -> bool | None:
    """``sharedMemory()``: True (crocopy's data are NumPy arrays, shared); ``sharedMemory(True)``: nothing
    to do; ``sharedMemory(False)``: ``ValueError`` (crocopy cannot hand out copies instead)."""
    if value is None:
        return True
    if not value:
        raise ValueError("sharedMemory(False): crocopy's data are NumPy arrays and always share their memory")
    return None
