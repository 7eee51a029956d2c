"""Peak memory (and time) of one (problem, library) solve, run as ``python -m crocopy.bench.memory``.

``python -m crocopy.bench.memory NAME LIBRARY SOLVER MAXITER`` imports the library (``crocopy``
or ``crocoddyl``), Pinocchio and the problem registry, warms up with two iterations of ``SOLVER``
on another small problem (:func:`warm_up`: crocopy's numba kernels are loaded, or compiled
after a source change, before anything is measured: one-time costs that Crocoddyl, compiled ahead
of time, does not have; another problem, since a problem's own memory freed by the warm-up would
be reused by its measured build),
resets the process's resident-memory high-water mark (``/proc/self/clear_refs``, Linux) and
records it (the baseline), builds problem ``NAME`` with one thread, solves it from the builder's
guess with ``SOLVER`` (a key of :data:`crocopy.bench.side_by_side.SOLVER_CLASSES`) and ``MAXITER``
iterations, and prints one JSON line: ``baseline_kib``, ``peak_kib`` (the high-water mark after
the solve), ``hwm_reset`` (whether the reset worked; without it a transient peak during the
imports can hide a smaller problem's), ``iters``, ``cost``, ``converged`` and ``seconds`` (the
solve's wall time).

The high-water mark is the process's own ``VmHWM`` (``/proc/self/status``), not
``getrusage(RUSAGE_SELF).ru_maxrss``: on Linux ``ru_maxrss`` is never below the parent's peak at
the time of the ``exec`` (a child spawned by a benchmark that already holds big problems would
report no growth at all).  ``ru_maxrss`` is the fallback where ``/proc`` is missing.
"""

from __future__ import annotations

import gc
import importlib
import json
import resource
import sys
import time


def reset_peak_memory() -> bool:
    """Reset the resident-set high-water mark to the current RSS; False where the kernel does not allow it."""
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
    except OSError:
        return False
    return True


def peak_memory_kib() -> int:
    """This process's resident-memory high-water mark in KiB (``VmHWM``, else ``ru_maxrss``)."""
    try:
        with open("/proc/self/status", encoding="ascii") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1])
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss


def warmup_problem(name: str) -> str:
    """The small problem solved before measuring ``name``: the quadrotor goal task (its nodes are
    compiled nodes, :mod:`crocopy.solvers.compiled_nodes`), or the arm when ``name`` is a quadrotor task."""
    return "arm" if name.startswith("quad") else "quad-goal"


def warm_up(lib, name: str, solver_name: str) -> None:
    """Two iterations of the solver on :func:`warmup_problem` from its guess and two from the rollout of its controls
    (a feasible start: crocopy's line search then runs in one compiled call); for crocopy, also once through a solver
    subclass (the Python node path), so that every kernel either path uses is loaded."""
    from .side_by_side import build_problem, make_solver

    problem, xs, us = build_problem(warmup_problem(name), lib)
    solver = make_solver(lib, problem, solver_name)
    solver.solve(xs, us, 2, False)
    make_solver(lib, problem, solver_name).solve(problem.rollout(us), us, 2, True)
    if lib.__name__ == "crocopy":
        solver = make_solver(lib, problem, solver_name)
        python_nodes = type("PythonNodes" + type(solver).__name__, (type(solver),), {})
        python_nodes(problem).solve(xs, us, 2, False)


def main(argv: list[str] | None = None) -> int:
    """Run one measurement and print its JSON line; returns the exit code."""
    name, library, solver_name, maxiter = argv if argv is not None else sys.argv[1:]
    from ..problems import registry
    from .side_by_side import build_problem, make_solver
    from .timing import limit_threads

    limit_threads()
    lib = importlib.import_module(library)
    registry.get(name)
    warm_up(lib, name, solver_name)
    gc.collect()
    reset = reset_peak_memory()
    baseline = peak_memory_kib()
    problem, xs, us = build_problem(name, lib)
    solver = make_solver(lib, problem, solver_name)
    t0 = time.perf_counter()
    converged = solver.solve(xs, us, int(maxiter), False)
    seconds = time.perf_counter() - t0
    peak = peak_memory_kib()
    report = {
        "baseline_kib": baseline,
        "peak_kib": peak,
        "hwm_reset": reset,
        "iters": int(solver.iter),
        "cost": float(solver.cost),
        "converged": bool(converged),
        "seconds": seconds,
    }
    print(json.dumps(report))
    return 0


if __name__ == "__main__":
    sys.exit(main())
