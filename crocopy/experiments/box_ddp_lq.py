"""Box-DDP paper (Tassa, Mansard, Todorov, ICRA 2014), Fig. 2: random box-constrained LQ problems.

Problem (paper §IV-A): ``x' = fx x + fu u``, cost ``½ Σ (xᵀ (h I) x + uᵀ (c_u h I) u) + ½ x_Nᵀ (h I) x_N``,
bounds ``±1``, ``x0 ~ N(0, I)``, ``U0 = 0``, ``h = 0.01``, ``N = 200``; showcase ``n = 20``, ``m = 7``;
20 random problems with ``n ~ U{10..100}``, ``m ~ U{1..⌊n/2⌋}``.

``J*`` is computed independently of every DDP variant (:mod:`.lq_reference`: a primal-dual
interior-point method on the sparse QP in states and controls, certified by the convexity bound
``J(U) - J* <= gap(U)`` to ``1e-11 |J*|``).  Metric: ``(J_k - J*) / |J*|`` per iteration, the first
iteration below ``1e-8`` and the order of convergence ``q_k = log(e_{k+1}/e_k) / log(e_k/e_{k-1})`` of
Box-DDP's last iterations above the ``1e-13`` round-off floor.  Squashing is measured with the box
problem's cost of the squashed controls (its ``10⁻⁶`` raw-control term removed).

Generator.  The paper prints ``fx = I + h N(n, n)`` (i.i.d. standard normal entries).  Taken
literally, the drift ``N(n, n)`` has eigenvalues spread over a disc of radius ``√n`` (circular law):
over ``N h = 2`` s the passive state grows like ``e^{2√n}`` — measured: passive costs ``1e3``..``1e15``,
and ``J*`` up to ``1e15`` on ``n = 99`` — while the paper's Fig. 2 plots ``ΔJ`` from ``1e2`` down to
``1e-6`` (absolute), so its problems had ``J*`` of order ``1e2`` at most.  Default here
(``normalized=True``): ``fx = I + (h/√n) N(n, n)``, drift spectral radius about 1 for every ``n``
(passive growth at most ``e²``); ``J*`` is then 10..200.  ``normalized=False`` gives the literal
generator (the showcase ``n = 20`` is still solvable: ``J* ≈ 58..100``).  ``c_u`` is not given:
``c_u = 0.01`` (the low end of a 0.01..1 sweep) keeps the bounds active on about 5..10 % of the
optimal controls (at ``c_u = 10`` none is active and every method needs one iteration).

Methods: Box-DDP (Tassa's exact value update, the paper's algorithm), Box-DDP with Crocoddyl's
update, squashing (``tanh``, plain DDP on :class:`ActionModelSquashed`), clamping variant 1 (rollout)
and variant 2 (backward pass); Crocoddyl's solver defaults, ``U0 = 0``.
"""

from __future__ import annotations

import os

import numpy as np

from ..actions import ActionModelLQR
from ..shooting import ShootingProblem
from ..solvers import SolverDDP
from ..solvers.box_ddp import SolverBoxDDP
from ..solvers.clamping import SolverClampedDDP
from ..squashing.action import ActionModelSquashed
from .box_ddp import box_ddp_tassa, solve_recording
from .lq_reference import BoxLQ, box_lq_optimum

__all__ = ["convergence_order", "lq_problem", "run_lq"]

TOL = 1e-8
FLOOR = 1e-13


def lq_problem(n: int = 20, m: int = 7, N: int = 200, h: float = 0.01, c_u: float = 0.01, seed: int = 0,
               normalized: bool = True):
    """Random box-constrained LQ problem of Fig. 2; returns ``(problem, model)`` (bounds ``±1``).

    ``fx = I + h G`` with ``G`` i.i.d. ``N(0, 1/n)`` when ``normalized`` (spectral radius about 1 for
    every ``n``), or ``N(0, 1)`` as printed in the paper (``normalized=False``).
    """
    rng = np.random.default_rng(seed)
    fx = np.eye(n) + (h / np.sqrt(n) if normalized else h) * rng.standard_normal((n, n))
    fu = h * rng.standard_normal((n, m))
    model = ActionModelLQR(fx, fu, h * np.eye(n), c_u * h * np.eye(m), np.zeros((n, m)),
                           np.zeros(n), np.zeros(n), np.zeros(m))
    model.u_lb, model.u_ub = -np.ones(m), np.ones(m)
    return ShootingProblem(rng.standard_normal(n), [model] * N, model), model


def _methods(problem: ShootingProblem, model) -> dict:
    squashed = ActionModelSquashed(model, "tanh", rawWeight=1e-6)
    return {
        "Box-DDP": (box_ddp_tassa(problem), 0.0),
        "Box-DDP (Crocoddyl update)": (SolverBoxDDP(problem), 0.0),
        "squashing": (SolverDDP(ShootingProblem(problem.x0, [squashed] * problem.T, model)), 1e-6),
        "clamping (rollout)": (SolverClampedDDP(problem, "forward"), 0.0),
        "clamping (backward)": (SolverClampedDDP(problem, "backward"), 0.0),
    }


def convergence_order(errors: np.ndarray, floor: float = FLOOR) -> list[float]:
    """Orders ``log(e_{k+1}/e_k) / log(e_k/e_{k-1})`` over the errors above ``floor`` (last first)."""
    e = np.asarray(errors, dtype=float)
    e = e[: int(np.argmax(e <= floor))] if np.any(e <= floor) else e
    q = [np.log(e[k + 1] / e[k]) / np.log(e[k] / e[k - 1]) for k in range(len(e) - 2, 0, -1)
         if e[k] < e[k - 1] and e[k + 1] < e[k]]
    return [float(v) for v in q]


def _solve_all(problem, model, maxiter: int) -> dict:
    """J* (certified), per-method relative errors, iterations to ``TOL`` and Box-DDP's orders."""
    ref = box_lq_optimum(BoxLQ.from_lqr_model(model, problem.x0, problem.T))
    out = {"J*": ref.J, "gap": ref.gap, "ip_iterations": ref.iterations, "maxiter": maxiter,
           "active": float(np.mean(np.abs(ref.us) >= 1.0 - 1e-6)), "errors": {}, "iterations": {}}
    for name, (solver, raw) in _methods(problem, model).items():
        costs = solve_recording(solver, [np.zeros(model.nu)] * problem.T, maxiter, raw)["costs"]
        err = (costs - ref.J) / abs(ref.J)
        below = np.flatnonzero(err < TOL)
        out["errors"][name] = err
        out["iterations"][name] = int(below[0]) if below.size else None
        if name == "Box-DDP":
            out["order"] = convergence_order(err)
            out["factorizations"], out["qp_solves"] = solver.nfactorizations, solver.nqp
    return out


def run_lq(out_dir: str = ".", maxiter: int = 30, n_random: int = 20, c_u: float = 0.01, plot: bool = True,
           sizes: tuple[int, int, int] = (20, 7, 200), n_range: tuple[int, int] = (10, 100),
           normalized: bool = True, verbose: bool = True) -> dict:
    """Fig. 2 against the certified ``J*``: the showcase ``sizes = (n, m, N)`` and ``n_random`` problems.

    Returns ``{"showcase": result, "random": [result, ...], "summary": {...}}`` where each result
    holds ``J*``, its certificate ``gap``, the active fraction of the optimal controls, per-method
    ``errors`` ``(J_k - J*)/|J*|`` and ``iterations`` to ``1e-8`` (None if never), Box-DDP's
    convergence ``order`` and box-QP factorisation counts; writes ``boxddp_lq.png`` when ``plot``.
    """
    n, m, N = sizes
    say = print if verbose else (lambda *a, **k: None)
    say(f"Box-DDP paper Fig. 2 — box-constrained LQ, c_u = {c_u:g}, N = {N}, h = 0.01, "
        f"{'normalised drift N(0, 1/n)' if normalized else 'literal drift N(0, 1)'}; J* by a certified "
        f"interior-point QP; iterations to (J - J*)/|J*| < {TOL:g} (max {maxiter})")
    showcase = _solve_all(*lq_problem(n, m, N, c_u=c_u, seed=0, normalized=normalized), maxiter)
    showcase.update(n=n, m=m)
    _print_problem(say, f"showcase n={n} m={m}", showcase, detail=True)
    rng = np.random.default_rng(12345)
    randoms = []
    for seed in range(1, n_random + 1):
        n_r = int(rng.integers(n_range[0], n_range[1] + 1))
        m_r = int(rng.integers(1, n_r // 2 + 1))
        res = _solve_all(*lq_problem(n_r, m_r, N, c_u=c_u, seed=seed, normalized=normalized), maxiter)
        res.update(n=n_r, m=m_r)
        randoms.append(res)
        _print_problem(say, f"random {seed:2d} n={n_r:3d} m={m_r:2d}", res)
    summary = _summary([showcase, *randoms], maxiter)
    for name, s in summary["methods"].items():
        say(f"  {name:28s} reached 1e-8 |J*| on {s['reached']}/{len(randoms) + 1} problems, within 20 iterations on "
            f"{s['within_20']}; median iterations {s['median']}")
    say(f"  Box-DDP order of the last steps above round-off: median {summary['order_median']:.2f}, range "
        f"{summary['order_range'][0]:.2f}..{summary['order_range'][1]:.2f} (the step after them reaches round-off)")
    say(f"  Box-DDP box-QP factorisations per QP solve: {summary['factorizations_per_qp']:.2f} (paper: ~1.5 per "
        "iteration)")
    show = showcase["iterations"]["Box-DDP"]
    within = sum(r["iterations"]["Box-DDP"] is not None and r["iterations"]["Box-DDP"] <= 20 for r in randoms)
    summary["bar"] = show is not None and show <= 20 and within >= 0.9 * len(randoms)
    say(f"  bar: Box-DDP reaches 1e-8 |J*| within 20 iterations on the showcase ({_fmt_it(show, maxiter)}) and on "
        f">= 90 % of the {len(randoms)} random problems ({within}): {'met' if summary['bar'] else 'NOT MET'}")
    out = {"showcase": showcase, "random": randoms, "summary": summary}
    if plot:
        out["plot"] = _plot(out, out_dir)
    return out


def _fmt_it(it: int | None, maxiter: int) -> str:
    return f">{maxiter}" if it is None else str(it)


def _print_problem(say, title: str, res: dict, detail: bool = False) -> None:
    maxiter = res["maxiter"]
    its = ", ".join(f"{k} {_fmt_it(v, maxiter)}" for k, v in res["iterations"].items())
    order = ", ".join(f"{q:.2f}" for q in res["order"][:3]) or "-"
    say(f"  {title}: J* = {res['J*']:.10g} (gap {res['gap']:.1e}), active {100 * res['active']:.0f} %; "
        f"iterations: {its}; Box-DDP order (last first) {order}")
    if detail:
        for name, err in res["errors"].items():
            say(f"    {name:28s} (J-J*)/|J*| " + " ".join(f"{max(v, 0.0):.1e}" for v in err[:min(maxiter, 16) + 1]))


def _summary(results: list[dict], maxiter: int) -> dict:
    methods = {}
    for name in results[0]["iterations"]:
        its = [r["iterations"][name] for r in results]
        reached = [i for i in its if i is not None]
        methods[name] = {"reached": len(reached), "within_20": sum(i <= 20 for i in reached),
                         "median": int(np.median(reached)) if reached else None}
    fact = sum(r["factorizations"] for r in results)
    nqp = sum(r["qp_solves"] for r in results)
    last = [r["order"][0] for r in results if r["order"]] or [float("nan")]
    return {"methods": methods, "factorizations_per_qp": fact / max(nqp, 1), "maxiter": maxiter,
            "order_median": float(np.median(last)), "order_range": (float(np.min(last)), float(np.max(last)))}


def _plot(results: dict, out_dir: str) -> str:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    names = list(results["showcase"]["errors"])
    colors = dict(zip(names, ("C0", "C4", "C1", "C2", "C3"), strict=False))
    for name, err in results["showcase"]["errors"].items():
        axes[0].semilogy(np.maximum(err, 1e-16), "-o", ms=3, color=colors[name], label=name)
    for r in results["random"]:
        for name, err in r["errors"].items():
            axes[1].semilogy(np.maximum(err, 1e-16), color=colors[name], alpha=0.5, lw=0.8)
    s = results["showcase"]
    axes[0].set_title(f"n={s['n']}, m={s['m']} (Fig. 2 top)")
    axes[1].set_title(f"{len(results['random'])} random LQ problems (Fig. 2 bottom)")
    for ax in axes:
        ax.set_xlabel("iteration")
        ax.set_ylim(1e-16, None)
        ax.axhline(TOL, color="k", lw=0.5)
        ax.set_ylabel("(J - J*) / |J*|  (J* certified)")
    axes[0].legend(fontsize=7)
    fig.tight_layout()
    path = os.path.join(out_dir, "boxddp_lq.png")
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path
