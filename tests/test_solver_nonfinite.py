"""NaN/inf inside a solve (issue 14): located, reported, never returned; re-allocation after updateModel."""

from __future__ import annotations

import numpy as np
import pytest
from solver_problems import SOLVERS, check_outcome, integrator_problem, poison

import crocopy

BOXED = ("BoxDDP", "BoxFDDP", "ClampedForward", "ClampedBackward")
KERNELS = [True, False] if crocopy.kernels.available else [False]


def _problem(name: str, **kw) -> crocopy.ShootingProblem:
    return integrator_problem(u_bound=0.5 if name in BOXED else np.inf, **kw)


@pytest.mark.parametrize("kernels", KERNELS)
@pytest.mark.parametrize("name", [n for n in SOLVERS if n != "HDDP"])
def test_overflowing_unicycle_returns_false_with_the_node(name, kernels):
    """Issue 14, reproducer 1: dt = 1e300 overflows Quu at the last node."""
    m = crocopy.ActionModelUnicycle()
    m.dt = 1e300
    problem = crocopy.ShootingProblem(np.array([-1.0, -1, 1]), [m] * 10, m)
    solver = SOLVERS[name](problem)
    with crocopy.use_kernels(kernels):
        assert solver.solve() is False
    assert solver.reason == "non-finite Quu at node 9 in the backward pass (kept the best finite iterate)"
    check_outcome(solver, problem)


@pytest.mark.parametrize("kernels", KERNELS)
def test_overflowing_hddp_returns_false(kernels):
    problem = integrator_problem(dt=1e300, x0=np.array([1e-3, 1e-3, 0.0, 0.0]))
    solver = SOLVERS["HDDP"](problem)
    with crocopy.use_kernels(kernels):
        assert solver.solve() is False
    assert solver.reason.startswith("non-finite ")
    check_outcome(solver, problem)


CASES = [(n, q, node) for n in SOLVERS for q, node in (("Fx", 3), ("Fu", 5), ("Lx", 8), ("Lxx", 2), ("Luu", 4))
         if n != "HDDP" or q in ("Fx", "Fu")]


@pytest.mark.parametrize("kernels", KERNELS)
@pytest.mark.parametrize(("name", "quantity", "node"), CASES)
def test_nan_derivative_is_named_with_its_node(name, quantity, node, kernels):
    problem = _problem(name, T=8)
    poison(problem, node, quantity, after=1)
    solver = SOLVERS[name](problem)
    with crocopy.use_kernels(kernels):
        assert solver.solve(maxiter=50) is False
    assert solver.reason == f"non-finite {quantity} at node {node} in the derivatives (kept the best finite iterate)"
    check_outcome(solver, problem)


def test_best_iterate_is_kept_not_the_last():
    """Steps of length 3 on an LQ problem raise the cost (accepted: th_grad is huge); a NaN then
    stops the solve, which goes back to the first, cheapest, iterate."""
    problem = integrator_problem(T=6)
    poison(problem, 2, "Fu", after=3)
    solver = crocopy.SolverFDDP(problem)
    solver.alphas, solver.th_grad = [3.0], 1e300
    logger = crocopy.CallbackLogger()
    solver.setCallbacks([logger])
    us0 = [np.full(2, 0.1) for _ in range(6)]
    xs0 = problem.rollout(us0)
    cost0 = problem.calc(xs0, us0)
    assert solver.solve(xs0, us0, maxiter=10, is_feasible=True) is False
    assert len(logger.costs) >= 2 and logger.costs[-1] > logger.costs[0] > cost0
    assert solver.reason.startswith("non-finite Fu at node 2")
    check_outcome(solver, problem)
    assert solver.cost == pytest.approx(cost0, rel=1e-12)
    for x, x0 in zip(solver.xs, xs0):
        np.testing.assert_allclose(x, x0, rtol=1e-12)


def test_verbose_prints_the_reason(capsys):
    problem = integrator_problem(T=5)
    poison(problem, 4, "Lxx", after=1)
    solver = crocopy.SolverFDDP(problem)
    solver.setCallbacks([crocopy.CallbackVerbose()])
    assert solver.solve() is False
    out = capsys.readouterr().out
    assert "solve stopped: non-finite Lxx at node 4 in the derivatives" in out


@pytest.mark.parametrize("name", SOLVERS)
def test_a_guess_whose_cost_is_not_finite_is_a_clear_error(name):
    problem = _problem(name, T=4, goal=np.full(4, 1e10), w_goal=1e300)
    with pytest.raises(ValueError, match="initial guess is not finite.*node 4"):
        SOLVERS[name](problem).solve()


class CubicModel(crocopy.ActionModelAbstract):
    """``x' = x + u + 1e300 u³``, cost ``½(x² + u²)``: the linearisation is tame, every rollout overflows."""

    def __init__(self) -> None:
        super().__init__(crocopy.StateVector(1), 1, 0)

    def calc(self, data, x, u=None):
        if u is None:
            data.xnext[:] = x
            data.cost = 0.5 * float(x @ x)
            return
        data.xnext[:] = x + u + 1e300 * u**3
        data.cost = 0.5 * float(x @ x + u @ u)

    def calcDiff(self, data, x, u=None):
        data.Lx[:] = x
        data.Lxx[:] = 1.0
        if u is not None:
            data.Fx[:] = 1.0
            data.Fu[:] = 1.0 + 3e300 * u**2
            data.Lu[:] = u
            data.Luu[:] = 1.0


@pytest.mark.parametrize("name", ["DDP", "FDDP", "BoxFDDP", "Projection"])
def test_rollouts_that_overflow_are_rejected_and_named(name):
    m = CubicModel()
    problem = crocopy.ShootingProblem(np.ones(1), [m] * 3, m)
    solver = SOLVERS[name](problem)
    solver.reg_max = 1e3
    us = [np.zeros(1)] * 3
    assert solver.solve(problem.rollout(us), us, maxiter=20, is_feasible=True) is False
    assert solver.reason.startswith("no step accepted and regularization reached reg_max = 1000 (last trial: "
                                    "non-finite cost at node 1 in the rollout)")
    check_outcome(solver, problem)


LQR_SOLVERS = [n for n in SOLVERS if n != "HDDP"]


@pytest.mark.parametrize("kernels", KERNELS)
@pytest.mark.parametrize("name", LQR_SOLVERS)
@pytest.mark.parametrize("change", ["updateModel", "circularAppend", "terminal"])
def test_node_dimension_change_reallocates(name, change, kernels):
    """Issue 14, reproducer 9: a node whose nu (or nx) changes after a solve."""
    problem = crocopy.ShootingProblem(np.ones(3), [crocopy.ActionModelLQR(3, 2)] * 5, crocopy.ActionModelLQR(3, 2))
    solver = SOLVERS[name](problem)
    with crocopy.use_kernels(kernels):
        assert solver.solve()
        if change == "updateModel":
            problem.updateModel(2, crocopy.ActionModelLQR(3, 1, True))
        elif change == "circularAppend":
            problem.circularAppend(crocopy.ActionModelLQR(3, 1, True))
        else:
            new_terminal = crocopy.ActionModelLQR(3, 1, True)
            problem.updateModel(5, new_terminal)
        assert solver.solve()
    nus = [m.nu for m in problem.runningModels]
    assert [u.shape for u in solver.us] == [(nu,) for nu in nus]
    assert [k.shape for k in solver.k] == [(nu,) for nu in nus]
    assert [K.shape for K in solver.K] == [(nu, 3) for nu in nus]
    check_outcome(solver, problem)


def test_hddp_follows_a_replaced_node():
    """HDDP reads its levels from the nodes' cost sums: a new terminal goal is the one reached."""
    problem = integrator_problem(T=10)
    solver = SOLVERS["HDDP"](problem)
    assert solver.solve()
    goal = np.array([0.5, -0.5, 0.0, 0.0])
    problem.updateModel(10, integrator_problem(T=1, goal=goal).terminalModel)
    assert solver.solve()
    np.testing.assert_allclose(solver.xs[-1][:2], goal[:2], atol=0.05)
    check_outcome(solver, problem)


WRAPPERS = {
    "squashed": lambda m: crocopy.ActionModelSquashed(m, "smooth-sat", -np.ones(2), np.ones(2)),
    "penalty": lambda m: crocopy.ActionModelControlPenalty(m, 1e3, -np.ones(2), np.ones(2)),
}


@pytest.mark.parametrize("kernels", KERNELS)
@pytest.mark.parametrize("wrapper", WRAPPERS)
@pytest.mark.parametrize("name", ["DDP", "FDDP"])
def test_squashing_and_penalty_baselines_stop_finitely(name, wrapper, kernels):
    """The squashing and penalty baselines wrap an overflowing unicycle: same stop, same report."""
    m = crocopy.ActionModelUnicycle()
    m.dt = 1e300
    w = WRAPPERS[wrapper](m)
    problem = crocopy.ShootingProblem(np.array([-1.0, -1, 1]), [w] * 10, w)
    solver = SOLVERS[name](problem)
    with crocopy.use_kernels(kernels):
        assert solver.solve() is False
    assert solver.reason.startswith("non-finite ") and " at node " in solver.reason
    check_outcome(solver, problem)


class ResetModel(crocopy.ActionModelAbstract):
    """``x' = u`` (the state is forgotten), cost ``½(u - 1)²``; with ``poisoned``, ``x' = NaN`` when ``u ≥ 0.4``."""

    def __init__(self, poisoned: bool = False) -> None:
        super().__init__(crocopy.StateVector(1), 1, 0)
        self.poisoned = poisoned

    def calc(self, data, x, u=None):
        if u is None:
            data.xnext[:] = x
            data.cost = 0.0
            return
        data.xnext[:] = np.nan if self.poisoned and u[0] >= 0.4 else u
        data.cost = 0.5 * float((u[0] - 1.0) ** 2)

    def calcDiff(self, data, x, u=None):
        data.Lx[:], data.Lxx[:] = 0.0, 0.0
        if u is not None:
            data.Fx[:], data.Fu[:], data.Lu[:], data.Luu[:] = 0.0, 1.0, u - 1.0, 1.0


class ForgetModel(crocopy.ActionModelAbstract):
    """``x' = 0`` without control or cost: whatever its state, nothing after it sees it."""

    def __init__(self) -> None:
        super().__init__(crocopy.StateVector(1), 0, 0)

    def calc(self, data, x, u=None):
        data.xnext[:] = 0.0
        data.cost = 0.0

    def calcDiff(self, data, x, u=None):
        data.Fx[:], data.Lx[:], data.Lxx[:] = 0.0, 0.0, 0.0


@pytest.mark.parametrize("name", ["DDP", "FDDP", "BoxFDDP"])
def test_a_trial_with_a_nan_state_inside_is_never_accepted(name):
    """The NaN state at node 2 leaves the cost and the last state finite; the step is still refused."""
    models = [ResetModel(), ResetModel(True), ForgetModel(), ResetModel()]
    problem = crocopy.ShootingProblem(np.zeros(1), models, ResetModel())
    solver = SOLVERS[name](problem)
    logger = crocopy.CallbackLogger()
    solver.setCallbacks([logger])
    us = [np.zeros(m.nu) for m in models]
    solver.solve(problem.rollout(us), us, maxiter=1, is_feasible=True)
    assert logger.steps[0] == 0.25
    check_outcome(solver, problem)
