"""Trial rollouts that diverge: compiled ranges run in steps give one call's numbers, and the reason is found as the
node-by-node search finds it."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import crocopy
from crocopy.problems import registry
from crocopy.solvers import compiled_nodes
from crocopy.solvers.base import ForwardPassError
from crocopy.solvers.nonfinite import NonFiniteError, locate_in_rollout


def _attached_solver(dt: float | None = None):
    problem, xs, us = registry.build("quad-goal")
    if dt is not None:
        for m in problem.runningModels:
            m.dt = dt
    solver = crocopy.SolverFDDP(problem)
    solver.setCandidate(xs, us, False)
    assert compiled_nodes.attach(solver).horizon is not None
    solver.computeDirection()
    return solver


def _trial(solver, alpha: float, chunked: bool):
    """``tryStep(alpha)`` with the compiled ranges in one call or in steps: ``(cost_try or the error, xs_try)``."""
    solver._diverged_steps = {alpha} if chunked else set()
    solver._last_trial_diverged = False
    try:
        outcome = solver.tryStep(alpha)
    except ForwardPassError:
        outcome = str(locate_in_rollout(solver.problem, solver.xs_try, solver.us_try))
    return outcome, [x.copy() for x in solver.xs_try]


@pytest.mark.parametrize("alpha", [0.25, 0.125, 0.01])
def test_a_range_run_in_steps_gives_the_numbers_of_one_call(alpha):
    solver = _attached_solver()
    one, xs_one = _trial(solver, alpha, False)
    steps, xs_steps = _trial(solver, alpha, True)
    assert isinstance(one, float) and one == steps  # the same total, bit for bit
    for a, b in zip(xs_one, xs_steps):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize(("dt", "alpha"), [(None, 1.0), (None, 0.5), (50.0, 1.0)])
def test_a_diverging_trial_fails_and_is_located_the_same_in_steps_and_in_one_call(dt, alpha):
    solver = _attached_solver(dt)
    one, _ = _trial(solver, alpha, False)
    steps, _ = _trial(solver, alpha, True)
    assert solver._last_trial_diverged  # a compiled step diverged: its range stopped there
    assert one.startswith("non-finite") and one == steps


def _reference(problem, xs, us):
    """The node-by-node search: state, control, cost at each node in turn."""
    datas = [*problem.runningDatas, problem.terminalData]
    for t, (x, d) in enumerate(zip(xs, datas)):
        if not np.isfinite(x).all():
            return "state", t
        if t < len(us) and not np.isfinite(us[t]).all():
            return "control", t
        if not math.isfinite(d.cost):
            return "cost", t
    return None


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.sampled_from(["state", "control", "cost"]), st.integers(0, 50),
                          st.sampled_from([math.nan, math.inf, -math.inf])), max_size=3))
def test_the_located_node_is_the_first_of_the_node_by_node_search(bad):
    problem, xs, us = registry.build("quad-goal")
    xs, us = [x.copy() for x in xs], [u.copy() for u in us]
    datas = [*problem.runningDatas, problem.terminalData]
    for d in datas:
        d.cost = 1.0
    for kind, t, value in bad:
        if kind == "state":
            xs[t][t % xs[t].size] = value
        elif kind == "control" and t < len(us):
            us[t][t % us[t].size] = value
        else:
            datas[t].cost = value
    found = locate_in_rollout(problem, xs, us)
    expected = _reference(problem, xs, us)
    assert (found is None) == (expected is None)
    if found is not None:
        assert (found.quantity, found.node, found.where) == (*expected, "rollout")


def test_a_cause_given_as_a_function_is_asked_once_when_the_message_is_read():
    calls = []

    def cause():
        calls.append(1)
        return "the mass matrix is singular"

    error = NonFiniteError("cost", 3, "rollout", cause)
    assert not calls
    assert str(error) == "non-finite cost at node 3 in the rollout: the mass matrix is singular"
    assert f"{error}" == str(error) and error.args == (str(error),) and len(calls) == 1
    assert str(NonFiniteError("state", 2, "rollout", lambda: None)) == "non-finite state at node 2 in the rollout"
    assert str(NonFiniteError("Quu", None, "backward pass", "given")) == "non-finite Quu in the backward pass: given"
