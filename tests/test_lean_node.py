"""The solver's trajectories are its own arrays, which never move: the rollout writes its trial in place.

:meth:`crocopy.SolverDDP._trial_rollout` writes ``xs_try``/``us_try`` in place, and an accepted trial is
copied into ``xs``/``us`` (:mod:`crocopy.solvers.trajectories`).  As in Crocoddyl, ``solver.xs`` is the
solver's storage (live), and assigning to it copies (:class:`crocopy.solvers.std_vector.Trajectory`).  These
tests check that the arrays never move, that a callback's copies are what it saw, that holding references
gives the same iterates bit for bit, and that ``setCandidate``/``updateModel`` keep the rollout right.  Also
the in-place ``diff``/``integrate`` of :class:`crocopy.StateVector`.
"""

from __future__ import annotations

import numpy as np
import pytest

import crocopy
from crocopy.guards import trusted_path

SOLVERS = (crocopy.SolverDDP, crocopy.SolverFDDP, crocopy.SolverBoxDDP, crocopy.SolverBoxFDDP)


def unicycle_problem(T: int = 20, bounded: bool = False) -> crocopy.ShootingProblem:
    model = crocopy.ActionModelUnicycle()
    model.costWeights = np.array([10.0, 1.0])
    if bounded:
        model.u_lb, model.u_ub = -np.ones(2), np.ones(2)
    return crocopy.ShootingProblem(np.array([-1.0, -1.0, 1.0]), [model] * T, crocopy.ActionModelUnicycle())


def infeasible_guess(problem: crocopy.ShootingProblem) -> tuple[list, list]:
    rng = np.random.default_rng(3)
    xs = [rng.normal(size=3) for _ in range(problem.T + 1)]
    us = [rng.normal(size=2) for _ in range(problem.T)]
    return xs, us


@pytest.mark.parametrize("Solver", SOLVERS)
def test_the_solver_arrays_never_move_and_are_live(Solver):
    problem = unicycle_problem(bounded=Solver in (crocopy.SolverBoxDDP, crocopy.SolverBoxFDDP))
    solver = Solver(problem)
    names = ("xs", "us", "xs_try", "us_try", "fs", "k", "K")
    ids = {name: [id(a) for a in getattr(solver, name)] for name in names}
    lists = {name: getattr(solver, name) for name in names if name in ("xs", "us", "fs")}
    seen, copies = [], []

    class Keep(crocopy.CallbackAbstract):
        def __call__(self, s):
            seen.append({name: [id(a) for a in getattr(s, name)] for name in names})
            copies.append(s.xs.tolist())

    solver.setCallbacks([Keep()])
    solver.solve(*infeasible_guess(problem), 30)
    solver.solve(solver.xs[1:] + [solver.xs[-1]], solver.us[1:] + [solver.us[-1]], 5)  # MPC-style shift
    assert solver.iter > 0 and len(seen) > 5
    assert all(s == ids for s in seen)
    assert all(getattr(solver, name) is held for name, held in lists.items())
    assert any(not np.array_equal(a[5], b[5]) for a, b in zip(copies, copies[1:]))  # copies kept what they saw
    np.testing.assert_array_equal(copies[-1][5], solver.xs[5])


@pytest.mark.parametrize("Solver", SOLVERS)
def test_holding_every_array_gives_the_same_iterates(Solver):
    """A callback holding all of ``xs``/``us`` forces a new array per node; the numbers must not change."""
    bounded = Solver in (crocopy.SolverBoxDDP, crocopy.SolverBoxFDDP)
    free, held = Solver(unicycle_problem(bounded=bounded)), Solver(unicycle_problem(bounded=bounded))
    hoard = []

    class Hoard(crocopy.CallbackAbstract):
        def __call__(self, s):
            hoard.append((list(s.xs), list(s.us), list(s.xs_try), list(s.us_try)))

    held.setCallbacks([Hoard()])
    for solver in (free, held):
        solver.solve(*infeasible_guess(solver.problem), 40)
    assert (free.iter, free.cost) == (held.iter, held.cost)
    for a, b in zip(free.xs + free.us, held.xs + held.us):
        np.testing.assert_array_equal(a, b)


def test_rollout_writes_its_arrays_in_place():
    problem = unicycle_problem()
    solver = crocopy.SolverFDDP(problem)
    solver.solve(*infeasible_guess(problem), 3)
    with trusted_path():
        solver.computeDirection()
        solver._trial_rollout(0.5, gaps=True)
        ids = [id(a) for a in solver.xs_try + solver.us_try + solver._dx_try[:-1]]
        held = solver.xs_try[4]
        value = held.copy()
        solver._trial_rollout(0.25, gaps=True)
        assert [id(a) for a in solver.xs_try + solver.us_try + solver._dx_try[:-1]] == ids
        assert solver.xs_try[4] is held and not np.array_equal(held, value)


@pytest.mark.parametrize("gaps", [False, True])
def test_rollout_matches_the_model_step_by_step(gaps):
    problem = unicycle_problem()
    solver = crocopy.SolverFDDP(problem)
    solver.setCandidate(*infeasible_guess(problem))
    alpha = 0.5
    with trusted_path():
        solver.computeDirection()
        assert solver.ffeas > 0.1
        solver._trial_rollout(alpha, gaps=gaps)
    model, data = problem.runningModels[0], problem.runningModels[0].createData()
    x = problem.x0 + ((alpha - 1.0) * solver.fs[0] if gaps else 0.0)
    cost = 0.0
    for t in range(problem.T):
        u = solver.us[t] - alpha * solver.k[t] - solver.K[t] @ (x - solver.xs[t])
        np.testing.assert_allclose(solver.us_try[t], u, rtol=1e-12, atol=1e-14)
        np.testing.assert_allclose(solver.xs_try[t], x, rtol=1e-12, atol=1e-14)
        model.calc(data, x, u)
        cost += data.cost
        x = data.xnext + ((alpha - 1.0) * solver.fs[t + 1] if gaps else 0.0)
    np.testing.assert_allclose(solver.xs_try[-1], x, rtol=1e-12, atol=1e-14)
    terminal = problem.terminalModel.createData()
    problem.terminalModel.calc(terminal, x)
    assert solver.cost_try == pytest.approx(cost + terminal.cost, rel=1e-12)


def test_set_candidate_and_update_model_keep_the_rollout_right():
    problem = unicycle_problem()
    solver = crocopy.SolverDDP(problem)
    xs, us = infeasible_guess(problem)
    solver.setCandidate(xs, us)
    solver.solve(xs, us, 5)
    guess_x = [x.copy() for x in xs]
    solver.solve(xs, us, 5)
    for a, b in zip(xs, guess_x):
        np.testing.assert_array_equal(a, b)
    for nu in (2, 3):  # same dimensions (the solver keeps its arrays), then another nu (it re-allocates)
        problem.updateModel(3, crocopy.ActionModelLQR.Random(3, nu))
        us[3] = np.full(nu, 0.1)
        other = crocopy.SolverDDP(problem)
        other.solve(xs, us, 20)
        solver.solve(xs, us, 20)
        assert (solver.iter, solver.cost) == (other.iter, other.cost)
        assert solver.us[3].shape == (nu,)


class ShiftedVector(crocopy.StateVector):
    """A vector state whose ``diff``/``integrate`` a user changed: the in-place forms must call them."""

    def diff(self, x0, x1):
        return 2.0 * (x1 - x0)

    def integrate(self, x, dx):
        return x + 0.5 * dx


@pytest.mark.parametrize("State", [crocopy.StateVector, ShiftedVector])
def test_state_vector_in_place_forms_follow_diff_and_integrate(State):
    state = State(4)
    rng = np.random.default_rng(0)
    x0, x1, dx, out = rng.normal(size=4), rng.normal(size=4), rng.normal(size=4), np.empty(4)
    state._diff_into(x0, x1, out)
    np.testing.assert_array_equal(out, state.diff(x0, x1))
    state._integrate_into(x0, dx, out)
    np.testing.assert_array_equal(out, state.integrate(x0, dx))


def _control_cost_sum(residual: crocopy.ResidualModelControl) -> tuple:
    state = crocopy.StateVector(4)
    costs = crocopy.CostModelSum(state, 2)
    costs.addCost("u", crocopy.CostModelResidual(state, residual), 2.0)
    costs.addCost("x", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, 2)), 1.0)
    return costs, costs.createData(crocopy.DataCollectorAbstract())


def test_the_stack_skips_only_the_control_residuals_own_empty_calcDiff(monkeypatch):
    calls = []

    class Logged(crocopy.ResidualModelControl):
        def calcDiff(self, data, x, u=None):
            calls.append("subclass")

    monkeypatch.setattr(crocopy.ResidualModelControl, "calcDiff", lambda self, data, x, u=None: calls.append("base"))
    x, u = np.arange(4.0), np.array([0.5, -1.0])
    for residual in (crocopy.ResidualModelControl(crocopy.StateVector(4), 2), Logged(crocopy.StateVector(4), 2)):
        costs, data = _control_cost_sum(residual)
        costs.calc(data, x, u)
        costs.calcDiff(data, x, u)
        np.testing.assert_allclose(data.Lu, 2.0 * u)
        np.testing.assert_allclose(data.Luu, 2.0 * np.eye(2))
    assert calls == ["subclass"]
