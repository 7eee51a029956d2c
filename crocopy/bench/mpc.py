"""``crocopy bench --mpc``: the cycle of a model-predictive controller, crocopy and Crocoddyl side by side.

For each problem (default: the quadrotor goal, the arm reach and ANYmal's walk, crocopy's builders built with each
library), one FDDP solve from the builder's guess gives the warm start; then each cycle, as a controller tracking a
moving target does:

1. assigns a new reference to every state residual of the problem's nodes (``residual.reference = xref``, the last
   entry moved by ``±0.001``), and
2. solves one FDDP iteration from the last solution (``solve(xs, us, 1, False)``), which becomes the next warm start.

Reported: the median wall milliseconds of a cycle over ``cycles`` cycles (after ``warmup`` untimed ones), one thread
on both sides.  A cycle's solve re-reads the changed references into the compiled nodes (their layout did not
change: :mod:`crocopy.versioning`) and ends with the nodes' datas filled on the Python path, as every solve.
"""

from __future__ import annotations

import statistics
import time
from types import ModuleType

import numpy as np

from .timing import limit_threads

PROBLEMS = ("quad-goal", "arm", "walk")

SECTION = """
## Model-predictive cycle

`crocopy bench --mpc`: after one FDDP solve from the builder's guess, each cycle assigns a new reference to every
state residual (`residual.reference = xref`) and runs one warm-started FDDP iteration (`solve(xs, us, 1, False)`);
median wall ms per cycle, one thread on both sides.

"""


def state_residuals(problem) -> list:
    """The state residuals of the cost sums of the problem's nodes that have a differential model."""
    found = []
    for model in [*problem.runningModels, problem.terminalModel]:
        dam = getattr(model, "differential", None)
        if dam is None:
            continue
        costs = dam.costs.costs
        items = costs.todict() if hasattr(costs, "todict") else costs
        found += [item.cost.residual for item in items.values()
                  if type(item.cost.residual).__name__ == "ResidualModelState"]
    return found


def run_cycles(lib: ModuleType, name: str, cycles: int = 20, warmup: int = 3) -> dict:
    """The cycles of the module docstring on problem ``name`` (a registry builder) built with ``lib`` (:mod:`crocopy`
    or ``crocoddyl``).

    Returns
    -------
    dict
        ``ms`` (median wall milliseconds of a timed cycle), ``T``, ``references`` (state residuals set per cycle),
        ``cost`` (the last cycle's) and ``xs``/``us`` (its solution).
    """
    from ..problems import registry

    spec = registry.get(name)
    problem, xs, us = spec.build(lib)
    if problem.nthreads != 1:
        problem.nthreads = 1
    solver = lib.SolverFDDP(problem)
    solver.solve(xs, us, spec.maxiter, False)
    xs, us = list(solver.xs), list(solver.us)
    residuals = state_residuals(problem)
    references = [np.array(r.reference) for r in residuals]
    times = []
    for k in range(warmup + cycles):
        start = time.perf_counter()
        for residual, reference in zip(residuals, references):
            moved = reference.copy()
            moved[-1] += 1e-3 * (k % 3 - 1)
            residual.reference = moved
        solver.solve(xs, us, 1, False)
        xs, us = list(solver.xs), list(solver.us)
        times.append(time.perf_counter() - start)
    return {"ms": 1e3 * statistics.median(times[warmup:]), "T": problem.T, "references": len(residuals),
            "cost": float(solver.cost), "xs": [np.array(x) for x in xs], "us": [np.array(u) for u in us]}


def run_mpc_bench(problems: tuple[str, ...] = PROBLEMS, cycles: int = 20, crocoddyl: bool = True) -> str:
    """The markdown table of :mod:`crocopy.bench.mpc`; Crocoddyl's column when ``crocoddyl`` and it is installed."""
    import crocopy

    limit_threads()
    other = None
    if crocoddyl:
        try:
            import crocoddyl as other
        except ImportError:
            other = None
    rows = ["| problem | T | references set per cycle | crocopy ms/cycle | Crocoddyl ms/cycle | crocopy / Crocoddyl |",
            "|---|---|---|---|---|---|"]
    for name in problems:
        mine = run_cycles(crocopy, name, cycles)
        theirs = run_cycles(other, name, cycles) if other is not None else None
        their_ms = "not run" if theirs is None else f"{theirs['ms']:.2f}"
        ratio = "" if theirs is None else f"{mine['ms'] / theirs['ms']:.2f}×"
        rows.append(f"| {name} | {mine['T']} | {mine['references']} | {mine['ms']:.2f} | {their_ms} | {ratio} |")
    return SECTION + "\n".join(rows) + "\n"
