"""Side-by-side benchmark of crocopy and Crocoddyl on the bundled problems (``crocopy bench --vs crocoddyl``).

For every problem (default: :data:`VS_PROBLEMS`, the Box-FDDP paper's Table I plus the ANYmal walk
and the Kinova arm) the same builder makes the problem with each library (Crocoddyl with
``problem.nthreads = 1``; one BLAS thread on both sides) and measures, per library:

* **solve**: the full solve with the chosen solver (Box-FDDP unless told otherwise) from the
  builder's guess with the problem's ``maxiter``: iterations, final cost, convergence and the wall
  time per iteration (solve time / iterations).  The first solve of each library runs in a fresh
  subprocess (:mod:`crocopy.bench.memory`, after a warm-up solve of a small problem that loads the
  numba kernels) that also measures its **peak memory**: the resident high-water mark after the
  solve minus that after the imports and warm-up (reset there), in MiB — Crocoddyl allocates in
  C++, where ``tracemalloc`` cannot see.  Further solves run in this process, the libraries
  alternating, up to ``repeats`` in all while the next round fits in ``solve_budget`` seconds, so
  the big problems (hop, monkey bar) are solved once per library; the wall time per iteration is
  the median over the runs (their number is reported).
* **phases**: milliseconds of ``problem.calc``, ``problem.calcDiff``, the backward pass
  (``solver.computeDirection(False)``) and the forward pass (``solver.tryStep``: the rollout,
  which also evaluates every node) on a fixed trajectory (the builder's guess, after one
  ``computeDirection``), medians over ``repeats`` samples, the libraries interleaved sample by
  sample so load drift hits both.  A short phase is looped within a sample to last ≥ 20 ms.  The
  step length is the largest of 1, 1/2, ... whose rollout stays finite for both libraries.
  ``total`` = calcDiff + backward + forward: the work of one iteration with one line-search trial
  (the forward pass does the iteration's calc).  crocopy's phases run as its solve runs them: with
  the compiled nodes where they apply (:func:`crocopy.solvers.compiled_nodes.attach`; ``calc`` and
  ``calcDiff`` are then those nodes' evaluations, whose ``calcDiff`` also evaluates the node, on the solver's
  trajectories whose addresses are read once, as in a solve).

:mod:`crocopy.bench.report` turns the results into the markdown report.
"""

from __future__ import annotations

import importlib
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from types import ModuleType

from ..solvers import SOLVERS, compiled_nodes
from .timing import limit_threads, loops_for, sample_ms

VS_PROBLEMS = ("pend", "quad-goal", "quad-loop", "quad-narrow", "man", "taichi", "jump", "hop", "bar", "walk", "arm")
"""Default problems: ``crocopy table1`` (the Box-FDDP paper's Table I) plus the ANYmal walk and the arm."""

SOLVER_CLASSES = SOLVERS
"""``--solver`` choice → class name (the same in both libraries)."""

PHASES = ("calc", "calcDiff", "backward", "forward")
"""Timed phases, in the order of one solver iteration."""

LIBRARIES = ("crocopy", "crocoddyl")


BENCH_EXTRA_HINT = "install the benchmark extra: pip install 'crocopy[bench]' (crocoddyl 3.2.1 with pin 4.0.0)"


class BenchDependencyError(RuntimeError):
    """Crocoddyl (the ``bench`` extra) is missing or unusable."""


def require_crocoddyl() -> ModuleType:
    """Import Crocoddyl for a side-by-side run.

    Raises
    ------
    BenchDependencyError
        If ``crocoddyl`` cannot be imported, or Pinocchio is not the 4.0.0 it was compiled against
        (with another Pinocchio it computes wrong numbers or crashes); the message names the extra.
    """
    try:
        crocoddyl = importlib.import_module("crocoddyl")
    except ImportError as exc:
        message = f"crocopy bench --vs crocoddyl needs Crocoddyl ({exc}); {BENCH_EXTRA_HINT}"
        raise BenchDependencyError(message) from None
    import pinocchio

    if pinocchio.__version__ != "4.0.0":
        found = f"Crocoddyl {crocoddyl.__version__} needs Pinocchio 4.0.0, found {pinocchio.__version__}"
        raise BenchDependencyError(f"{found}; {BENCH_EXTRA_HINT}")
    return crocoddyl


@dataclass
class LibResult:
    """One library's figures on one problem (times in ms, memory in MiB)."""

    iters: int
    cost: float
    converged: bool
    ms_per_iter: float
    """Median wall time of the full solve divided by its iterations."""
    solve_runs: int
    phases: dict[str, float] = field(default_factory=dict)
    """Median ms of each of :data:`PHASES` and of ``total``."""
    memory_mib: float | None = None


@dataclass
class ProblemResult:
    """Both libraries' figures on one problem."""

    name: str
    dims: tuple[int, int, int]
    solver: str
    maxiter: int
    libs: dict[str, LibResult] = field(default_factory=dict)

    def ratio(self, key: str) -> float | None:
        """crocopy / Crocoddyl for ``key`` (a phase, ``total``, ``ms_per_iter`` or ``memory_mib``)."""
        if "crocopy" not in self.libs or "crocoddyl" not in self.libs:
            return None
        a, b = (_figure(self.libs[lib], key) for lib in LIBRARIES)
        return a / b if a is not None and b else None

    def cost_rel_diff(self) -> float | None:
        """``|cost_crocopy - cost_Crocoddyl| / |cost_Crocoddyl|`` (None without both libraries)."""
        if "crocopy" not in self.libs or "crocoddyl" not in self.libs:
            return None
        a, b = self.libs["crocopy"].cost, self.libs["crocoddyl"].cost
        return abs(a - b) / max(abs(b), 1e-300)

    def agree(self, rtol: float = 1e-6) -> bool | None:
        """Same iterations and final costs equal to ``rtol`` relative (None without both libraries)."""
        diff = self.cost_rel_diff()
        if diff is None:
            return None
        return self.libs["crocopy"].iters == self.libs["crocoddyl"].iters and diff <= rtol


def _figure(result: LibResult, key: str) -> float | None:
    if key in ("ms_per_iter", "memory_mib"):
        return getattr(result, key)
    return result.phases.get(key)


def _library(name: str) -> ModuleType:
    if name == "crocoddyl":
        return require_crocoddyl()
    if name == "crocopy":
        return importlib.import_module("crocopy")
    raise ValueError(f"libraries: expected names among {LIBRARIES}, got {name!r}")


def build_problem(name: str, lib: ModuleType) -> tuple:
    """``registry.build(name, lib)`` with one thread for the problem's node loop: ``(problem, xs, us)``."""
    from ..problems import registry

    problem, xs, us = registry.build(name, lib)
    if problem.nthreads != 1:  # Crocoddyl warns on every assignment when built without threads
        problem.nthreads = 1
    return problem, [x.copy() for x in xs], [u.copy() for u in us]


def make_solver(lib: ModuleType, problem, solver_name: str):
    """The solver ``solver_name`` of ``lib`` on ``problem``; crocopy's box solvers in ``compat_crocoddyl``
    mode, so that both libraries run the same algorithm (crocopy's default follows the papers)."""
    solver = getattr(lib, SOLVER_CLASSES[solver_name])(problem)
    if hasattr(solver, "compat_crocoddyl"):
        solver.compat_crocoddyl = True
    return solver


def _phase_calls(
    lib: ModuleType, problem, xs, us, solver_name: str
) -> tuple[dict[str, Callable[[], object]], list[float]]:
    """The phase callables on the fixed trajectory ``(xs, us)`` after one setup iteration.

    Also returns the one-element list the forward callable reads its step length from (set by
    :func:`_common_steplength`).
    """
    solver = make_solver(lib, problem, solver_name)
    solver.setCandidate(xs, us, False)
    nodes = compiled_nodes.attach(solver) if lib.__name__ == "crocopy" else None
    solver.computeDirection(True)
    xs_c, us_c = list(solver.xs), list(solver.us)
    steplength = [1.0]
    calls = {
        "calc": lambda: problem.calc(xs_c, us_c),
        "calcDiff": lambda: problem.calcDiff(xs_c, us_c),
        "backward": lambda: solver.computeDirection(False),
        "forward": lambda: solver.tryStep(steplength[0]),
    }
    if nodes is not None:
        at = solver._addresses()  # the solver's own arrays: their addresses, read once as a solve reads them
        calls["calc"] = lambda: nodes.calc(problem, xs_c, us_c, at)
        calls["calcDiff"] = lambda: nodes.calcDiff(problem, xs_c, us_c, True, None, at)
    return calls, steplength


def _common_steplength(forwards: Sequence[Callable[[], object]], steplengths: Sequence[list]) -> float:
    """The largest step ``2^-k`` (k < 10) whose rollout is finite for every library; set it in ``steplengths``.

    A full step from a rough guess can diverge (the double pendulum's does); the solver's line
    search would then try shorter steps, so the forward pass is timed on the first that works.
    """
    for k in range(10):
        alpha = 0.5**k
        for cell in steplengths:
            cell[0] = alpha
        try:
            if all(math.isfinite(fn()) for fn in forwards):
                return alpha
        except Exception:  # a diverged rollout raises in both libraries
            continue
    raise RuntimeError("no step length in 1, 1/2, ..., 1/512 gives a finite rollout from the guess")






def time_phases_interleaved(setups: dict[str, tuple], solver_name: str, repeats: int) -> dict[str, dict[str, float]]:
    """Median ms per phase for each library, samples interleaved across libraries.

    Parameters
    ----------
    setups : dict
        Library name → ``(lib, problem, xs, us)``.
    solver_name : str
        Key of :data:`SOLVER_CLASSES`.
    repeats : int
        Samples per phase and library (the order of the libraries alternates between samples).

    Returns
    -------
    dict
        Library name → phase (:data:`PHASES` and ``total``) → median ms.
    """
    made = {name: _phase_calls(*setup, solver_name) for name, setup in setups.items()}
    calls = {name: c for name, (c, _) in made.items()}
    _common_steplength([c["forward"] for c in calls.values()], [cell for _, cell in made.values()])
    loops = {name: {p: loops_for(fn) for p, fn in c.items()} for name, c in calls.items()}
    samples: dict[str, dict[str, list[float]]] = {name: {p: [] for p in PHASES} for name in calls}
    order = list(calls)
    for r in range(repeats):
        for name in order if r % 2 == 0 else order[::-1]:
            for phase in PHASES:
                samples[name][phase].append(sample_ms(calls[name][phase], loops[name][phase]))
    out = {}
    for name, s in samples.items():
        med = {p: statistics.median(v) for p, v in s.items()}
        med["total"] = med["calcDiff"] + med["backward"] + med["forward"]
        out[name] = med
    return out


def _solve_once(lib: ModuleType, problem, xs, us, solver_name: str, maxiter: int) -> tuple[int, float, bool, float]:
    """One full solve from the guess: ``(iterations, final cost, converged, seconds)``."""
    solver = make_solver(lib, problem, solver_name)
    init_xs, init_us = [x.copy() for x in xs], [u.copy() for u in us]
    t0 = time.perf_counter()
    converged = solver.solve(init_xs, init_us, maxiter, False)
    elapsed = time.perf_counter() - t0
    return int(solver.iter), float(solver.cost), bool(converged), elapsed


def measure_memory(name: str, library: str, solver_name: str, maxiter: int, timeout: float = 3600.0) -> dict:
    """Build and solve ``name`` with ``library`` in a fresh subprocess; its peak memory and solve.

    Runs ``python -m crocopy.bench.memory`` with one BLAS thread (see that module).

    Returns
    -------
    dict
        ``mib`` (peak resident memory of building and solving, above the post-import baseline),
        ``hwm_reset``, ``iters``, ``cost``, ``converged`` and ``seconds`` (the solve's wall time).

    Raises
    ------
    RuntimeError
        If the subprocess fails (the end of its stderr is quoted).
    """
    env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    cmd = [sys.executable, "-m", "crocopy.bench.memory", name, library, solver_name, str(maxiter)]
    with tempfile.TemporaryDirectory() as cwd:  # a source checkout in the cwd would shadow the installed package
        proc = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=timeout, cwd=cwd)
    if proc.returncode != 0:
        raise RuntimeError(f"memory run of {name} with {library} failed: {proc.stderr.strip()[-2000:]}")
    report = json.loads(proc.stdout.strip().splitlines()[-1])
    report["mib"] = (report.pop("peak_kib") - report.pop("baseline_kib")) / 1024.0
    return report


def solve_interleaved(
    name: str,
    setups: dict[str, tuple],
    solver_name: str,
    maxiter: int,
    repeats: int,
    budget: float,
    memory: bool = True,
) -> dict[str, dict]:
    """Full solves of problem ``name``, libraries alternating, up to ``repeats`` rounds while the next
    round fits in ``budget`` s.

    With ``memory`` the first round runs in subprocesses (:func:`measure_memory`), which also
    measure the peak memory; the other rounds run in this process on the problems of ``setups``
    (library name → ``(lib, problem, xs, us)``).

    Returns
    -------
    dict
        Library name → ``iters``, ``cost``, ``converged`` (of the first run; the solves are
        deterministic), ``ms_per_iter`` (median wall ms per iteration), ``runs`` and ``mib``
        (None without ``memory``).
    """
    out: dict[str, dict] = {}
    per_iter: dict[str, list[float]] = {name: [] for name in setups}
    order = list(setups)
    start = time.perf_counter()
    for r in range(repeats):
        for lib_name in order if r % 2 == 0 else order[::-1]:
            mib = None
            if r == 0 and memory:
                report = measure_memory(name, lib_name, solver_name, maxiter)
                iters, cost, converged, elapsed, mib = (
                    report[k] for k in ("iters", "cost", "converged", "seconds", "mib")
                )
            else:
                iters, cost, converged, elapsed = _solve_once(*setups[lib_name], solver_name, maxiter)
            if r == 0:
                out[lib_name] = {"iters": iters, "cost": cost, "converged": converged, "mib": mib}
            per_iter[lib_name].append(1e3 * elapsed / max(iters, 1))
        if (time.perf_counter() - start) / (r + 1) * (r + 2) > budget:
            break
    for lib_name, samples in per_iter.items():
        out[lib_name].update(ms_per_iter=statistics.median(samples), runs=len(samples))
    return out


def bench_problem(
    name: str,
    libraries: Sequence[str] = LIBRARIES,
    solver_name: str = "boxfddp",
    repeats: int = 5,
    maxiter: int | None = None,
    solve_budget: float = 30.0,
    memory: bool = True,
) -> ProblemResult:
    """Benchmark problem ``name`` with each of ``libraries`` (see the module docstring).

    Parameters
    ----------
    name : str
        Registry name of the problem.
    libraries : sequence of str
        ``"crocopy"`` and/or ``"crocoddyl"``.
    solver_name : str
        Key of :data:`SOLVER_CLASSES` (default Box-FDDP, the Table I solver).
    repeats : int
        Samples per phase (medians) and maximum number of full solves per library.
    maxiter : int, optional
        Iteration limit of the full solve (default: the problem's ``maxiter``).
    solve_budget : float
        Seconds after which no further round of full solves starts.
    memory : bool
        Measure the peak memory in subprocesses.
    """
    from ..problems import registry

    spec = registry.get(name)
    if solver_name not in SOLVER_CLASSES:
        raise ValueError(f"solver_name: expected one of {sorted(SOLVER_CLASSES)}, got {solver_name!r}")
    if repeats < 1:
        raise ValueError(f"repeats: expected a positive integer, got {repeats}")
    maxiter = spec.maxiter if maxiter is None else int(maxiter)
    limit_threads()
    setups = {}
    for lib_name in libraries:
        lib = _library(lib_name)
        setups[lib_name] = (lib, *build_problem(name, lib))
    problem = next(iter(setups.values()))[1]
    dims = (problem.T, problem.runningModels[0].state.nx, problem.runningModels[0].nu)
    phases = time_phases_interleaved(setups, solver_name, repeats)
    solves = solve_interleaved(name, setups, solver_name, maxiter, repeats, solve_budget, memory)
    result = ProblemResult(name, dims, SOLVER_CLASSES[solver_name], maxiter)
    for lib_name in libraries:
        sv = solves[lib_name]
        result.libs[lib_name] = LibResult(
            sv["iters"], sv["cost"], sv["converged"], sv["ms_per_iter"], sv["runs"], phases[lib_name], sv["mib"]
        )
    return result


def run_vs(
    problems: Sequence[str] | None = None,
    libraries: Sequence[str] = LIBRARIES,
    solver_name: str = "boxfddp",
    repeats: int = 5,
    maxiter: int | None = None,
    solve_budget: float = 30.0,
    memory: bool = True,
    progress: Callable[[str], None] | None = None,
) -> str:
    """Benchmark ``problems`` (default :data:`VS_PROBLEMS`) and return the markdown report.

    ``progress`` (e.g. ``print``) receives one line per finished problem.  Other arguments as
    :func:`bench_problem`.

    Raises
    ------
    BenchDependencyError
        If ``"crocoddyl"`` is among ``libraries`` and cannot be used.
    KeyError
        If a problem name is not registered.
    """
    from ..problems import registry
    from . import report as bench_report

    names = list(problems or VS_PROBLEMS)
    for name in names:
        registry.get(name)
    if "crocoddyl" in libraries:
        require_crocoddyl()
    start = time.perf_counter()
    load_start = os.getloadavg()
    results = []
    for name in names:
        t0 = time.perf_counter()
        results.append(bench_problem(name, libraries, solver_name, repeats, maxiter, solve_budget, memory))
        if progress is not None:
            progress(bench_report.progress_line(results[-1], time.perf_counter() - t0))
    meta = {
        "repeats": repeats,
        "solve_budget": solve_budget,
        "wall_s": time.perf_counter() - start,
        "load": (load_start, os.getloadavg()),
    }
    return bench_report.format_report(results, meta)
