"""``crocopy bench --threads``: node evaluation on one and on two threads (``problem.nthreads``).

For each problem (default: Talos' taichi and ANYmal's walk, crocopy's builders), the compiled nodes' values and
derivatives (what a DDP-family solve runs per iteration: ``calc`` + ``calcDiff`` of every node, from the builder's
guess) are timed with ``problem.nthreads = 1`` and ``= 2``, rounds interleaved, median wall milliseconds; then
one FDDP solve each checks that the two give the same iterations and bit-identical costs and trajectories.
Crocoddyl 3.2.1's pip wheel is built without multithreading (``nthreads`` has no effect there).  The bar: at least
1.6× faster on two threads of a 2-core machine, bit-identical.
"""

from __future__ import annotations

import os
import statistics
import time

import numpy as np

from .timing import limit_threads

PROBLEMS = ("taichi", "walk")
BAR = 1.6

SECTION = """
## Two threads

`crocopy bench --threads`: the compiled nodes' `calc` + `calcDiff` from the builder's guess with
`problem.nthreads = 1` and `= 2` (median wall ms, rounds interleaved), and one FDDP solve each (same iterations,
bit-identical cost and trajectory).  Crocoddyl 3.2.1's pip wheel has no multithreading: `nthreads` has no effect
there.

"""


def _evaluator(name: str, nthreads: int):
    import crocopy
    from crocopy.problems import registry
    from crocopy.solvers import compiled_nodes

    problem, xs, us = registry.build(name)
    problem.nthreads = nthreads
    solver = crocopy.SolverFDDP(problem)
    solver.setCandidate(xs, us, False)
    nodes = compiled_nodes.attach(solver)
    return lambda: nodes.calcDiff(problem, solver.xs, solver.us, False)


def _solve(name: str, nthreads: int) -> tuple[int, float, list]:
    import crocopy
    from crocopy.problems import registry

    problem, xs, us = registry.build(name)
    problem.nthreads = nthreads
    solver = crocopy.SolverFDDP(problem)
    solver.solve(xs, us, registry.get(name).maxiter)
    return solver.iter, solver.cost, [a.copy() for a in (*solver.xs, *solver.us)]


def run_threads_bench(problems: tuple[str, ...] = PROBLEMS, repeats: int = 15) -> str:
    """The markdown table of :mod:`crocopy.bench.threads` (see the module docstring)."""
    limit_threads()
    rows = ["| problem | 1 thread (ms) | 2 threads (ms) | speed-up | bar (≥ 1.6×) | solve: same iterations, "
            "bit-identical |", "|---|---|---|---|---|---|"]
    for name in problems:
        calls = {k: _evaluator(name, k) for k in (1, 2)}
        for call in calls.values():
            call()
        times: dict[int, list[float]] = {1: [], 2: []}
        for _ in range(repeats):
            for k, call in calls.items():
                start = time.perf_counter()
                call()
                times[k].append(1e3 * (time.perf_counter() - start))
        one, two = statistics.median(times[1]), statistics.median(times[2])
        (i1, c1, a1), (i2, c2, a2) = _solve(name, 1), _solve(name, 2)
        same = i1 == i2 and c1 == c2 and all(np.array_equal(a, b) for a, b in zip(a1, a2, strict=True))
        rows.append(f"| {name} | {one:.3g} | {two:.3g} | {one / two:.2f}× | {'yes' if one / two >= BAR else 'no'} | "
                    f"{'yes' if same else 'NO'} ({i1} iterations) |")
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    return "\n".join(rows) + f"\n\n{os.cpu_count()} cores, load average {load:.2f} at the end.\n"
