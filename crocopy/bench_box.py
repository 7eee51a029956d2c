"""Box-DDP / Box-FDDP parity with Crocoddyl 3.2 and the box-QP backward-pass overhead.

``crocopy bench --box-parity`` (needs the ``bench`` extra) solves each problem of
:data:`PARITY_PROBLEMS` with Crocoddyl's ``SolverBoxDDP``/``SolverBoxFDDP`` and with crocopy's, built
by the same registry builder, warm-started with the builder's guess (``isFeasible=False``), one
thread, the problem's ``maxiter``.  crocopy runs twice: with its defaults (the papers' rules) and with
``compat_crocoddyl = True`` (Crocoddyl 3.2's three departures from the papers, see
:mod:`crocopy.solvers.box_ddp`).  For each run it prints iterations, final cost, the relative cost
difference to Crocoddyl, the first iteration whose cost or stopping value differs from Crocoddyl's by
more than :data:`RTOL` (relative), and whether the bar (same iterations, final cost within
:data:`RTOL`) is met.

It also times the backward pass of Box-FDDP against plain FDDP's on the ANYmal jump at a feasible
iterate with clamped controls (same derivatives, interleaved medians): the box-QP overhead.
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from types import ModuleType

from .bench_problems import BenchDependencyError, build_problem, require_crocoddyl

__all__ = ["PARITY_PROBLEMS", "RTOL", "BenchDependencyError", "Trace", "solve_trace", "first_divergence",
           "meets_bar", "backward_overhead", "run_box_parity"]

PARITY_PROBLEMS = ("quad-goal", "quad-loop", "quad-narrow", "arm", "jump")
"""The bar's problems: the three quadrotor tasks, the Kinova arm with torque limits, the ANYmal jump."""

RTOL = 1e-6
"""Relative tolerance of the parity bar on the final cost (and of the per-iteration comparison)."""

SOLVERS = {"boxddp": "SolverBoxDDP", "boxfddp": "SolverBoxFDDP"}


@dataclass
class Trace:
    """One solve: result and the per-iteration ``(cost, stop, stepLength)`` of the callbacks."""

    iters: int
    cost: float
    converged: bool
    seconds: float
    log: list[tuple[float, float, float]] = field(default_factory=list)


def _callback(lib: ModuleType, log: list) -> object:
    def record(solver) -> None:
        log.append((float(solver.cost), float(solver.stop), float(solver.stepLength)))

    if lib.__name__ != "crocoddyl":
        return record

    class Recorder(lib.CallbackAbstract):
        def __init__(self) -> None:
            lib.CallbackAbstract.__init__(self)

        def __call__(self, solver) -> None:
            record(solver)

    return Recorder()


def solve_trace(lib: ModuleType, name: str, solver_name: str, maxiter: int | None = None,
                compat: bool = False) -> Trace:
    """Solve registry problem ``name`` with ``lib``'s Box solver and record every iteration.

    Parameters
    ----------
    lib : module
        ``crocopy`` or ``crocoddyl``.
    name : str
        Registry name.
    solver_name : str
        ``"boxddp"`` or ``"boxfddp"``.
    maxiter : int, optional
        Iteration limit (default: the problem's).
    compat : bool
        crocopy only: set ``compat_crocoddyl``.
    """
    from .problems import registry

    if solver_name not in SOLVERS:
        raise ValueError(f"solver_name: expected one of {sorted(SOLVERS)}, got {solver_name!r}")
    maxiter = registry.get(name).maxiter if maxiter is None else int(maxiter)
    problem, xs, us = build_problem(name, lib)
    solver = getattr(lib, SOLVERS[solver_name])(problem)
    if compat:
        solver.compat_crocoddyl = True
    log: list[tuple[float, float, float]] = []
    solver.setCallbacks([_callback(lib, log)])
    t0 = time.perf_counter()
    converged = bool(solver.solve(xs, us, maxiter, False))
    return Trace(int(solver.iter), float(solver.cost), converged, time.perf_counter() - t0, log)


def _rel(a: float, b: float) -> float:
    return abs(a - b) / max(abs(a), 1e-300)


def first_divergence(ref: Trace, other: Trace, rtol: float = RTOL) -> int | None:
    """First iteration whose cost or stopping value differs by more than ``rtol`` (or whose step
    length differs); ``None`` if the two logs agree over their common length and have equal length."""
    for i, (a, b) in enumerate(zip(ref.log, other.log)):
        if _rel(a[0], b[0]) > rtol or _rel(a[1], b[1]) > rtol or a[2] != b[2]:
            return i
    return None if len(ref.log) == len(other.log) else min(len(ref.log), len(other.log))


def meets_bar(ref: Trace, other: Trace, rtol: float = RTOL) -> bool:
    """Same number of iterations and final cost within ``rtol`` (relative)."""
    return ref.iters == other.iters and _rel(ref.cost, other.cost) <= rtol


def backward_overhead(name: str = "jump", warm_iters: int = 60, repeats: int = 15) -> dict[str, float]:
    """Median ms of Box-FDDP's and FDDP's backward passes on the same feasible iterate of ``name``.

    The iterate is crocopy's Box-FDDP after ``warm_iters`` iterations (feasible, controls on their
    bounds); both solvers differentiate it once and their backward passes are timed interleaved.
    Returns ``{"box": ms, "plain": ms, "ratio": box/plain, "clamped_nodes": n}``.
    """
    import crocopy

    problem, xs, us = build_problem(name, crocopy)
    warm = crocopy.SolverBoxFDDP(problem)
    warm.solve(xs, us, warm_iters, False)
    box = crocopy.SolverBoxFDDP(problem)
    plain = crocopy.SolverFDDP(problem)
    for s in (box, plain):
        s.setCandidate(warm.xs, warm.us, True)
        s.preg = s.dreg = 1e-9
    box.computeDirection(True)
    plain.computeDirection(True)
    clamped = int(sum(box._clamped))
    samples: dict[str, list[float]] = {"box": [], "plain": []}
    calls: dict[str, Callable[[], None]] = {"box": box.backwardPass, "plain": plain.backwardPass}
    for r in range(repeats):
        for key in ("box", "plain") if r % 2 == 0 else ("plain", "box"):
            t0 = time.perf_counter()
            calls[key]()
            samples[key].append(1e3 * (time.perf_counter() - t0))
    out = {k: statistics.median(v) for k, v in samples.items()}
    out["ratio"] = out["box"] / out["plain"]
    out["clamped_nodes"] = clamped
    return out


def _row(problem: str, solver: str, label: str, ref: Trace, t: Trace) -> str:
    div = first_divergence(ref, t)
    mark = "met" if meets_bar(ref, t) else "not met"
    return (f"| {problem} | {solver} | {label} | {t.iters} | {t.cost:.10g} | {_rel(ref.cost, t.cost):.1e} | "
            f"{'-' if div is None else div} | {mark} |")


def run_box_parity(problems: Sequence[str] | None = None, solvers: Sequence[str] = ("boxddp", "boxfddp"),
                   maxiter: int | None = None, overhead: bool = True,
                   progress: Callable[[str], None] | None = None) -> str:
    """Markdown report of the parity runs (and the backward-pass overhead on the jump).

    Raises
    ------
    BenchDependencyError
        If Crocoddyl cannot be used.
    KeyError
        If a problem name is not registered.
    """
    import crocopy

    from .bench_problems import _limit_threads
    from .problems import registry

    crocoddyl = require_crocoddyl()
    _limit_threads()
    names = list(problems or PARITY_PROBLEMS)
    for n in names:
        registry.get(n)
    lines = [
        f"Box solvers vs Crocoddyl 3.2 (bar: same iterations, final cost within {RTOL:g} relative)",
        "",
        "| problem | solver | library | iters | final cost | rel. diff | first diverging iter | bar |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for name in names:
        for solver in solvers:
            ref = solve_trace(crocoddyl, name, solver, maxiter)
            lines.append(f"| {name} | {solver} | Crocoddyl | {ref.iters} | {ref.cost:.10g} | | | |")
            for label, compat in (("crocopy", False), ("crocopy compat", True)):
                lines.append(_row(name, solver, label, ref, solve_trace(crocopy, name, solver, maxiter, compat)))
            if progress:
                progress("\n".join(lines[-3:]))
    if overhead:
        o = backward_overhead()
        lines += ["", f"Backward pass on the ANYmal jump, feasible iterate with {o['clamped_nodes']} clamped nodes: "
                  f"Box-FDDP {o['box']:.2f} ms, FDDP {o['plain']:.2f} ms, ratio {o['ratio']:.2f}x (bar 1.5x)"]
    return "\n".join(lines)
