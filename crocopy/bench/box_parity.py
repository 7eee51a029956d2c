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

from .side_by_side import BenchDependencyError, build_problem, require_crocoddyl

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
    "Replay",
    "replay_steps",
    "verdict",
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

REPLAY_MAX = 100
"""Iterations of Crocoddyl's run replayed step by step for a row that misses the bar."""

REPLAY_EPS = 1e-14
"""Perturbation of Crocoddyl's own iterate when a replayed step misses (:attr:`Replay.self_err`)."""

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


def _callback(lib: ModuleType, log: list | None = None, record: Callable[[object], None] | None = None) -> object:
    """A callback of ``lib`` calling ``record(solver)`` (default: append the log row to ``log``)."""
    if record is None:

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
    if eps == 0.0:  # x ⊕ 0 may differ from x in the last bit on a manifold
        return [np.array(x, dtype=float) for x in xs], [np.array(u, dtype=float) for u in us]
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
    from ..problems import registry

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


@dataclass
class Replay:
    """crocopy's single iterations from Crocoddyl's own iterates (see :func:`replay_steps`).

    ``cost_err[i]`` is the relative difference between crocopy's cost after one iteration from
    Crocoddyl's iterate entering iteration ``i`` and Crocoddyl's cost after iteration ``i``;
    ``step_same[i]`` whether both took the same step length.
    """

    cost_err: list[float] = field(default_factory=list)
    step_same: list[bool] = field(default_factory=list)
    self_err: dict[int, float] = field(default_factory=dict)
    """At iterations whose replay misses (cost error > :data:`RTOL` or other step): the relative
    difference between Crocoddyl's single iterations from its iterate and from that iterate perturbed
    by :data:`REPLAY_EPS` (both warm-started with its own ``k``), i.e. its own sensitivity at that step."""

    @property
    def worst(self) -> tuple[int | None, float]:
        """``(iteration, error)`` of the largest cost error (``(None, 0.0)`` when empty)."""
        if not self.cost_err:
            return None, 0.0
        i = int(np.argmax([e if np.isfinite(e) else np.inf for e in self.cost_err]))
        return i, self.cost_err[i]

    @property
    def step_mismatches(self) -> list[int]:
        """Iterations whose step lengths differ."""
        return [i for i, same in enumerate(self.step_same) if not same]

    def misses(self, rtol: float = RTOL) -> list[int]:
        """Iterations whose replayed cost differs by more than ``rtol`` or whose step length differs."""
        return [i for i, (e, same) in enumerate(zip(self.cost_err, self.step_same)) if not (e <= rtol and same)]

    def matched_error(self, rtol: float = RTOL) -> float:
        """Largest cost error over the replayed iterations that do not miss (0 when there are none)."""
        missed = set(self.misses(rtol))
        return max((e for i, e in enumerate(self.cost_err) if i not in missed), default=0.0)

    def unexplained(self, rtol: float = RTOL) -> list[int]:
        """Missed iterations at which Crocoddyl's own step is stable (``self_err <= rtol``): real differences."""
        return [i for i in self.misses(rtol) if i in self.self_err and self.self_err[i] <= rtol]

    def unchecked(self, rtol: float = RTOL) -> list[int]:
        """Missed iterations whose own sensitivity was not measured (beyond ``max_self_checks``)."""
        return [i for i in self.misses(rtol) if i not in self.self_err]


def replay_steps(name: str, solver_name: str, upto: int, max_self_checks: int = 5) -> Replay:
    """Replay Crocoddyl's iterations ``0..upto`` one at a time with crocopy (``compat_crocoddyl``).

    Crocoddyl solves registry problem ``name`` for ``upto + 1`` iterations; its callbacks keep each
    accepted iterate ``(xs, us)``, feed-forward ``k`` (the box QP's warm start), regularization and
    feasibility flag.  From each of these states (the builder's guess, ``k = 0`` and ``reg_min``
    for iteration 0) crocopy runs one iteration, ``solve(xs, us, 1, isFeasible, reg)``, and its
    cost and step length are compared with Crocoddyl's next ones; at the first ``max_self_checks``
    iterations that miss, :attr:`Replay.self_err` measures Crocoddyl's own sensitivity.  Small errors
    all the way up to a divergence of the full runs mean crocopy applies the same iteration map, and
    the divergence is the amplification of round-off by the problem.

    Raises
    ------
    BenchDependencyError
        If Crocoddyl cannot be used.
    """
    import crocopy

    crocoddyl = require_crocoddyl()
    if solver_name not in SOLVERS:
        raise ValueError(f"solver_name: expected one of {sorted(SOLVERS)}, got {solver_name!r}")
    problem, xs, us = build_problem(name, crocoddyl)
    ref = getattr(crocoddyl, SOLVERS[solver_name])(problem)
    states = [([x.copy() for x in xs], [u.copy() for u in us], None, None, False)]
    results: list[tuple[float, float]] = []

    def snapshot(solver) -> None:
        results.append((float(solver.cost), float(solver.stepLength)))
        states.append(
            (
                [np.array(x) for x in solver.xs],
                [np.array(u) for u in solver.us],
                [np.array(k) for k in solver.k],
                float(solver.preg),
                bool(solver.isFeasible),
            )
        )

    ref.setCallbacks([_callback(crocoddyl, record=snapshot)])
    ref.solve(xs, us, upto + 1, False)
    mine_problem, _, _ = build_problem(name, crocopy)
    mine = getattr(crocopy, SOLVERS[solver_name])(mine_problem)
    mine.compat_crocoddyl = True
    replay = Replay()
    model_states = [m.state for m in problem.runningModels] + [problem.terminalModel.state]
    for i, ((cost, step), (x_i, u_i, k_i, reg, feasible)) in enumerate(zip(results, states)):
        for k, k_ref in zip(mine.k, k_i or [np.zeros_like(k) for k in mine.k]):
            k[:] = k_ref
        try:
            mine.solve(x_i, u_i, 1, feasible, reg)
            replay.cost_err.append(_rel(cost, float(mine.cost)))
            replay.step_same.append(float(mine.stepLength) == step)
        except (ArithmeticError, ValueError):
            replay.cost_err.append(float("inf"))
            replay.step_same.append(False)
        if (replay.cost_err[-1] > RTOL or not replay.step_same[-1]) and len(replay.self_err) < max_self_checks:
            own = []
            for guess in ((x_i, u_i), perturb_guess(model_states, x_i, u_i, REPLAY_EPS, 1)):
                # Crocoddyl's k cannot be set: rerun its first i iterations so that its QP warm start is k_{i-1}
                again, xs0, us0 = build_problem(name, crocoddyl)
                fresh = getattr(crocoddyl, SOLVERS[solver_name])(again)
                if i:
                    fresh.solve(xs0, us0, i, False)
                fresh.solve(*guess, 1, feasible, reg if reg is not None else fresh.reg_min)
                own.append(float(fresh.cost))
            replay.self_err[i] = _rel(*own)
    return replay


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


def _replay_cell(replay: Replay | None) -> str:
    if replay is None:
        return ""
    missed = replay.misses()
    shown = ",".join(map(str, missed[:5])) + ("..." if len(missed) > 5 else "")
    return f"{len(replay.cost_err)} its <= {replay.matched_error():.0e}, missed {shown or '-'}"


def _row(
    problem: str,
    solver: str,
    label: str,
    ref: Trace,
    t: Trace,
    spread: Spread | None,
    epss: Sequence[float],
    replay: Replay | None = None,
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
    return f"| {problem} | {solver} | {label} | {cells}{_spread_cells(spread, epss)} {chaos} | {_replay_cell(replay)} |"


def verdict(ref: Trace, compat: Trace, croc: Spread | None, replay: Replay | None, eps: float = CHAOS_EPS) -> str:
    """One-line reading of a row: bar met, ill-conditioned (chaotic), or a real difference.

    ``croc`` is Crocoddyl's self-spread (:func:`self_spread`), ``replay`` the one-step replay
    (:func:`replay_steps`); either may be ``None`` (not measured).  A row missing the bar is *chaotic*
    when Crocoddyl disagrees with itself under a perturbation ``eps`` (:func:`is_chaotic`); a replayed
    iteration that misses while Crocoddyl's own step there is stable is a *real difference*.
    """
    div = first_divergence(ref, compat)
    if meets_bar(ref, compat):
        return "bar met"
    parts = [f"bar not met, first diverging iteration {div}"]
    if croc is not None:
        lo, hi = croc.iters[eps]
        parts.append(
            f"under a {eps:g} perturbation Crocoddyl's own final cost moves by {croc.cost[eps]:.1e} "
            f"(iterations {lo}-{hi}, unperturbed {croc.base_iters}) and its run leaves the unperturbed one at "
            f"iteration {croc.divergence[eps]}"
        )
    if replay is not None:
        missed = replay.misses()
        text = (
            f"crocopy's single iterations from Crocoddyl's iterates 0-{len(replay.cost_err) - 1} match its "
            f"costs within {replay.matched_error():.0e}"
        )
        if missed:
            own = ", ".join(f"{i}: {replay.self_err[i]:.0e}" for i in missed if i in replay.self_err)
            text += (
                f" except at {len(missed)} iterations (first {missed[0]}), where Crocoddyl's own step moves "
                f"by [{own}] when its iterate is perturbed by {REPLAY_EPS:g}"
            )
        parts.append(text)
    real = replay.unexplained() if replay is not None else []
    if real:
        head = f"REAL DIFFERENCE at iterations {real} (crocopy misses a step on which Crocoddyl is stable)"
    elif croc is not None and is_chaotic(croc, eps):
        head = "ill-conditioned (chaotic)" + (
            "; no algorithmic difference found" if replay is not None and not replay.unchecked() else ""
        )
    elif croc is None:
        head = "not classified (self-sensitivity not measured)"
    else:
        head = "unexplained: Crocoddyl is stable under the perturbation"
    return head + ": " + "; ".join(parts)


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
    :data:`PERTURBATIONS`' perturbed guesses (their rows get the spread columns), a row missing the
    bar gets the one-step replay of up to :data:`REPLAY_MAX` of Crocoddyl's iterations
    (:func:`replay_steps`), and the report ends with a :func:`verdict` per problem and solver.

    Raises
    ------
    BenchDependencyError
        If Crocoddyl cannot be used.
    KeyError
        If a problem name is not registered.
    """
    import crocopy

    from ..problems import registry
    from .timing import limit_threads

    crocoddyl = require_crocoddyl()
    limit_threads()
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
        f"{pert_cols} first self-div. iter @{' / '.join(f'{e:g}' for e in epss)} | conditioning | "
        "one-step replay (its <= matched err, missed its) |",
        "|---" * (9 + 2 * len(epss) + 2) + "|",
    ]
    verdicts = []
    for name in names:
        for solver in solvers:
            ref = solve_trace(crocoddyl, name, solver, maxiter)
            default = solve_trace(crocopy, name, solver, maxiter)
            compat = solve_trace(crocopy, name, solver, maxiter, True)
            spreads: dict[str, Spread | None] = {"croc": None, "compat": None}
            replay = None
            if sensitivity and not meets_bar(ref, compat):
                replay = replay_steps(name, solver, min(ref.iters, REPLAY_MAX) - 1)
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
                _row(name, solver, "crocopy compat", ref, compat, spreads["compat"], epss, replay),
            ]
            verdicts.append(f"- {name} {solver}: {verdict(ref, compat, spreads['croc'], replay)}")
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
