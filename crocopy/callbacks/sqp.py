"""mim-solvers' callbacks for :class:`~crocopy.SolverSQP` and :class:`~crocopy.SolverCSQP`.

``CallbackSQPVerbose(precision=3)`` (``mim_solvers.CallbackVerbose``) prints one row per iteration,
its header every 10 iterations:

- SQP: ``iter  merit  cost  ||gaps||  step  KKT criteria``;
- CSQP: ``iter  merit  cost  ||gaps||  ||Constraint||  ||(dx,du)||  step  KKT criteria  QP iters``, with
  ``||(dx,du)|| = ½ (Σ_t ‖δx_t‖₁ / (T+1) + Σ_t ‖δu_t‖₁ / T)``.

Rows print before the line search, so ``step`` is the previous iteration's step length (CSQP's
merit, computed after the callbacks, is the previous one too); on the converged row the step
(and for CSQP ``||(dx,du)||`` and the QP iterations) print as dashes.

``CallbackSQPLogger()`` (``mim_solvers.CallbackLogger``) fills ``convergence_data``, a dict of lists with
one entry per iteration: ``us, xs, fs, iter, cost, merit, preg, dreg, step`` then, for CSQP,
``gap_norm, constraint_norm, qp_iter``, and last ``KKT``.  :func:`plotSQPConvergence` plots it.
"""

from __future__ import annotations

import numpy as np

from .base import CallbackAbstract


def _constrained(solver) -> bool:
    return hasattr(solver, "qp_iters")


class CallbackSQPVerbose(CallbackAbstract):
    """mim-solvers' ``CallbackVerbose(precision=3)``: one row per iteration (see the module docstring)."""

    def __init__(self, precision: int = 3) -> None:
        if int(precision) < 0:
            raise ValueError(f"precision must be non-negative, got {precision}")
        self.precision = int(precision)

    def header(self, constrained: bool) -> str:
        """The header of the table (mim-solvers' spacing)."""
        p = self.precision
        if not constrained:
            gaps = (p + 1, 6, p + 2, p + 2, p + 2, p)
            names = ("iter", "merit", "cost", "||gaps||", "step", "KKT criteria")
        else:
            gaps = (p + 1, 6, p + 2, p, p, max(7 - p, 1), p + 2, p, max(p - 2, 0))
            names = ("iter", "merit", "cost", "||gaps||", "||Constraint||", "||(dx,du)||", "step", "KKT criteria",
                     "QP iters")
        return "".join(name + " " * gap for name, gap in zip(names, gaps))

    def line(self, solver) -> str:
        """The row of ``solver``'s current iteration."""
        p = self.precision
        e = lambda v: f"{v:.{p}e}"  # noqa: E731
        done = solver.KKT <= solver.termination_tolerance
        out = f"{solver.iter:4d}  {e(solver.merit)}  {e(solver.cost)}  {e(solver.gap_norm)}"
        if not _constrained(solver):
            if done:
                return out + f"         ----     {e(solver.KKT)}    "
            return out + f"    {e(solver.stepLength)}  {e(solver.KKT)}     "
        out += f"    {e(solver.constraint_norm)}"
        if done:
            return out + f"         ----        ----     {e(solver.KKT)}       -----  "
        return out + (f"      {e(step_norm(solver))}      {solver.stepLength:.{p}f}    {e(solver.KKT)}      "
                      f"{int(solver.qp_iters)}  ")

    def __call__(self, solver) -> None:
        if solver.iter % 10 == 0:
            print(self.header(_constrained(solver)))
        print(self.line(solver), flush=True)


def step_norm(solver) -> float:
    """``½ (Σ_t ‖δx_t‖₁ / (T+1) + Σ_t ‖δu_t‖₁ / T)`` of the solver's QP step."""
    T = len(solver.du)
    xs = sum(float(np.abs(v).sum()) for v in solver.dx) / (T + 1)
    us = sum(float(np.abs(v).sum()) for v in solver.du) / max(T, 1)
    return 0.5 * (xs + us)


class CallbackSQPLogger(CallbackAbstract):
    """mim-solvers' ``CallbackLogger()``: per-iteration lists in ``convergence_data``."""

    def __init__(self) -> None:
        self.convergence_data: dict[str, list] = {}

    def __call__(self, solver) -> None:
        row = {
            "us": [np.array(u) for u in solver.us], "xs": [np.array(x) for x in solver.xs],
            "fs": [np.array(f) for f in solver.fs], "iter": int(solver.iter), "cost": float(solver.cost),
            "merit": float(solver.merit), "preg": float(solver.preg), "dreg": float(solver.dreg),
            "step": float(solver.stepLength),
        }
        if _constrained(solver):
            row.update(gap_norm=float(solver.gap_norm), constraint_norm=float(solver.constraint_norm),
                       qp_iter=float(solver.qp_iters))
        row["KKT"] = float(solver.KKT)
        for key, value in row.items():
            self.convergence_data.setdefault(key, []).append(value)


def plotSQPConvergence(convergence_data: dict, show: bool = True):
    """mim-solvers' ``plotConvergence(data, show=True)``: one panel per scalar series (``KKT`` on a log
    scale; ``preg``/``dreg`` skipped); returns the matplotlib figure."""
    import matplotlib.pyplot as plt

    keys = [k for k, v in convergence_data.items()
            if k not in ("preg", "dreg", "xs", "us", "fs") and v and np.isscalar(v[0])]
    fig, axes = plt.subplots(len(keys), 1, figsize=(8, 2.2 * len(keys)), sharex=True, squeeze=False)
    for ax, key in zip(axes[:, 0], keys):
        ax.plot(convergence_data[key], marker=".")
        ax.set_ylabel(key)
        if key == "KKT":
            ax.set_yscale("log")
        if key == "qp_iter":
            total = int(sum(convergence_data[key]))
            ax.set_title(f"{total} QP iterations in {len(convergence_data[key])} SQP iterations", fontsize=8)
    axes[-1, 0].set_xlabel("iteration")
    fig.tight_layout()
    if show:
        plt.show()
    return fig
