"""Getting the compiled kernels ready: the first-run notice, the warm-up call, and ``crocopy compile``.

A kernel (:mod:`crocopy.kernels`) is compiled on its first call with new argument types, unless
numba's on-disk cache holds it; compiling all of them takes about 100 s of CPU time (``time crocopy
compile`` in a fresh cache), loading them from the cache a fraction of a second.  Here:

* :func:`announce_cold_cache` prints :data:`COMPILING_NOTICE` at once when the cache lacks a kernel
  (:func:`crocopy.kernels.cache_is_cold`, which compiles nothing);
* :func:`warm_up_kernels` runs a call (one solver iteration) that loads or compiles the kernels, and
  prints the notice as soon as it compiles (a signature missing from a cache that has an index);
* :func:`compile_kernels` (``crocopy compile``) runs warm-up solves that call every kernel, so that
  later processes only load them.
"""

from __future__ import annotations

import os
import sys
import threading
import time
from collections.abc import Callable, Sequence

from . import kernels

COMPILING_NOTICE = "compiling kernels (first run only) ..."


def compilations(dispatchers: Sequence) -> int:
    """Signatures compiled so far in this process (not loaded from numba's cache) by ``dispatchers``."""
    return sum(sum(d.stats.cache_misses.values()) for d in dispatchers)


def announce_cold_cache() -> bool:
    """Print :data:`COMPILING_NOTICE` on stderr now if numba's cache lacks some kernel (the first solve
    will compile); True if printed."""
    if not kernels.cache_is_cold():
        return False
    print(COMPILING_NOTICE, file=sys.stderr, flush=True)
    return True


def warm_up_kernels(run: Callable[[], object], dispatchers: Sequence | None = None, poll: float = 0.2,
                    announced: bool = False) -> float:
    """Call ``run()`` once, announcing on stderr when it compiles kernels; return the seconds compiling took.

    While ``run`` executes, a thread polls ``dispatchers`` (default :data:`crocopy.kernels.KERNELS`)
    every ``poll`` seconds; as soon as one of them compiles a signature instead of loading it from
    numba's on-disk cache, :data:`COMPILING_NOTICE` is printed (unless ``announced``: the caller
    printed it already).  Returns the wall time of ``run`` when something was compiled, else ``0.0``.
    """
    dispatchers = kernels.KERNELS if dispatchers is None else dispatchers
    before = compilations(dispatchers)
    done = threading.Event()

    def announce() -> None:
        while not done.wait(poll):
            if compilations(dispatchers) > before:
                print(COMPILING_NOTICE, file=sys.stderr, flush=True)
                return

    watcher = threading.Thread(target=announce, daemon=True)
    t0 = time.perf_counter()
    if not announced:
        watcher.start()
    try:
        run()
    finally:
        done.set()
        if not announced:
            watcher.join()
    elapsed = time.perf_counter() - t0
    if compilations(dispatchers) == before:
        return 0.0
    print(f"kernels compiled in {elapsed:.1f} s (cached for the next runs; not counted in the solve time)",
          file=sys.stderr, flush=True)
    return elapsed


def compile_kernels(build: Callable[[Callable], tuple], runs: Sequence[tuple[Callable, Sequence[type]]]) -> int:
    """Compile (or load) every kernel by warm-up solves; print a summary; return an exit status.

    Parameters
    ----------
    build : callable
        ``build(builder) -> (problem, xs, us)`` for each builder of ``runs``.
    runs : sequence of (builder, solver classes)
        Each solver runs one iteration from the builder's guess, then one from that result flagged
        feasible (both kinds of steps).

    Returns
    -------
    int
        0 when every kernel of :data:`crocopy.kernels.KERNELS` is then in numba's cache, else 1 (the
        kernels left out are named on stderr).
    """
    if not kernels.available:
        print("numba is not installed: nothing to compile (the numpy paths run)", file=sys.stderr)
        return 0
    announce_cold_cache()
    before = compilations(kernels.KERNELS)
    t0 = time.perf_counter()
    for builder, solver_classes in runs:
        problem, xs, us = build(builder)
        for solver_class in solver_classes:
            first = solver_class(problem)
            first.solve(xs, us, 1, False)
            solver_class(problem).solve(first.xs, first.us, 1, True)
    new = compilations(kernels.KERNELS) - before
    folders = [str(k._cache._cache_path) for k in kernels.KERNELS if getattr(k, "_cache", None) is not None]
    where = os.path.commonpath(folders) if folders else "none"
    print(f"{len(kernels.KERNELS)} kernels ready in {time.perf_counter() - t0:.1f} s ({new} signatures compiled, "
          f"the others loaded from the cache); cache under {where}")
    missing = [k.py_func.__qualname__ for k in kernels.KERNELS if not kernels.is_cached(k)]
    if missing:
        print(f"not cached (the next run compiles them): {', '.join(missing)}", file=sys.stderr)
        return 1
    return 0
