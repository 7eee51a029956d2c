"""How much of crocopy's node evaluation is spent inside Pinocchio's Python bindings (``crocopy bench --floor``).

crocopy evaluates every node from Python and calls Pinocchio through its Python bindings; the time of
those calls is a floor no Python-side optimisation can remove.  This bench runs ``problem.calc`` and
``problem.calcDiff`` of a bundled problem with every function of the ``pinocchio`` module wrapped by
a timer (the wrapper's own cost, calibrated on a no-op binding, is subtracted), and reports

* crocopy's ``calc + calcDiff`` (unwrapped; thread CPU time, medians, samples interleaved with
  Crocoddyl's), the part spent inside Pinocchio calls and the number
  of calls per node;
* with Crocoddyl importable (``bench`` extra), Crocoddyl's ``calc + calcDiff`` on the same problem
  and the *floor ratio* ``Pinocchio-call time / Crocoddyl time``: the per-iteration ratio crocopy
  would reach with every line of its own Python made free.

Only module-level functions (``pinocchio.aba``, ``pinocchio.constraintDynamics``, ...) are wrapped;
methods of Pinocchio objects (``SE3.act``, ``Force`` setters) are not counted, so the floor is a lower
bound.
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable
from types import ModuleType

import pinocchio

from .side_by_side import build_problem
from .timing import limit_threads, loops_for, sample_ms

FLOOR_PROBLEMS = ("pend", "quad-goal", "arm", "jump", "walk", "taichi")


class PinocchioCallTimer:
    """Context manager wrapping every Boost.Python function of :mod:`pinocchio` with a timer.

    Attributes
    ----------
    seconds : float
        Time spent inside the wrapped calls, wrapper overhead (``overhead`` per call) subtracted.
    calls : int
        Number of wrapped calls.
    """

    def __init__(self) -> None:
        self.seconds, self.calls = 0.0, 0
        self.overhead = 0.0
        self._saved: dict[str, Callable] = {}

    def _wrap(self, function: Callable) -> Callable:
        clock = time.perf_counter

        def timed(*args, **kwargs):
            t0 = clock()
            try:
                return function(*args, **kwargs)
            finally:
                self.seconds += clock() - t0
                self.calls += 1

        return timed

    def __enter__(self) -> "PinocchioCallTimer":
        binding = type(pinocchio.aba)
        for name in dir(pinocchio):
            value = getattr(pinocchio, name)
            if type(value) is binding:
                self._saved[name] = value
                setattr(pinocchio, name, self._wrap(value))
        self.overhead = self._calibrate()
        self.seconds, self.calls = 0.0, 0
        return self

    def __exit__(self, *exc: object) -> None:
        for name, value in self._saved.items():
            setattr(pinocchio, name, value)
        self._saved.clear()

    def _calibrate(self, n: int = 2000) -> float:
        """Per-call cost of the wrapper: a wrapped cheap binding minus the bare binding."""
        bare, wrapped = self._saved["neutral"], pinocchio.neutral
        model = pinocchio.Model()
        samples = []
        for _ in range(5):
            t0 = time.perf_counter()
            for _ in range(n):
                bare(model)
            t1 = time.perf_counter()
            for _ in range(n):
                wrapped(model)
            t2 = time.perf_counter()
            samples.append(((t2 - t1) - (t1 - t0)) / n)
        return max(0.0, min(samples))

    @property
    def pinocchio_seconds(self) -> float:
        """Time inside the bindings with the wrapper overhead removed (never below zero)."""
        return max(0.0, self.seconds - self.calls * self.overhead)


def _evaluator(problem, xs: list, us: list) -> Callable[[], None]:
    def evaluate() -> None:
        problem.calc(xs, us)
        problem.calcDiff(xs, us)

    return evaluate


def floor_of_problem(name: str, crocopy: ModuleType, crocoddyl: ModuleType | None, repeats: int = 7) -> dict:
    """Figures of one problem (CPU ms per ``calc + calcDiff`` over the horizon; the two libraries' samples
    interleaved, medians); see the module docstring."""
    problem, xs, us = build_problem(name, crocopy)
    evaluators = {"crocopy": _evaluator(problem, xs, us)}
    if crocoddyl is not None:
        evaluators["crocoddyl"] = _evaluator(*build_problem(name, crocoddyl))
    loops = {lib: loops_for(fn) for lib, fn in evaluators.items()}
    samples: dict[str, list[float]] = {lib: [] for lib in evaluators}
    for _ in range(repeats):
        for lib, fn in evaluators.items():
            samples[lib].append(sample_ms(fn, loops[lib], time.thread_time))
    inside = []
    with PinocchioCallTimer() as timer:  # wall clock inside the calls: run it on a quiet machine
        evaluators["crocopy"]()
        for _ in range(repeats):
            timer.seconds, timer.calls = 0.0, 0
            evaluators["crocopy"]()
            inside.append(1e3 * timer.pinocchio_seconds)
        calls = timer.calls
    return {
        "problem": name,
        "T": problem.T,
        "crocopy": statistics.median(samples["crocopy"]),
        "pinocchio": statistics.median(inside),
        "calls_per_node": calls / (problem.T + 1),
        "crocoddyl": statistics.median(samples["crocoddyl"]) if crocoddyl is not None else None,
    }


def format_floor(rows: list[dict]) -> str:
    """Markdown table of :func:`floor_of_problem` rows."""
    lines = [
        "## Pinocchio-binding floor of calc + calcDiff (ms over the horizon)",
        "",
        "| problem | T | crocopy | in Pinocchio calls | calls / node | Crocoddyl | crocopy / Crocoddyl "
        "| floor: Pinocchio calls / Crocoddyl |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        theirs = r["crocoddyl"]
        cells = [r["problem"], str(r["T"]), f"{r['crocopy']:.3g}", f"{r['pinocchio']:.3g}"]
        cells.append(f"{r['calls_per_node']:.1f}")
        if theirs:
            cells += [f"{theirs:.3g}", f"{r['crocopy'] / theirs:.2f}×", f"{r['pinocchio'] / theirs:.2f}×"]
        else:
            cells += ["—", "—", "—"]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def run_floor_bench(problems: tuple[str, ...] = FLOOR_PROBLEMS, repeats: int = 7) -> str:
    """Run :func:`floor_of_problem` on ``problems`` (Crocoddyl side when importable) and return the table."""
    limit_threads()
    import crocopy

    try:
        import crocoddyl
    except ImportError:
        crocoddyl = None
    rows = [floor_of_problem(name, crocopy, crocoddyl, repeats) for name in problems]
    return format_floor(rows)
