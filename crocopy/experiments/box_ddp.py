"""Experiments of Tassa, Mansard, Todorov, *Control-Limited DDP* (ICRA 2014), Figs. 2–4.

:func:`run_lq` — random box-constrained LQ problems (Fig. 2).  ``x' = fx x + fu u`` with
``fx = I + h N(n, n)``, ``fu = h N(n, m)`` (i.i.d. standard normals), cost
``½ Σ (xᵀ (h I) x + uᵀ (c_u h I) u) + ½ x_Nᵀ (h I) x_N``, bounds ``±1``, ``x0 ~ N(0, I)``,
``U0 = 0``.  Methods: Box-DDP, squashing (``tanh``, plain DDP on :class:`ActionModelSquashed`),
clamping variant 1 (rollout) and variant 2 (backward pass).  Metric: ``ΔJ = J_k - J*`` per
iteration (``J*`` the lowest cost any method reached) and the mean number of box-QP Cholesky
factorizations per QP solve (paper: ≈ 1.5).

:func:`run_car` — car parking (Figs. 3–4).  State ``(x, y, θ, v)``, controls front-wheel angle
``ω ∈ [-0.5, 0.5]`` and acceleration ``a ∈ [-2, 2]``; :class:`ActionModelCar` implements the
paper's dynamics and costs.  Box-DDP against squashing (``ω = 0.5 tanh ω̃``, ``a = 2 tanh ã`` and
``10⁻⁶ (ω̃² + ã²)``).  Metric: iterations to convergence (paper: Box-DDP after 64, squashing not
by 500) and zero rows of ``K`` where controls are clamped.

Constants the paper leaves open, and the values chosen here:

* LQ: ``c_u = 10`` (unspecified; sweepable — with ``c_u <= 1`` almost every control saturates on
  these open-loop unstable systems and every method stalls), seed 0 for the showcase and seeds 1..20
  for the random sizes ``n ~ U{10..100}``, ``m ~ U{1..n/2}`` (``N = 200``, ``h = 0.01`` as in the
  showcase); squashing raw-control weight ``1e-6`` (``ActionModelSquashed.rawWeight``).
* Car: ``h = 0.03`` s and axle distance ``d = 2`` m (from Tassa's public demo, not the paper),
  ``N = 500``, initial controls ``0.1 N(0, 1)`` clipped to the box (seed 0), squashing raw weight
  ``2e-6`` (i.e. ``10⁻⁶ Σ ũ²`` with our ``½ w ‖ũ‖²`` convention).
* Box-DDP is run with Tassa's exact value update (``general_value_update = True``, the paper's
  reference code); the Crocoddyl-3.2-identical default variant is shown as a fifth curve on the LQ
  problems (it zeroes ``Qu`` of clamped controls in the expected improvement and stalls when most
  controls saturate).
* Solvers: Crocoddyl's defaults (initial regularisation ``1e-9``, factors 10, step lengths
  ``2^-n``); "converged" means the solver's own stopping test (``th_stop = 5e-5`` Box-DDP,
  ``1e-9`` plain DDP) — and, to compare like with like, the first iteration with ``ΔJ < 1e-6 |J*|``.
"""

from __future__ import annotations

import os

import numpy as np

from ..action_base import ActionDataAbstract, ActionModelAbstract
from ..actions import ActionModelLQR
from ..shooting import ShootingProblem
from ..solvers import SolverDDP
from ..solvers.box_ddp import SolverBoxDDP
from ..solvers.clamping import SolverClampedDDP
from ..squashing.action import ActionModelSquashed
from ..state import StateVector

__all__ = ["ActionModelCar", "box_ddp_tassa", "car_problem", "lq_problem", "run_car", "run_lq", "solve_recording"]


def _z(s: float, p: float) -> tuple[float, float, float]:
    """Pseudo-Huber ``z(s, p) = sqrt(s² + p²) - p`` and its first two derivatives."""
    r = np.sqrt(s * s + p * p)
    return r - p, s / r, p * p / r**3


class ActionModelCar(ActionModelAbstract):
    """Tassa et al.'s car (eq. 14): Euler step ``h``, axle distance ``d``, exact cost Hessians.

    Dynamics (``f = h v``, ``b = f cos ω + d - sqrt(d² - f² sin² ω)``)::

        x' = x + b cos θ,  y' = y + b sin θ,  θ' = θ + asin(sin ω f / d),  v' = v + h a.

    Running cost ``0.01 (z(x, 0.1) + z(y, 0.1)) + c_ω ω² + c_a a²``; terminal cost
    ``z(x, 0.1) + z(y, 0.1) + z(θ, 0.01) + z(v, 1)``.  Derivatives of the dynamics are first order
    (iLQR); the cost Hessians are exact.
    """

    def __init__(self, h: float = 0.03, d: float = 2.0, c_w: float = 0.01, c_a: float = 1e-4) -> None:
        super().__init__(StateVector(4), 2, 0)
        self.h, self.d, self.c_w, self.c_a = float(h), float(d), float(c_w), float(c_a)
        self.u_lb = np.array([-0.5, -2.0])
        self.u_ub = np.array([0.5, 2.0])

    def calc(self, data: ActionDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        """Next state and cost."""
        if u is None:
            data.xnext[:] = x
            data.cost = _z(x[0], 0.1)[0] + _z(x[1], 0.1)[0] + _z(x[2], 0.01)[0] + _z(x[3], 1.0)[0]
            return
        h, d = self.h, self.d
        w, a = u
        f = h * x[3]
        s, c = np.sin(w), np.cos(w)
        b = f * c + d - np.sqrt(d * d - f * f * s * s)
        data.xnext[0] = x[0] + b * np.cos(x[2])
        data.xnext[1] = x[1] + b * np.sin(x[2])
        data.xnext[2] = x[2] + np.arcsin(s * f / d)
        data.xnext[3] = x[3] + h * a
        data.cost = 0.01 * (_z(x[0], 0.1)[0] + _z(x[1], 0.1)[0]) + self.c_w * w * w + self.c_a * a * a

    def calcDiff(self, data: ActionDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        """Jacobians of the dynamics and gradient/Hessian of the cost."""
        if u is None:
            for i, p in enumerate((0.1, 0.1, 0.01, 1.0)):
                _, data.Lx[i], hess = _z(x[i], p)
                data.Lxx[i, i] = hess
            data.Fx[:] = np.eye(4)
            return
        h, d = self.h, self.d
        w, a = u
        f = h * x[3]
        s, c = np.sin(w), np.cos(w)
        r = np.sqrt(d * d - f * f * s * s)
        b = f * c + d - r
        db_dv = h * (c + f * s * s / r)
        db_dw = -f * s + f * f * s * c / r
        ct, st = np.cos(x[2]), np.sin(x[2])
        q = 1.0 / np.sqrt(1.0 - (s * f / d) ** 2)
        Fx, Fu = data.Fx, data.Fu
        Fx[:] = np.eye(4)
        Fx[0, 2], Fx[0, 3] = -b * st, db_dv * ct
        Fx[1, 2], Fx[1, 3] = b * ct, db_dv * st
        Fx[2, 3] = q * s * h / d
        Fu[:] = 0.0
        Fu[0, 0], Fu[1, 0] = db_dw * ct, db_dw * st
        Fu[2, 0] = q * c * f / d
        Fu[3, 1] = h
        data.Lx[:] = 0.0
        data.Lxx[:] = 0.0
        for i in (0, 1):
            _, g, hess = _z(x[i], 0.1)
            data.Lx[i], data.Lxx[i, i] = 0.01 * g, 0.01 * hess
        data.Lu[:] = (2.0 * self.c_w * w, 2.0 * self.c_a * a)
        data.Luu[:] = np.diag([2.0 * self.c_w, 2.0 * self.c_a])
        data.Lxu[:] = 0.0


def lq_problem(n: int = 20, m: int = 7, N: int = 200, h: float = 0.01, c_u: float = 10.0, seed: int = 0):
    """Random box-constrained LQ problem of Fig. 2; returns ``(problem, model)`` (bounds ``±1``)."""
    rng = np.random.default_rng(seed)
    fx = np.eye(n) + h * rng.standard_normal((n, n))
    fu = h * rng.standard_normal((n, m))
    model = ActionModelLQR(fx, fu, h * np.eye(n), c_u * h * np.eye(m), np.zeros((n, m)),
                           np.zeros(n), np.zeros(n), np.zeros(m))
    model.u_lb, model.u_ub = -np.ones(m), np.ones(m)
    return ShootingProblem(rng.standard_normal(n), [model] * N, model), model


def car_problem(N: int = 500, squashed: bool = False) -> ShootingProblem:
    """Car parking from ``(1, 1, 3π/2, 0)``; with ``squashed`` the controls go through ``tanh``."""
    car = ActionModelCar()
    running = ActionModelSquashed(car, "tanh", rawWeight=2e-6) if squashed else car
    return ShootingProblem(np.array([1.0, 1.0, 1.5 * np.pi, 0.0]), [running] * N, ActionModelCar())


def solve_recording(solver, us0, maxiter: int) -> dict:
    """Solve from the rollout of ``us0``; return costs per iteration (index 0 = initial) and status."""
    problem = solver.problem
    xs0 = problem.rollout(us0)
    costs = [problem.calc(xs0, us0)]
    solver.setCallbacks([lambda s: costs.append(s.cost)])
    ok = solver.solve(xs0, us0, maxiter, True)
    return {"costs": np.array(costs), "converged": ok, "iter": solver.iter, "solver": solver}


def box_ddp_tassa(problem: ShootingProblem) -> SolverBoxDDP:
    """Box-DDP with Tassa's exact value update (``general_value_update = True``)."""
    solver = SolverBoxDDP(problem)
    solver.general_value_update = True
    return solver


def _methods_lq(problem: ShootingProblem, model) -> dict:
    squashed = ActionModelSquashed(model, "tanh", rawWeight=1e-6)
    sq_problem = ShootingProblem(problem.x0, [squashed] * problem.T, model)
    return {
        "Box-DDP": box_ddp_tassa(problem),
        "Box-DDP (Crocoddyl update)": SolverBoxDDP(problem),
        "squashing": SolverDDP(sq_problem),
        "clamping (rollout)": SolverClampedDDP(problem, "forward"),
        "clamping (backward)": SolverClampedDDP(problem, "backward"),
    }


def run_lq(out_dir: str = ".", maxiter: int = 30, n_random: int = 20, c_u: float = 10.0, plot: bool = True,
           sizes: tuple[int, int, int] = (20, 7, 200), n_range: tuple[int, int] = (10, 100)) -> dict:
    """Fig. 2: ΔJ per iteration on the showcase LQ problem and on ``n_random`` random sizes.

    ``sizes`` is ``(n, m, N)`` of the showcase; the random problems draw ``n`` in ``n_range`` and
    ``m ~ U{1..n/2}`` with the same ``N``.
    Returns ``{"showcase": {method: costs}, "random": [...], "factorizations_per_qp": float}``
    and writes ``boxddp_lq.png`` in ``out_dir`` when ``plot``.
    """
    n, m, N = sizes
    problem, model = lq_problem(n, m, N, c_u=c_u, seed=0)
    showcase, fact, nqp = {}, 0, 0
    for name, solver in _methods_lq(problem, model).items():
        rec = solve_recording(solver, [np.zeros(model.nu)] * N, maxiter)
        showcase[name] = rec["costs"]
        if name == "Box-DDP":
            fact, nqp = solver.nfactorizations, solver.nqp
    results = {"showcase": showcase, "random": []}
    rng = np.random.default_rng(12345)
    for seed in range(1, n_random + 1):
        n_r = int(rng.integers(n_range[0], n_range[1] + 1))
        m_r = int(rng.integers(1, n_r // 2 + 1))
        prob_r, model_r = lq_problem(n_r, m_r, N, c_u=c_u, seed=seed)
        curves = {}
        for name, solver in _methods_lq(prob_r, model_r).items():
            curves[name] = solve_recording(solver, [np.zeros(m_r)] * N, maxiter)["costs"]
            if name == "Box-DDP":
                fact, nqp = fact + solver.nfactorizations, nqp + solver.nqp
        results["random"].append({"n": n_r, "m": m_r, "costs": curves})
    results["factorizations_per_qp"] = fact / max(nqp, 1)
    print(f"Box-DDP paper Fig. 2 — random box-constrained LQ (c_u = {c_u:g}, N = {N}, h = 0.01)")
    _print_delta_table(f"showcase n={n}, m={m}", showcase)
    for r in results["random"]:
        _print_delta_table(f"random n={r['n']}, m={r['m']}", r["costs"], compact=True)
    print(f"mean box-QP factorizations per QP solve: {results['factorizations_per_qp']:.2f} (paper: ~1.5)")
    if plot:
        results["plot"] = _plot_lq(results, out_dir)
    return results


def _delta(costs: dict) -> dict:
    best = min(float(np.min(c)) for c in costs.values())
    return {k: np.maximum(c - best, 1e-16) for k, c in costs.items()}, best


def _first_below(delta: np.ndarray, tol: float) -> int | None:
    idx = np.flatnonzero(delta < tol)
    return int(idx[0]) if idx.size else None


def _print_delta_table(title: str, costs: dict, compact: bool = False) -> None:
    deltas, best = _delta(costs)
    parts = []
    for name, dj in deltas.items():
        it = _first_below(dj, 1e-6 * max(abs(best), 1.0))
        parts.append(f"{name}: {'>' + str(len(dj) - 1) if it is None else it} it, final ΔJ {dj[-1]:.1e}")
    print(f"  {title}: J* = {best:.6g}; " + ("; ".join(parts)))
    if not compact:
        for name, dj in deltas.items():
            print(f"    {name:20s} ΔJ[0..10] = " + " ".join(f"{v:.1e}" for v in dj[:11]))


def _plot_lq(results: dict, out_dir: str) -> str:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    colors = dict(zip(results["showcase"], ("C0", "C4", "C1", "C2", "C3"), strict=False))
    deltas, _ = _delta(results["showcase"])
    for name, dj in deltas.items():
        axes[0].semilogy(dj, "-o", ms=3, color=colors[name], label=name)
    for r in results["random"]:
        deltas_r, best_r = _delta(r["costs"])
        for name, dj in deltas_r.items():
            axes[1].semilogy(dj / max(abs(best_r), 1e-300), color=colors[name], alpha=0.5, lw=0.8)
    axes[0].set_title("n=20, m=7, N=200 (Fig. 2 top)")
    axes[1].set_title(f"{len(results['random'])} random LQ problems (Fig. 2 bottom)")
    for ax in axes:
        ax.set_xlabel("iteration")
        ax.set_ylim(1e-10, None)
    axes[0].set_ylabel("ΔJ = J - J*  (J* = lowest cost reached)")
    axes[1].set_ylabel("(J - J*) / |J*|")
    axes[0].legend()
    fig.tight_layout()
    path = os.path.join(out_dir, "boxddp_lq.png")
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def run_car(out_dir: str = ".", maxiter: int = 500, plot: bool = True, N: int = 500) -> dict:
    """Figs. 3–4: car parking with Box-DDP against squashing; prints iterations and ``K`` structure."""
    rng = np.random.default_rng(0)
    lb, ub = np.array([-0.5, -2.0]), np.array([0.5, 2.0])
    u_init = [np.clip(0.1 * rng.standard_normal(2), lb, ub) for _ in range(N)]
    box = box_ddp_tassa(car_problem(N))
    rec_box = solve_recording(box, u_init, maxiter)
    sq_problem = car_problem(N, squashed=True)
    sq_init = [np.arctanh(u / ub) for u in u_init]
    rec_sq = solve_recording(SolverDDP(sq_problem), sq_init, maxiter)
    costs = {"Box-DDP": rec_box["costs"], "squashing": rec_sq["costs"]}
    deltas, best = _delta(costs)
    box.computeDirection(True)
    clamped_nodes = zero_rows_ok = 0
    for t in range(N):
        free = np.diag(box.Quu_inv[t]) != 0.0
        if not free.all():
            clamped_nodes += 1
            zero_rows_ok += int(np.all(box.K[t][~free] == 0.0))
    us_box = np.array(box.us)
    sq_model = sq_problem.runningModels[0]
    us_sq = np.array([sq_model.squash(u) for u in rec_sq["solver"].us])
    result = {
        "costs": costs, "best": best,
        "iterations": {"Box-DDP": rec_box["iter"], "squashing": rec_sq["iter"]},
        "converged": {"Box-DDP": rec_box["converged"], "squashing": rec_sq["converged"]},
        "iterations_to_1e-6": {k: _first_below(v, 1e-6 * abs(best)) for k, v in deltas.items()},
        "clamped_nodes": clamped_nodes, "clamped_nodes_with_zero_K_rows": zero_rows_ok,
        "max_gain": {"Box-DDP": max(np.abs(K).max() for K in box.K),
                     "squashing": max(np.abs(K).max() for K in rec_sq["solver"].K)},
        "final_state": {"Box-DDP": box.xs[-1].copy(), "squashing": rec_sq["solver"].xs[-1].copy()},
        "us": {"Box-DDP": us_box, "squashing": us_sq},
        "xs": {"Box-DDP": np.array(box.xs), "squashing": np.array(rec_sq["solver"].xs)},
    }
    print(f"Box-DDP paper Figs. 3-4 — car parking (N = {N}, h = 0.03, d = 2; J* = {best:.6g})")
    for k in costs:
        print(f"  {k:10s} solver stop after {result['iterations'][k]:3d} it (converged={result['converged'][k]}), "
              f"ΔJ < 1e-6 J* at it {result['iterations_to_1e-6'][k]}, final cost {costs[k][-1]:.6g}, "
              f"max |K| {result['max_gain'][k]:.3g}, final state {np.round(result['final_state'][k], 3)}")
    print("  paper: Box-DDP converges after 64 iterations, squashing has barely converged by 500")
    print(f"  Box-DDP nodes with a clamped control: {clamped_nodes}; with the clamped rows of K all zero: "
          f"{zero_rows_ok}")
    if plot:
        result["plot"] = _plot_car(result, out_dir)
    return result


def _plot_car(result: dict, out_dir: str) -> str:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(15, 4))
    for name, color in (("Box-DDP", "C0"), ("squashing", "C1")):
        xs = result["xs"][name]
        axes[0].plot(xs[:, 0], xs[:, 1], color=color, label=name)
        axes[1].plot(result["us"][name][:, 0], color=color, label=f"{name} ω")
        axes[1].plot(result["us"][name][:, 1] / 4.0, "--", color=color, label=f"{name} a/4")
        axes[2].semilogy(np.maximum(result["costs"][name] - result["best"], 1e-16), color=color, label=name)
    axes[0].plot([1.0], [1.0], "ko")
    axes[0].plot([0.0], [0.0], "k*")
    axes[0].set_aspect("equal")
    axes[0].set_title("paths (Fig. 3)")
    axes[1].set_title("controls (ω, a/4), bounds ±0.5")
    axes[1].axhline(0.5, color="k", lw=0.5)
    axes[1].axhline(-0.5, color="k", lw=0.5)
    axes[2].set_title("ΔJ per iteration (Fig. 4)")
    axes[2].set_xlabel("iteration")
    for ax in axes:
        ax.legend(fontsize=7)
    fig.tight_layout()
    path = os.path.join(out_dir, "boxddp_car.png")
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path
