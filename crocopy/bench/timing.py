"""Timing helpers shared by the benchmarks: one BLAS thread, and samples of a call's duration.

Samples run on crocopy's trusted path (:func:`crocopy.guards.trusted_path`): a phase such as
``problem.calc`` is timed as a solve runs it, without the argument checks of a user's direct call
(calls into Crocoddyl are unaffected)."""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable

from ..guards import trusted_path

MIN_SAMPLE_S = 2e-2
"""A call faster than this (seconds) is looped within one sample: timer resolution, call overhead, and on a
loaded machine a sample spanning several scheduler slices sees the average CPU share, not one slice."""


def limit_threads() -> None:
    """One thread for BLAS/OpenMP (environment defaults and threadpoolctl): small matrices run faster."""
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")
    try:
        from threadpoolctl import threadpool_limits

        threadpool_limits(1)
    except ImportError:
        pass


def loops_for(fn: Callable[[], object]) -> int:
    """Calls per sample so that one sample lasts at least :data:`MIN_SAMPLE_S` (``fn`` runs once here)."""
    with trusted_path():
        t0 = time.perf_counter()
        fn()
        elapsed = time.perf_counter() - t0
    return max(1, math.ceil(MIN_SAMPLE_S / max(elapsed, 1e-9)))


def sample_ms(fn: Callable[[], object], loops: int, clock: Callable[[], float] = time.perf_counter) -> float:
    """Milliseconds per call of ``fn`` over ``loops`` calls, by ``clock`` (wall clock unless told)."""
    with trusted_path():
        t0 = clock()
        for _ in range(loops):
            fn()
        elapsed = clock() - t0
    return 1e3 * elapsed / loops
