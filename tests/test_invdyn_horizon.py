"""The inverse-dynamics nodes' horizon (:class:`crocopy.models.rbd.invdyn_horizon.InvDynHorizon`): a range of nodes in
one compiled call gives, bit for bit, what the same compiled nodes give one call at a time (values, derivatives,
constraint rows, whole solves), and on two threads what it gives on one."""

from __future__ import annotations

import numpy as np
import pytest
from node_checks import make_solver
from test_invdyn_node import arm_problem, quadruped_problem

import crocopy
from crocopy.models.rbd.invdyn_horizon import InvDynHorizon
from crocopy.models.rbd.invdyn_node import InvDynNode
from crocopy.solvers import compiled_nodes

pytestmark = pytest.mark.skipif(not crocopy.kernels_enabled(), reason="compiled nodes need numba")

FIELDS = ("xnext", "Fx", "Fu", "Lx", "Lu", "Lxx", "Lxu", "Luu", "h", "Hx", "Hu")
BUILDERS = {"arm": arm_problem, "quadruped": quadruped_problem}


def _point(problem, seed: int = 0) -> tuple[list, list]:
    """A state and control per node off the problem's standing guess."""
    rng = np.random.default_rng(seed)
    state = problem.runningModels[0].state
    xs = [state.integrate(problem.x0, 0.1 * rng.standard_normal(state.ndx)) for _ in range(problem.T + 1)]
    us = [0.1 * rng.standard_normal(m.nu) for m in problem.runningModels]
    return xs, us


def _evaluate(problem, xs, us) -> tuple:
    """Values then derivatives through the compiled nodes of a FDDP solver on ``problem``: the two totals and every
    running node's cost and fields."""
    nodes = compiled_nodes.attach(crocopy.SolverFDDP(problem))
    total = nodes.calc(problem, xs, us)
    values = [(d.cost, np.array(d.xnext)) for d in problem.runningDatas]
    total_diff = nodes.calcDiff(problem, xs, us, False)
    fields = [(d.cost, [np.array(getattr(d, f)) for f in FIELDS]) for d in problem.runningDatas]
    return nodes, total, values, total_diff, fields


def test_every_running_node_is_in_one_range_of_the_horizon():
    problem = quadruped_problem()
    nodes = compiled_nodes.attach(make_solver("SolverIntro", problem))
    assert type(nodes.horizon) is InvDynHorizon
    assert nodes.ranges == [(0, problem.T)] and nodes.python_nodes == []


@pytest.mark.parametrize("nthreads", [1, 2])
@pytest.mark.parametrize("name", list(BUILDERS))
def test_the_horizon_equals_the_nodes_one_call_at_a_time(name, nthreads, monkeypatch):
    build = BUILDERS[name]
    xs, us = _point(build())
    problem = build()
    problem.nthreads = nthreads
    got = _evaluate(problem, xs, us)
    assert type(got[0].horizon) is InvDynHorizon
    assert (got[0].horizon.threads is not None) == (nthreads > 1)
    monkeypatch.setattr(InvDynNode, "horizon", None)
    expected = _evaluate(build(), xs, us)
    assert expected[0].horizon is None
    assert got[1] == expected[1] and got[3] == expected[3]
    for (c, xnext), (c_ref, xnext_ref) in zip(got[2], expected[2], strict=True):
        assert c == c_ref
        np.testing.assert_array_equal(xnext, xnext_ref)
    for (c, arrays), (c_ref, arrays_ref) in zip(got[4], expected[4], strict=True):
        assert c == c_ref
        for a, b in zip(arrays, arrays_ref, strict=True):
            np.testing.assert_array_equal(a, b)


def _solve(problem, solver: str, maxiter: int):
    s = make_solver(solver, problem)
    guess = [problem.x0] * (problem.T + 1)
    s.solve(guess, problem.quasiStatic(guess[:-1]), maxiter)
    return s


@pytest.mark.parametrize(("name", "solver", "maxiter"), [
    ("arm", "SolverIntro", 20), ("arm", "SolverFDDP", 20), ("arm", "SolverSQP", 6), ("quadruped", "SolverIntro", 10),
    ("quadruped", "SolverCSQP", 10)])
def test_solves_through_the_horizon_equal_solves_node_by_node(name, solver, maxiter, monkeypatch):
    build = BUILDERS[name]
    got = _solve(build(), solver, maxiter)
    monkeypatch.setattr(InvDynNode, "horizon", None)
    expected = _solve(build(), solver, maxiter)
    assert got.iter == expected.iter > 1
    if name == "arm":  # revolute joints: the compiled gaps and the Python ones are the same subtraction
        assert got.cost == expected.cost
        for a, b in zip([*got.xs, *got.us], [*expected.xs, *expected.us], strict=True):
            np.testing.assert_array_equal(a, b)
    else:  # a free flyer's gaps: the compiled logarithm and Pinocchio's differ by round-off
        assert got.cost == pytest.approx(expected.cost, rel=1e-12)
        for a, b in zip([*got.xs, *got.us], [*expected.xs, *expected.us], strict=True):
            np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-10)


@pytest.mark.parametrize(("name", "solver"), [("arm", "SolverSQP"), ("quadruped", "SolverIntro")])
def test_solves_on_two_threads_are_bit_identical(name, solver):
    solves = []
    for nthreads in (1, 2):
        problem = BUILDERS[name]()
        problem.nthreads = nthreads
        solves.append(_solve(problem, solver, 6))
    one, two = solves
    assert two.iter == one.iter > 1
    assert two.cost == one.cost
    for a, b in zip([*two.xs, *two.us], [*one.xs, *one.us], strict=True):
        np.testing.assert_array_equal(a, b)
