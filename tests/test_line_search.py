"""The DDP family's line search in one compiled call (:mod:`crocopy.solvers.line_search`): the same trials, iterates
and outcome as the Python loop of one ``tryStep`` per step length, to the bit; a trial that is not finite hands the
search back to that loop."""

from __future__ import annotations

import numpy as np
import pytest

import crocopy
from crocopy.models.rbd import euler_horizon, line_search_kernel
from crocopy.problems import registry
from crocopy.solvers import compiled_nodes, line_search, rollout, stopwatch

SOLVERS = ["SolverDDP", "SolverFDDP", "SolverBoxDDP", "SolverBoxFDDP"]


def _spy(monkeypatch, name: str) -> list:
    """The ``(i, status)`` of every call of the horizon's search ``name`` while the test runs (None where it did not
    apply)."""
    seen = []
    search = getattr(euler_horizon.EulerHorizon, name)

    def spy(self, *args):
        found = search(self, *args)
        seen.append(found)
        return found

    monkeypatch.setattr(euler_horizon.EulerHorizon, name, spy)
    return seen


@pytest.fixture
def statuses(monkeypatch):
    """The compiled searches from a feasible iterate run while the test runs."""
    return _spy(monkeypatch, "line_search")


@pytest.fixture
def gap_statuses(monkeypatch):
    """The compiled searches from an infeasible iterate run while the test runs."""
    return _spy(monkeypatch, "line_search_gaps")


def _outcome(solver, solved):
    return (solved, solver.iter, solver.cost, solver.stop, solver.stepLength, solver.preg, solver.isFeasible,
            np.concatenate(solver.xs).tobytes(), np.concatenate(solver.us).tobytes(),
            [d.cost for d in solver.problem.runningDatas], solver.problem.terminalData.cost)


def _solve(build, solver_name, maxiter, feasible=False, solver_class=None):
    problem, xs, us = build()
    solver = (solver_class or getattr(crocopy, solver_name))(problem)
    return solver, _outcome(solver, solver.solve(xs, us, maxiter, feasible))


def _python_loop(monkeypatch, build, solver_name, maxiter, feasible=False):
    with monkeypatch.context() as patch:
        patch.setattr(line_search, "compiled_trials", lambda solver, first: (first, False))
        return _solve(build, solver_name, maxiter, feasible)[1]


@pytest.mark.parametrize("name", ["quad-goal", "pend"])
@pytest.mark.parametrize("solver_name", SOLVERS)
def test_the_compiled_search_gives_the_iterates_of_the_python_loop(name, solver_name, statuses, monkeypatch):
    def build():
        return registry.build(name)

    expected = _python_loop(monkeypatch, build, solver_name, 120)
    statuses.clear()
    _, outcome = _solve(build, solver_name, 120)
    assert any(s is not None and s[1] == line_search_kernel.ACCEPTED for s in statuses)
    assert outcome == expected


@pytest.mark.parametrize("name", ["quad-goal", "quad-narrow", "pend"])
@pytest.mark.parametrize("solver_name", ["SolverFDDP", "SolverBoxFDDP"])
def test_the_compiled_search_from_an_infeasible_iterate_gives_the_iterates_of_the_python_loop(
        name, solver_name, gap_statuses, monkeypatch):
    # the gaps kept open by (1 - α), d of each trial step and the infeasible acceptance rules, in one call
    def build():
        return registry.build(name)

    cls = getattr(crocopy, solver_name)
    taken = []
    accept = cls._accept_trial

    def record(solver, alpha):  # d, dV, dVexp of every trial taken, as its tryStep (or the compiled search) left them
        taken.append((alpha, solver.dV, solver.dVexp, solver.d.tobytes()))
        accept(solver, alpha)

    monkeypatch.setattr(cls, "_accept_trial", record)
    expected = _python_loop(monkeypatch, build, solver_name, 150), list(taken)
    gap_statuses.clear()
    taken.clear()
    outcome = _solve(build, solver_name, 150)[1], list(taken)
    assert any(s is not None and s[1] == line_search_kernel.ACCEPTED for s in gap_statuses)
    assert outcome == expected


@pytest.mark.parametrize("grad_negative", [True, False])
def test_a_predicted_increase_passes_on_a_small_gradient_for_fddp_only(grad_negative):
    # the rule of a negative dVexp from an infeasible iterate: FDDP's passes when |d₀| < th_grad, Box-FDDP's only
    # when dV > th_acceptNegStep dVexp (made to fail here by a negative threshold); d = (dg, dq) makes dVexp < 0
    problem, xs, us = registry.build("pend")
    solver = crocopy.SolverFDDP(problem)
    solver.setCandidate(xs, us, False)
    nodes = compiled_nodes.attach(solver)
    try:
        solver.computeDirection()
        out = np.zeros(6)
        found = nodes.horizon.line_search_gaps(
            rollout.horizon_addresses(solver, nodes, None, None), nodes.terminal, problem.x0, solver._terminal_step(),
            (solver._horizon.addr, solver._horizon.dims), np.array([0.01, 0.005]), float(solver.cost), (0.0, -1e12),
            (1e9, 0.1, -1e9), (True, grad_negative), out)
    finally:
        solver._nodes = None
    assert out[3] < 0.0 and abs(out[4]) < 1e9
    assert found == ((0, line_search_kernel.ACCEPTED) if grad_negative else (1, line_search_kernel.REJECTED))


def test_ddp_and_box_ddp_search_from_an_infeasible_iterate_on_the_python_loop(gap_statuses):
    for solver_name in ("SolverDDP", "SolverBoxDDP"):
        _solve(lambda: registry.build("quad-goal"), solver_name, 20)
    assert gap_statuses == []


def _hovering(dt: float):
    """quad-goal with time step ``dt`` from a feasible hover-thrust rollout: its first full steps diverge."""

    def build():
        problem, _, us = registry.build("quad-goal")
        for model in problem.runningModels:
            model.dt = dt
        us = [np.full(4, 8.0) for _ in us]
        return problem, problem.rollout(us), us

    return build


@pytest.mark.parametrize("dt", [0.05, 2.0])
@pytest.mark.parametrize("solver_name", ["SolverFDDP", "SolverBoxFDDP"])
def test_a_trial_that_is_not_finite_hands_the_search_back_to_the_python_loop(dt, solver_name, statuses, monkeypatch):
    expected = _python_loop(monkeypatch, _hovering(dt), solver_name, 30, True)
    statuses.clear()
    _, outcome = _solve(_hovering(dt), solver_name, 30, True)
    assert any(s is not None and s[1] == line_search_kernel.NONFINITE for s in statuses)
    assert outcome == expected


@pytest.mark.parametrize("solver_name", ["SolverFDDP", "SolverBoxFDDP"])
def test_an_infeasible_trial_that_is_not_finite_hands_the_search_back_to_the_python_loop(solver_name, gap_statuses,
                                                                                        monkeypatch):
    expected = _python_loop(monkeypatch, _hovering(2.0), solver_name, 30)
    gap_statuses.clear()
    _, outcome = _solve(_hovering(2.0), solver_name, 30)
    assert any(s is not None and s[1] == line_search_kernel.NONFINITE for s in gap_statuses)
    assert outcome == expected


def test_a_subclass_and_the_profiler_keep_the_python_loop(statuses):
    class Mine(crocopy.SolverFDDP):
        _nodes_compiled = True  # compiled nodes, not the compiled search (not declared in its own body)

    def build():
        return registry.build("quad-goal")

    _, subclassed = _solve(build, None, 20, solver_class=Mine)
    stopwatch.enable_profiler()
    try:
        _, profiled = _solve(build, "SolverFDDP", 20)
    finally:
        stopwatch.disable_profiler()
        stopwatch.stop_watch_reset_all()
    assert statuses == []
    statuses.clear()
    _, compiled = _solve(build, "SolverFDDP", 20)
    assert statuses and subclassed == profiled == compiled
