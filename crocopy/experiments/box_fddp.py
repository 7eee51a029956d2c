"""Experiments of Mastalli et al., *Control-limited feasibility-driven DDP* (Box-FDDP): quadrotor.

:func:`run_quadrotor_ics` — Fig. 7: the IRIS goal task (:mod:`crocopy.problems.quadrotor`) from 10
initial positions ``(-0.3 ± 0.6, 0, 0)`` m to the target ``(3, 0, 1)``, solved by Box-FDDP,
Box-DDP and squashing DDP (smooth saturation with ``β = 2`` in front of the thrusts, plain
:class:`SolverDDP` on :class:`ActionModelSquashed`).  Metric: final cost and iterations per initial
condition (paper: squashing is the most sensitive to the initial condition; Box-FDDP has the
lowest cost and fewest iterations).

:func:`run_quadrotor_table` — the quad rows of Table I: goal, loop and narrow with Box-DDP and
Box-FDDP (iterations, cost, success).

Constants the paper leaves open, and the values chosen here:

* initial positions: 10 evenly spaced x in ``[-0.9, 0.3]`` (the paper's "±0.6" read as a range),
  vehicle level and at rest; cold start (``x0`` at every node, zero thrust) for every solver;
* task geometry, horizon (50 nodes of 30 ms for goal) and cost weights: see
  :mod:`crocopy.problems.quadrotor`;
* squashing: bounds ``[0.1, 10.3]`` N, ``β = 2`` (paper), raw-control weight ``1e-6``
  (``ActionModelSquashed.rawWeight``; unspecified).  Its final cost is reported on the original
  problem (rollout of ``s(u)``), without the raw-control term, so the three numbers compare;
* solvers: Crocoddyl's defaults (initial regularisation ``1e-9`` as in the paper), at most 300
  iterations; "solved" means the solver's own stopping test fired.

The module needs Pinocchio and example-robot-data (it builds the problems from
:mod:`crocopy.problems`, imported when a function runs).
"""

from __future__ import annotations

import os

import numpy as np

from ..shooting import ShootingProblem
from ..solvers import SolverDDP
from ..solvers.box_ddp import SolverBoxDDP
from ..solvers.box_fddp import SolverBoxFDDP
from ..squashing.action import ActionModelSquashed

__all__ = ["initial_positions", "run_quadrotor_ics", "run_quadrotor_table", "solve_quadrotor"]

METHODS = ("Box-FDDP", "Box-DDP", "squashing")


def initial_positions(n: int = 10) -> np.ndarray:
    """The ``n`` start positions ``(x, 0, 0)`` with x evenly spaced in ``[-0.9, 0.3]``, shape ``(n, 3)``."""
    xs = np.linspace(-0.9, 0.3, n)
    return np.column_stack([xs, np.zeros(n), np.zeros(n)])


def solve_quadrotor(method: str, task: str = "goal", x0_position=(-0.3, 0.0, 0.0), maxiter: int = 300,
                    T: int | None = None, beta: float = 2.0) -> dict:
    """Solve one quadrotor task from a cold start with ``method`` in :data:`METHODS`.

    Returns ``{"cost", "iter", "solved", "costs" (per iteration), "gaps", "us", "xs", "max_violation"}``
    where ``cost`` is the original problem's cost of the returned (squashed, for squashing) controls.
    """
    import crocopy
    from crocopy.problems.quadrotor import build_quadrotor

    problem, xs0, us0 = build_quadrotor(crocopy, task, x0_position, T=T)
    if method == "Box-FDDP":
        solver = SolverBoxFDDP(problem)
    elif method == "Box-DDP":
        solver = SolverBoxDDP(problem)
    elif method == "squashing":
        running = [ActionModelSquashed(m, "smooth-sat", smooth=beta, rawWeight=1e-6) for m in problem.runningModels]
        solver = SolverDDP(ShootingProblem(problem.x0, running, problem.terminalModel))
    else:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    costs, gaps = [], []
    solver.setCallbacks([lambda s: (costs.append(s.cost), gaps.append(s.ffeas))])
    solved = solver.solve(xs0, us0, maxiter, False)
    us = [np.array(u) for u in solver.us]
    if method == "squashing":
        us = [m.squash(u) for m, u in zip(solver.problem.runningModels, us, strict=True)]
    xs = problem.rollout(us)
    lb, ub = problem.runningModels[0].u_lb, problem.runningModels[0].u_ub
    U = np.array(us)
    return {
        "cost": problem.calc(xs, us), "iter": solver.iter, "solved": solved, "costs": np.array(costs),
        "gaps": np.array(gaps), "us": U, "xs": np.array(xs),
        "max_violation": float(max(np.max(U - ub), np.max(lb - U), 0.0)),
    }


def run_quadrotor_ics(out_dir: str = ".", n: int = 10, maxiter: int = 300, plot: bool = True,
                      T: int | None = None) -> dict:
    """Fig. 7: final cost and iterations of the three methods from ``n`` initial positions."""
    starts = initial_positions(n)
    results = {m: [] for m in METHODS}
    print(f"Box-FDDP paper Fig. 7 — IRIS goal (target (3, 0, 1)) from {n} starts (-0.3 ± 0.6, 0, 0), cold start")
    print(f"  {'start x':>8s} " + " ".join(f"{m + ' cost/it':>24s}" for m in METHODS))
    for p in starts:
        row = []
        for m in METHODS:
            r = solve_quadrotor(m, "goal", p, maxiter, T=T)
            results[m].append(r)
            row.append(f"{r['cost']:13.5g} / {r['iter']:3d}{'' if r['solved'] else '*'}")
        print(f"  {p[0]:8.3f} " + " ".join(f"{s:>24s}" for s in row))
    summary = {}
    for m in METHODS:
        c = np.array([r["cost"] for r in results[m]])
        it = np.array([r["iter"] for r in results[m]])
        summary[m] = {"cost_mean": c.mean(), "cost_std": c.std(), "iter_mean": it.mean(),
                      "solved": int(sum(r["solved"] for r in results[m])),
                      "max_violation": max(r["max_violation"] for r in results[m])}
        print(f"  {m:9s}: cost {c.mean():.4g} ± {c.std():.2g}, iterations {it.mean():.1f} "
              f"(min {it.min()}, max {it.max()}), solved {summary[m]['solved']}/{n}, "
              f"max bound violation {summary[m]['max_violation']:.1e} N   (* = not converged)")
    print("  paper: Box-FDDP lowest cost and fewest iterations; squashing most sensitive to the start")
    out = {"starts": starts, "results": results, "summary": summary}
    if plot:
        out["plot"] = _plot_ics(out, out_dir)
    return out


def _plot_ics(out: dict, out_dir: str) -> str:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(15, 4))
    x = out["starts"][:, 0]
    for m, color in zip(METHODS, ("C0", "C3", "C1"), strict=True):
        res = out["results"][m]
        axes[0].semilogy(x, [r["cost"] for r in res], "o-", color=color, label=m)
        axes[1].plot(x, [r["iter"] for r in res], "o-", color=color, label=m)
        for r in res:
            axes[2].semilogy(r["costs"], color=color, alpha=0.5, lw=0.8)
    axes[0].set_title("final cost (Fig. 7)")
    axes[1].set_title("iterations")
    axes[2].set_title("cost per iteration, all starts")
    axes[0].set_xlabel("initial x (m)")
    axes[1].set_xlabel("initial x (m)")
    axes[2].set_xlabel("iteration")
    axes[0].legend()
    fig.tight_layout()
    path = os.path.join(out_dir, "boxfddp_quadrotor.png")
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def run_quadrotor_table(maxiter: int = 500) -> dict:
    """Table I quad rows: iterations, cost and success of Box-DDP and Box-FDDP on goal/loop/narrow."""
    table = {}
    print("Box-FDDP paper Table I (quad rows) — Box-DDP vs Box-FDDP, cold start")
    print(f"  {'task':8s} {'Box-DDP it':>10s} {'cost':>10s} {'sol':>4s} {'Box-FDDP it':>12s} {'cost':>10s} {'sol':>4s}")
    for task in ("goal", "loop", "narrow"):
        ddp = solve_quadrotor("Box-DDP", task, maxiter=maxiter)
        fddp = solve_quadrotor("Box-FDDP", task, maxiter=maxiter)
        table[task] = {"Box-DDP": ddp, "Box-FDDP": fddp}
        print(f"  {task:8s} {ddp['iter']:10d} {ddp['cost']:10.4g} {'yes' if ddp['solved'] else 'no':>4s} "
              f"{fddp['iter']:12d} {fddp['cost']:10.4g} {'yes' if fddp['solved'] else 'no':>4s}")
    print("  paper: goal 23/0.0764 vs 18/0.0072, loop 133/6.7211 vs 56/0.6444, narrow 70/1.9492 vs 35/0.4577")
    return table
