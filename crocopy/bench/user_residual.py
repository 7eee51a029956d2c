"""``crocopy bench --user-residual``: what a user's own residual costs against the built-in one.

The Talos-arm reach (:func:`crocopy.problems.user_residual.build_user_reach`, T = 100, FDDP from the
quasi-static guess, one thread) is solved with its goal residual written three ways: the built-in
``ResidualModelFrameTranslation``, the same residual as a ``ResidualModelNumba`` (compiled nodes stay compiled)
and as a Crocoddyl-style Python subclass (only that residual runs in Python).  With the ``bench`` extra,
Crocoddyl solves the built-in and the Python-subclass variants too.  Rounds interleave the variants; the report
gives the iterations, the final cost, the median wall and CPU milliseconds per iteration and each variant's
ratio to its library's built-in residual (bars: numba ≤ 1.10×, Python subclass ≤ 1.5×).
"""

from __future__ import annotations

import statistics
import time
from types import ModuleType

from .side_by_side import BenchDependencyError, require_crocoddyl
from .timing import limit_threads

BARS = {"numba": 1.10, "python": 1.5}

SECTION = """
## A user's residual

`crocopy bench --user-residual`: Talos' arm reaching a point (`crocopy solve reach`, T = 100, FDDP, one thread),
its goal residual written as the built-in `ResidualModelFrameTranslation`, as a `ResidualModelNumba` (numba
functions: the node stays compiled) and as a Crocoddyl-style Python subclass (only that residual runs in Python);
Crocoddyl runs its built-in residual and the same Python subclass.  Medians of interleaved solves; the ratio is to
the same library's built-in residual, on CPU time (less sensitive to the machine's load than wall time).

"""


def _solve_ms(lib: ModuleType, problem, xs: list, us: list) -> tuple[int, float, float, float]:
    """``(iterations, cost, wall ms/iter, CPU ms/iter)`` of one FDDP solve."""
    solver = lib.SolverFDDP(problem)
    wall, cpu = time.perf_counter(), time.process_time()
    solver.solve([x.copy() for x in xs], [u.copy() for u in us], 200)
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    n = max(solver.iter, 1)
    return solver.iter, solver.cost, 1e3 * wall / n, 1e3 * cpu / n


def run_user_residual_bench(repeats: int = 7, crocoddyl: bool | None = None) -> str:
    """The report (Markdown table) of ``repeats`` interleaved rounds; ``crocoddyl``: also run Crocoddyl (default:
    when the ``bench`` extra is installed)."""
    import crocopy
    from crocopy.problems.user_residual import build_user_reach

    limit_threads()
    runs = {("crocopy", v): (crocopy, *build_user_reach(crocopy, v)) for v in ("builtin", "numba", "python")}
    if crocoddyl is not False:
        try:
            lib = require_crocoddyl()
        except BenchDependencyError:
            if crocoddyl:
                raise
        else:
            runs.update({("Crocoddyl", v): (lib, *build_user_reach(lib, v)) for v in ("builtin", "python")})
    samples: dict = {key: [] for key in runs}
    for lib, problem, xs, us in runs.values():
        _solve_ms(lib, problem, xs, us)
    for _ in range(repeats):
        for key, (lib, problem, xs, us) in runs.items():
            samples[key].append(_solve_ms(lib, problem, xs, us))
    medians = {key: (s[-1][0], s[-1][1], statistics.median(r[2] for r in s), statistics.median(r[3] for r in s))
               for key, s in samples.items()}
    lines = ["| library | goal residual | iterations | cost | ms/iter (wall) | ms/iter (CPU) | vs built-in (CPU) |",
             "|---|---|---|---|---|---|---|"]
    for (library, variant), (iters, cost, wall, cpu) in medians.items():
        base = medians[(library, "builtin")][3]
        bar = f" (bar ≤ {BARS[variant]:.2f}×)" if library == "crocopy" and variant in BARS else ""
        lines.append(f"| {library} | {variant} | {iters} | {cost:.6g} | {wall:.2f} | {cpu:.2f} | "
                     f"{cpu / base:.2f}×{bar} |")
    return "\n".join(lines)
