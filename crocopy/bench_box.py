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

**Self-sensitivity** decides whether a row that misses the bar is evidence of a different algorithm
or of an ill-conditioned (chaotic) run: each library's solver (crocopy in ``compat_crocoddyl`` mode)
is rerun from the builder's guess perturbed by tiny relative amounts (:data:`PERTURBATIONS`:
``1e-14``, a few dozen round-off units; ``1e-12`` with two seeds; ``1e-10``; :func:`perturb_guess`),
and the spread of its own iterations and final cost is reported (:func:`self_spread`), with the
first iteration at which a perturbed run leaves the unperturbed one.  A row where Crocoddyl
disagrees with itself (other iteration count, or final cost off by more than :data:`RTOL`) under a
:data:`CHAOS_EPS` perturbation is *ill-conditioned (chaotic)*: a reimplementation whose arithmetic
differs from Crocoddyl's only in round-off (other summation orders, other BLAS kernels) cannot be
expected to match it.  A row that misses the bar while Crocoddyl is stable under the same
perturbation points to a real algorithmic difference.

It also times the backward pass of Box-FDDP against plain FDDP's on the ANYmal jump at a feasible
iterate with clamped controls (same derivatives, interleaved medians): the box-QP overhead.
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from types import ModuleType

import numpy as np

from .bench_problems import BenchDependencyError, build_problem, require_crocoddyl

__all__ = [
    "PARITY_PROBLEMS",
    "RTOL",
    "PERTURBATIONS",
    "CHAOS_EPS",
    "BenchDependencyError",
    "Trace",
    "Spread",
    "solve_trace",
    "perturb_guess",
    "first_divergence",
    "meets_bar",
    "self_spread",
    "is_chaotic",
    "backward_overhead",
    "run_box_parity",
]

PARITY_PROBLEMS = ("quad-goal", "quad-loop", "quad-narrow", "arm", "jump")
"""The bar's problems: the three quadrotor tasks, the Kinova arm with torque limits, the ANYmal jump."""

RTOL = 1e-6
"""Relative tolerance of the parity bar on the final cost (and of the per-iteration comparison)."""

PERTURBATIONS = ((1e-14, 1), (1e-12, 1), (1e-12, 2), (1e-10, 1))
"""``(relative size, seed)`` of the perturbed initial guesses of the self-sensitivity runs."""

CHAOS_EPS = 1e-12
"""Perturbation size under which a self-disagreement beyond :data:`RTOL` marks a run as chaotic."""

SOLVERS = {"boxddp": "SolverBoxDDP", "boxfddp": "SolverBoxFDDP"}


@dataclass
class Trace:
    """One solve: result and the per-iteration ``(cost, stop, stepLength, iter)`` of the callbacks.

    Only the first three entries of a log row are compared; ``iter`` is the solver's own count.
    """

    iters: int
    cost: float
    converged: bool
    seconds: float
    log: list[tuple] = field(default_factory=list)


def _callback(lib: ModuleType, log: list) -> object:
    def record(solver) -> None:
        log.append((float(solver.cost), float(solver.stop), float(solver.stepLength), int(solver.iter)))

    if lib.__name__ != "crocoddyl":
        return record

    class Recorder(lib.CallbackAbstract):
        def __init__(self) -> None:
            lib.CallbackAbstract.__init__(self)

        def __call__(self, solver) -> None:
            record(solver)

    return Recorder()


def perturb_guess(
    states: Sequence, xs: Sequence[np.ndarray], us: Sequence[np.ndarray], eps: float, seed: int
) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Initial guess perturbed by a relative amount ``eps`` (reproducible with ``seed``).

    ``xs[t]`` moves on its manifold, ``states[t].integrate(xs[t], δ)`` with ``δ`` of shape
    ``(ndx,)``, and ``us[t]`` by ``ε``; every entry of ``δ``/``ε`` is ``eps * z * max(1, s)`` with
    ``z`` standard normal and ``s`` the largest magnitude of ``xs[t]`` (resp. ``|us[t]_j|``
    entry-wise), so entries near zero get an absolute ``eps``.  ``eps = 0`` returns copies.

    Raises
    ------
    ValueError
        If ``states`` and ``xs`` differ in length or ``eps`` is negative.
    """
    if len(states) != len(xs):
        raise ValueError(f"states: expected one state per xs entry ({len(xs)}), got {len(states)}")
    if not eps >= 0.0:
        raise ValueError(f"eps: expected a non-negative size, got {eps}")
    rng = np.random.default_rng(seed)
    xs_p = []
    for state, x in zip(states, xs):
        x = np.asarray(x, dtype=float)
        scale = max(1.0, float(np.abs(x).max())) if x.size else 1.0
        xs_p.append(np.array(state.integrate(x, eps * scale * rng.standard_normal(state.ndx)), dtype=float))
    us_p = []
    for u in us:
        u = np.asarray(u, dtype=float)
        us_p.append(u + eps * np.maximum(np.abs(u), 1.0) * rng.standard_normal(u.shape))
    return xs_p, us_p


def solve_trace(
    lib: ModuleType,
    name: str,
    solver_name: str,
    maxiter: int | None = None,
    compat: bool = False,
    perturbation: tuple[float, int] | None = None,
) -> Trace:
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
    perturbation : (float, int), optional
        ``(eps, seed)``: start from :func:`perturb_guess` of the builder's guess.
    """
    from .problems import registry

    if solver_name not in SOLVERS:
        raise ValueError(f"solver_name: expected one of {sorted(SOLVERS)}, got {solver_name!r}")
    maxiter = registry.get(name).maxiter if maxiter is None else int(maxiter)
    problem, xs, us = build_problem(name, lib)
    if perturbation is not None:
        states = [m.state for m in problem.runningModels] + [problem.terminalModel.state]
        xs, us = perturb_guess(states, xs, us, *perturbation)
    solver = getattr(lib, SOLVERS[solver_name])(problem)
    if compat:
        solver.compat_crocoddyl = True
    log: list[tuple] = []
    solver.setCallbacks([_callback(lib, log)])
    t0 = time.perf_counter()
    converged = bool(solver.solve(xs, us, maxiter, False))
    return Trace(int(solver.iter), float(solver.cost), converged, time.perf_counter() - t0, log)


def _rel(a: float, b: float) -> float:
    if not (np.isfinite(a) and np.isfinite(b)):
        return 0.0 if a == b else float("inf")
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


@dataclass
class Spread:
    """A solver's disagreement with itself under perturbed initial guesses (see :func:`self_spread`).

    Dictionaries are keyed by the perturbation size ``eps``: ``iters[eps]`` is the ``(min, max)``
    iteration count of the perturbed runs, ``cost[eps]`` the largest relative difference of their
    final costs to the unperturbed run's, ``divergence[eps]`` the earliest iteration at which one of
    them leaves the unperturbed run (:func:`first_divergence`; ``None``: none does).
    """

    base_iters: int
    base_cost: float
    iters: dict[float, tuple[int, int]] = field(default_factory=dict)
    cost: dict[float, float] = field(default_factory=dict)
    divergence: dict[float, int | None] = field(default_factory=dict)


def self_spread(base: Trace, runs: Sequence[tuple[float, Trace]], rtol: float = RTOL) -> Spread:
    """Spread of the perturbed runs ``[(eps, trace), ...]`` around the unperturbed ``base``."""
    spread = Spread(base.iters, base.cost)
    for eps in sorted({e for e, _ in runs}):
        group = [t for e, t in runs if e == eps]
        spread.iters[eps] = (min(t.iters for t in group), max(t.iters for t in group))
        spread.cost[eps] = max(_rel(base.cost, t.cost) for t in group)
        divs = [d for d in (first_divergence(base, t, rtol) for t in group) if d is not None]
        spread.divergence[eps] = min(divs) if divs else None
    return spread


def is_chaotic(spread: Spread, eps: float = CHAOS_EPS, rtol: float = RTOL) -> bool:
    """Whether a perturbation of size ``eps`` changes the iteration count or moves the final cost by
    more than ``rtol`` (relative).

    Raises
    ------
    KeyError
        If ``spread`` has no runs perturbed by ``eps``.
    """
    if eps not in spread.cost:
        raise KeyError(f"eps: no perturbed runs of size {eps:g} (have {sorted(spread.cost)})")
    lo, hi = spread.iters[eps]
    return lo != spread.base_iters or hi != spread.base_iters or spread.cost[eps] > rtol


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


def _spread_cells(spread: Spread | None, epss: Sequence[float]) -> str:
    if spread is None:
        return "  |" * (2 * len(epss) + 1)
    cells = []
    for eps in epss:
        lo, hi = spread.iters[eps]
        cells += [f"{lo}" if lo == hi else f"{lo}-{hi}", f"{spread.cost[eps]:.1e}"]
    cells.append(" / ".join("-" if spread.divergence[e] is None else str(spread.divergence[e]) for e in epss))
    return "".join(f" {c} |" for c in cells)


def _row(
    problem: str, solver: str, label: str, ref: Trace, t: Trace, spread: Spread | None, epss: Sequence[float]
) -> str:
    if t is ref:
        cells = f"{t.iters} | {t.cost:.10g} | | | |"
    else:
        div = first_divergence(ref, t)
        cells = (
            f"{t.iters} | {t.cost:.10g} | {_rel(ref.cost, t.cost):.1e} | {'-' if div is None else div} | "
            f"{'met' if meets_bar(ref, t) else 'not met'} |"
        )
    chaos = "" if spread is None else ("chaotic" if is_chaotic(spread, CHAOS_EPS) else "stable")
    return f"| {problem} | {solver} | {label} | {cells}{_spread_cells(spread, epss)} {chaos} |"


def _verdict(name: str, solver: str, ref: Trace, compat: Trace, croc: Spread | None, eps: float) -> str:
    head = f"- {name} {solver}: "
    div = first_divergence(ref, compat)
    if meets_bar(ref, compat):
        return head + "bar met"
    if croc is None:
        return head + f"bar not met (first diverging iteration {div}); self-sensitivity not measured"
    lo, hi = croc.iters[eps]
    own = (
        f"Crocoddyl's own final cost moves by {croc.cost[eps]:.1e} (iterations {lo}-{hi}, unperturbed "
        f"{croc.base_iters}) under a {eps:g} perturbation, and leaves its unperturbed run at iteration "
        f"{croc.divergence[eps]}; crocopy compat leaves it at iteration {div}"
    )
    if is_chaotic(croc, eps):
        return head + "bar not met; ill-conditioned (chaotic): " + own
    return head + "bar not met while Crocoddyl is stable: a real difference? " + own


def run_box_parity(
    problems: Sequence[str] | None = None,
    solvers: Sequence[str] = ("boxddp", "boxfddp"),
    maxiter: int | None = None,
    overhead: bool = True,
    sensitivity: bool = True,
    progress: Callable[[str], None] | None = None,
) -> str:
    """Markdown report of the parity runs, their self-sensitivity and the backward-pass overhead.

    With ``sensitivity``, Crocoddyl and crocopy (compat mode) are rerun from each of
    :data:`PERTURBATIONS`' perturbed guesses; their rows get the spread columns and the report ends
    with a verdict per problem and solver.

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
    t_start = time.perf_counter()
    names = list(problems or PARITY_PROBLEMS)
    for n in names:
        registry.get(n)
    epss = sorted({e for e, _ in PERTURBATIONS})
    pert_cols = "".join(f" iters @{e:g} | cost spread @{e:g} |" for e in epss)
    lines = [
        f"Box solvers vs Crocoddyl 3.2 (bar: same iterations, final cost within {RTOL:g} relative); "
        f"self-spread: the library's own runs from the guess perturbed by {', '.join(f'{e:g}' for e in epss)} "
        f"({len(PERTURBATIONS)} runs), cost spread relative to its unperturbed run; 'chaotic': it disagrees "
        f"with itself beyond {RTOL:g} under {CHAOS_EPS:g}",
        "",
        "| problem | solver | library | iters | final cost | rel. diff | first diverging iter | bar |"
        f"{pert_cols} first self-div. iter @{' / '.join(f'{e:g}' for e in epss)} | conditioning |",
        "|---" * (9 + 2 * len(epss) + 1) + "|",
    ]
    verdicts = []
    for name in names:
        for solver in solvers:
            ref = solve_trace(crocoddyl, name, solver, maxiter)
            default = solve_trace(crocopy, name, solver, maxiter)
            compat = solve_trace(crocopy, name, solver, maxiter, True)
            spreads: dict[str, Spread | None] = {"croc": None, "compat": None}
            if sensitivity:
                for key, lib, base in (("croc", crocoddyl, ref), ("compat", crocopy, compat)):
                    runs = [
                        (e, solve_trace(lib, name, solver, maxiter, lib is crocopy, (e, seed)))
                        for e, seed in PERTURBATIONS
                    ]
                    spreads[key] = self_spread(base, runs)
            lines += [
                _row(name, solver, "Crocoddyl", ref, ref, spreads["croc"], epss),
                _row(name, solver, "crocopy", ref, default, None, epss),
                _row(name, solver, "crocopy compat", ref, compat, spreads["compat"], epss),
            ]
            verdicts.append(_verdict(name, solver, ref, compat, spreads["croc"], CHAOS_EPS))
            if progress:
                progress("\n".join(lines[-3:]))
    lines += ["", "Verdicts (crocopy compat against Crocoddyl):", *verdicts]
    if overhead:
        o = backward_overhead()
        lines += [
            "",
            f"Backward pass on the ANYmal jump, feasible iterate with {o['clamped_nodes']} clamped nodes: "
            f"Box-FDDP {o['box']:.2f} ms, FDDP {o['plain']:.2f} ms, ratio {o['ratio']:.2f}x (bar 1.5x)",
        ]
    lines += ["", f"Run time {time.perf_counter() - t_start:.0f} s"]
    return "\n".join(lines)
