"""Benchmarks of crocopy (and, with the ``bench`` extra, Crocoddyl on the same problems).

``crocopy bench`` times DDP on LQR problems of ANYmal-like (nx=36, nu=12) and Talos-like
(nx=76, nu=32) sizes, T=100: milliseconds per iteration and per phase (calc, calcDiff,
backward pass, forward pass), medians over repeats, single-threaded BLAS.  With Crocoddyl
importable it builds the same problem with Crocoddyl's ``ActionModelLQR`` and prints the ratio.
"""

from __future__ import annotations

import importlib
import statistics
import time
from collections.abc import Callable

import numpy as np

from ..guards import trusted_path
from .timing import limit_threads


def lqr_problem(lib, nx: int, nu: int, T: int = 100, seed: int = 0):
    """A random stable LQR shooting problem built through ``lib``'s public API (crocopy or crocoddyl)."""
    rng = np.random.default_rng(seed)
    A = np.eye(nx) + 0.01 * rng.standard_normal((nx, nx))
    B = 0.1 * rng.standard_normal((nx, nu))
    Q, R, N = np.eye(nx), np.eye(nu), np.zeros((nx, nu))
    model = lib.ActionModelLQR(A, B, Q, R, N, np.zeros(nx), rng.standard_normal(nx), rng.standard_normal(nu))
    return lib.ShootingProblem(rng.standard_normal(nx), [model] * T, model)


def _median_ms(fn: Callable[[], object], repeats: int) -> float:
    samples = []
    with trusted_path():  # timed as a solve runs it, without a user's call checks
        for _ in range(repeats):
            t0 = time.perf_counter()
            fn()
            samples.append(time.perf_counter() - t0)
    return 1e3 * statistics.median(samples)


def time_phases(lib, problem, repeats: int = 20) -> dict[str, float]:
    """Median ms of calc, calcDiff, backward pass, forward pass and one full DDP iteration."""
    solver = lib.SolverDDP(problem)
    T = problem.T
    xs = [problem.x0] * (T + 1)
    us = [np.zeros(problem.runningModels[0].nu)] * T
    solver.setCandidate(xs, us, False)
    problem.calc(solver.xs, solver.us)
    problem.calcDiff(solver.xs, solver.us)
    solver.preg = solver.dreg = 1e-9
    solver.computeDirection(True)
    out = {
        "calc": _median_ms(lambda: problem.calc(solver.xs, solver.us), repeats),
        "calcDiff": _median_ms(lambda: problem.calcDiff(solver.xs, solver.us), repeats),
        "backward": _median_ms(solver.backwardPass, repeats),
        "forward": _median_ms(lambda: solver.forwardPass(1.0), repeats),
    }

    fresh = lib.SolverDDP(problem)
    out["iteration"] = _median_ms(lambda: fresh.solve(xs, us, 1, False), repeats)
    return out


def run_lqr_bench(repeats: int = 20, T: int = 100) -> str:
    """Markdown table of the LQR benchmark; includes Crocoddyl when it can be imported."""
    limit_threads()
    import crocopy

    libs = [("crocopy", crocopy)]
    try:
        libs.append(("crocoddyl", importlib.import_module("crocoddyl")))
    except ImportError:
        pass
    lines = [
        f"LQR benchmark, T={T}, median of {repeats} runs, ms (per node in µs for the backward pass)",
        "",
        "| size (nx, nu) | library | calc | calcDiff | backward | backward µs/node | forward | DDP iteration | ratio |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for nx, nu in ((36, 12), (76, 32)):
        results = {name: time_phases(lib, lqr_problem(lib, nx, nu, T), repeats) for name, lib in libs}
        ref = results.get("crocoddyl")
        for name, r in results.items():
            ratio = f"{r['iteration'] / ref['iteration']:.2f}×" if ref and name == "crocopy" else ""
            lines.append(
                f"| ({nx}, {nu}) | {name} | {r['calc']:.3f} | {r['calcDiff']:.3f} | {r['backward']:.3f} | "
                f"{1e3 * r['backward'] / T:.1f} | {r['forward']:.3f} | {r['iteration']:.3f} | {ratio} |"
            )
    return "\n".join(lines)
