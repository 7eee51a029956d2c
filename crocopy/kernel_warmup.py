"""Getting the compiled kernels ready: the first-run notice with its progress count, the warm-up call, and
``crocopy compile``.

A kernel (:mod:`crocopy.kernels`) is compiled on its first call with new argument types, unless
numba's on-disk cache holds it; loading it from the cache takes a fraction of a second.  Here:

* :class:`CompileProgress` prints :data:`COMPILING_NOTICE` with a count (``compiling kernels (first run
  only): 12/40``) as soon as numba starts compiling a kernel, and nothing at all when every kernel a run
  needs is loaded from the cache.  The count's total is the kernels the ones being compiled call, directly
  or not, that the cache does not hold (read from their sources, :func:`crocopy.kernels.kernel_callees`):
  only what the problem in hand needs;
* :func:`warm_up_kernels` runs a call (one solver iteration) that loads or compiles the kernels under a
  :class:`CompileProgress`;
* :func:`compile_kernels` (``crocopy compile``) runs warm-up solves that call every kernel, so that
  later processes only load them.
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable, Sequence
from typing import TextIO

from . import kernels

COMPILING_NOTICE = "compiling kernels (first run only)"


def compilations(dispatchers: Sequence) -> int:
    """Signatures compiled so far in this process (not loaded from numba's cache) by ``dispatchers``."""
    return sum(sum(d.stats.cache_misses.values()) for d in dispatchers)


class CompileProgress:
    """The first-run notice: ``compiling kernels (first run only): done/total`` on ``stream`` (default stderr).

    Called with a kernel whenever numba starts compiling one (:func:`crocopy.kernels.watch_compilations`).
    The first call prints the notice; on a terminal the line is then rewritten in place at every kernel,
    elsewhere (a pipe, a log) a new line is printed at most every ``interval`` seconds.  ``done`` counts the
    kernels compiled so far; ``total`` adds those they call, directly or not, that numba's cache lacks.
    Nothing is printed when nothing is compiled.  ``on_compile`` (if given) is called once, at the first
    compilation (e.g. to start work that can overlap it).
    """

    def __init__(self, stream: TextIO | None = None, interval: float = 5.0,
                 clock: Callable[[], float] = time.perf_counter,
                 on_compile: Callable[[], object] | None = None) -> None:
        self.stream = sys.stderr if stream is None else stream
        self.on_compile = on_compile
        self.interval = interval
        self.clock = clock
        self.compiled: dict[int, object] = {}
        self.expected: dict[int, object] = {}
        self.signatures = 0
        self.started: float | None = None
        self.printed: float | None = None
        self._cached: dict[int, bool] = {}

    @property
    def terminal(self) -> bool:
        isatty = getattr(self.stream, "isatty", None)
        return bool(isatty and isatty())

    def line(self) -> str:
        """The notice with its count."""
        return f"{COMPILING_NOTICE}: {len(self.compiled)}/{len(self.expected)}"

    def _expect(self, kernel: object) -> None:
        """Add ``kernel`` and the uncached kernels it calls, directly or not, to the total."""
        stack = [kernel]
        while stack:
            k = stack.pop()
            if id(k) in self.expected:
                continue
            self.expected[id(k)] = k
            for callee in kernels.kernel_callees(k):
                if id(callee) not in self._cached:
                    self._cached[id(callee)] = kernels.is_cached(callee)
                if not self._cached[id(callee)]:
                    stack.append(callee)

    def __call__(self, kernel: object) -> None:
        now = self.clock()
        if self.started is None:
            self.started = now
            if self.on_compile is not None:
                self.on_compile()
        self.signatures += 1
        self.compiled[id(kernel)] = kernel
        self._expect(kernel)
        if self.terminal:
            self.stream.write("\r" + self.line())
        elif self.printed is None or now - self.printed >= self.interval:
            self.stream.write(self.line() + "\n")
            self.printed = now
        self.stream.flush()

    def finish(self) -> float:
        """Close the notice with the count and the seconds since the first compilation (returned; 0.0 and
        nothing printed when nothing was compiled)."""
        if self.started is None:
            return 0.0
        elapsed = self.clock() - self.started
        if self.terminal:
            self.stream.write("\r" + self.line() + "\n")
        self.stream.write(f"kernels compiled in {elapsed:.1f} s: {len(self.compiled)} kernels, {self.signatures}"
                          f" signatures (cached for the next runs; not counted in the solve time)\n")
        self.stream.flush()
        return elapsed


def warm_up_kernels(run: Callable[[], object], progress: CompileProgress | None = None) -> float:
    """Call ``run()`` once under ``progress`` (default: a :class:`CompileProgress` on stderr), which announces
    the kernels it compiles; return the seconds compiling took (``0.0``, silently, when every kernel was
    loaded from numba's cache)."""
    progress = CompileProgress() if progress is None else progress
    with kernels.watch_compilations(progress):
        run()
    return progress.finish()


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
    before = compilations(kernels.KERNELS)
    t0 = time.perf_counter()
    progress = CompileProgress()
    with kernels.watch_compilations(progress):
        for builder, solver_classes in runs:
            problem, xs, us = build(builder)
            for solver_class in solver_classes:
                first = solver_class(problem)
                first.solve(xs, us, 1, False)
                solver_class(problem).solve(first.xs, first.us, 1, True)
    progress.finish()
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
