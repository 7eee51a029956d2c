"""A compiled Euler node's ``calcDiff`` at the point of its last ``calc`` reuses the values that ``calc`` left (the
node's own arrays, :data:`crocopy.models.rbd.node_table.OWN`, and its stamp): the same numbers, to the bit, as an
evaluation from scratch, whatever the other nodes of the model evaluated in between; anywhere else, or after a
refresh (a solve's start) or the Python path, the values are evaluated again."""

from __future__ import annotations

import numpy as np
import pytest
from test_constraint_rows import arm_node, random_point, solo_node
from test_contact_node import contact_node
from test_contact_node import point as contact_point
from test_euler_node import KINDS, node, point
from test_python_residual_node import arm_node as python_residual_node
from test_residual_numba import NAMES as USER_NAMES
from test_residual_numba import NODES as USER_NODES

import crocopy
from crocopy.models.rbd import euler_node_kernel as kernel

pytestmark = pytest.mark.skipif(not crocopy.kernels_enabled(), reason="compiled nodes need numba")

FIELDS = ("xnext", "cost", "Fx", "Fu", "Lx", "Lu", "Lxx", "Lxu", "Luu", "g", "Gx", "Gu", "h", "Hx", "Hu")


def _free(robot):
    def make(terminal):
        iam, state = node(robot, KINDS)
        return iam, lambda seed: point(state, iam.nu, seed)
    return make


def _contact(case):
    def make(terminal):
        iam, state = contact_node(case)
        return iam, lambda seed: contact_point(state, iam.nu, seed)
    return make


def _arm_rows(terminal):
    iam = arm_node(("control", "translation", "state", "velocity", "com"))
    return iam, lambda seed: random_point(iam, np.random.default_rng(seed))


def _solo_rows(terminal):
    iam, x0 = solo_node(terminal)
    return iam, lambda seed: random_point(iam, np.random.default_rng(seed), x0)


def _python(kind):
    def make(terminal):
        iam = python_residual_node(kind, terminal)
        return iam, lambda seed: random_point(iam, np.random.default_rng(seed))
    return make


def _user(robot, name):
    def make(terminal):
        iam = USER_NODES[robot](name, terminal)
        state = iam.state
        reference = iam.differential.costs.costs["state"].cost.residual.reference

        def draw(seed):
            rng = np.random.default_rng(seed)
            return state.integrate(reference, 0.05 * rng.standard_normal(state.ndx)), 0.1 * rng.standard_normal(iam.nu)
        return iam, draw
    return make


CASES = {**{f"user {name} ({robot})": _user(robot, name) for robot in USER_NODES for name in USER_NAMES},
         "kinova": _free("kinova"), "iris": _free("iris"), "anymal-contacts": _contact("anymal-lwa"),
         "talos-6d": _contact("talos-6d"), "arm-constraints": _arm_rows, "solo-constraints": _solo_rows,
         **{f"python {kind}": _python(kind) for kind in ("translation", "velocity")}}


def _evaluators(iam, terminal: bool, n: int):
    memo: dict = {}
    datas = [iam.createData() for _ in range(n)]
    return datas, [iam._compiled_node(d, terminal, memo) for d in datas]


def _fields(data) -> dict:
    return {name: np.array(getattr(data, name)) for name in FIELDS if hasattr(data, name)}


@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("terminal", [False, True])
def test_calc_diff_after_calc_equals_an_evaluation_from_scratch(case, terminal):
    iam, draw = CASES[case](terminal)
    (kept, fresh, other), (e_kept, e_fresh, e_other) = _evaluators(iam, terminal, 3)
    (x, u), (y, w) = draw(1), draw(2)
    u, w = (None, None) if terminal else (u, w)
    e_kept.calc(x, u)
    assert e_kept.stamp[0] == 1.0
    e_other.calcDiff(y, w, False)  # another node of the model: the shared workspace and scratch now hold its point
    e_kept.calcDiff(x, u, True)
    e_fresh.calcDiff(x, u, False)
    uu = e_kept.no_control if u is None else u
    assert not kernel.stamp_current(e_kept.stamp, x, uu)  # the node's own arrays: spent by the derivatives
    assert kernel.values_current(e_kept.stamp, x, uu)  # its data's values: those of (x, u)
    assert not kernel.values_current(e_kept.stamp, y, e_kept.no_control if w is None else w)
    mine, expected = _fields(kept), _fields(fresh)
    for name in expected:
        assert np.array_equal(mine[name], expected[name]), name


def test_the_values_are_reused_only_at_the_stamped_point_to_the_bit():
    """A sentinel planted in the stamp's value shows when the values were skipped."""
    iam, state = node("kinova", ("state", "translation", "control"))
    (data,), (evaluator,) = _evaluators(iam, False, 1)
    x, u = point(state, iam.nu, 3)
    x[2] = 0.0
    sentinel = 1.0e6

    def planted():
        evaluator.calc(x, u)
        evaluator.stamp[1] = sentinel
        return evaluator

    planted().calcDiff(x, u, True)
    assert data.cost == iam.dt * sentinel
    evaluator.calcDiff(x, u, True)  # the stamp was spent
    assert data.cost != iam.dt * sentinel
    signed = x.copy()
    signed[2] = -0.0
    planted().calcDiff(signed, u, True)
    assert data.cost != iam.dt * sentinel
    nudged = u.copy()
    nudged[0] = np.nextafter(u[0], np.inf)
    planted().calcDiff(x, nudged, True)
    assert data.cost != iam.dt * sentinel


@pytest.mark.parametrize("horizon", [False, True], ids=["node", "horizon"])
def test_a_python_residual_node_reuses_its_rollout_values(horizon):
    """The rollout step of a node with a Python residual evaluates that residual's rows after the compiled step (which
    stamped a stack value without them): the stamp then holds the value with them, and a ``calcDiff`` there equals an
    evaluation from scratch, to the bit (one node's step, and the horizon's rollout with its recost)."""
    iam = python_residual_node("velocity", False)
    (kept, fresh), (e_kept, e_fresh) = _evaluators(iam, False, 2)
    x, u = random_point(iam, np.random.default_rng(5))
    nu, ndx = iam.nu, iam.state.ndx
    xs, us = [x.copy(), x.copy()], [u.copy()]
    xs_try, us_try = [x.copy(), np.zeros_like(x)], [np.zeros(nu)]
    ks, Ks, dxs = [np.zeros(nu)], [np.zeros((nu, ndx))], [np.zeros(ndx)]
    fs = [np.zeros(ndx), np.zeros(ndx)]
    lbs, ubs = [np.full(nu, -np.inf)], [np.full(nu, np.inf)]
    if horizon:
        from crocopy.solvers.trajectories import addresses

        rollout = type(e_kept).horizon([e_kept], [nu])
        at = tuple(addresses(a) for a in (xs, us, xs_try, us_try, dxs, ks, Ks, fs, lbs, ubs))
        cost = rollout.rollout(at, xs_try, us_try, 1.0, False, -1, 0, 1)
    else:
        cost = e_kept.rollout_step(xs[0], xs_try[0], us[0], ks[0], Ks[0], 1.0, lbs[0], ubs[0], us_try[0], dxs[0],
                                   xs_try[1], fs[1], False)
    assert e_kept.stamp[0] == 1.0 and np.array_equal(us_try[0], u)
    e_fresh.calc(x, u)
    assert cost == fresh.cost
    e_kept.calcDiff(x, u, True)
    e_fresh.forget()
    e_fresh.calcDiff(x, u, True)
    mine, expected = _fields(kept), _fields(fresh)
    for name in expected:
        assert np.array_equal(mine[name], expected[name]), name


@pytest.mark.parametrize("case", ["kinova", "python velocity", "anymal-contacts"])
def test_a_python_calc_of_the_data_in_between_spends_the_stamp(case):
    """The model's own ``calc`` on the node's data at another point, between the compiled ``calc`` and ``calcDiff`` at
    one point, writes the data's values (residuals, Pinocchio data): the ``calcDiff`` evaluates them again."""
    iam, draw = CASES[case](False)
    (kept, fresh), (e_kept, e_fresh) = _evaluators(iam, False, 2)
    (x, u), (y, w) = draw(1), draw(2)
    e_kept.calc(x, u)
    iam.calc(kept, y, w)
    assert e_kept.stamp[0] == 0.0
    e_kept.calcDiff(x, u, True)
    e_fresh.calcDiff(x, u, False)
    mine, expected = _fields(kept), _fields(fresh)
    for name in expected:
        assert np.array_equal(mine[name], expected[name]), name


def test_a_refresh_and_the_python_path_spend_the_stamp():
    iam, state = node("kinova", ("state", "translation", "control"))
    (data,), (evaluator,) = _evaluators(iam, False, 1)
    x, u = point(state, iam.nu, 4)
    evaluator.calc(x, u)
    evaluator.stamp[1] = 1.0e6
    assert iam._compiled_node(data, False, {}) is evaluator  # what every solve's start does
    evaluator.calcDiff(x, u, True)
    assert data.cost != iam.dt * 1.0e6
    evaluator.calc(x, u)
    evaluator.python_path(x, u, False)
    assert evaluator.stamp[0] == 0.0


def _reach(weight: float, target: np.ndarray, T: int = 20):
    iam = arm_node(())
    state, nu = iam.state, iam.nu
    nodes = []
    for _ in range(T + 1):
        costs = crocopy.CostModelSum(state, nu)
        costs.addCost("x", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, state.zero(), nu)), 1e-2)
        costs.addCost("u", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, nu)), 1e-3)
        fid = state.pinocchio.getFrameId("j2s6s200_end_effector")
        goal = crocopy.ResidualModelFrameTranslation(state, fid, target, nu)
        costs.addCost("goal", crocopy.CostModelResidual(state, goal), weight)
        dam = crocopy.DifferentialActionModelFreeFwdDynamics(state, crocopy.ActuationModelFull(state), costs)
        nodes.append(crocopy.IntegratedActionModelEuler(dam, 0.02))
    return crocopy.ShootingProblem(state.zero(), nodes[:-1], nodes[-1])


def test_a_warm_started_solve_after_a_mutation_reads_the_new_parameters():
    """The same solver solving again from its own solution (its nodes stamped at exactly that point) after a weight
    and a reference changed through their setters: a fresh problem's solve from there, iterations and cost."""
    problem = _reach(10.0, np.array([0.4, 0.2, 0.5]))
    solver = crocopy.SolverFDDP(problem)
    solver.solve([], [], 6)
    xs, us = [x.copy() for x in solver.xs], [u.copy() for u in solver.us]
    target = np.array([0.3, -0.1, 0.6])
    for model in [*problem.runningModels, problem.terminalModel]:
        model.differential.costs.costs["goal"].weight = 30.0
        model.differential.costs.costs["goal"].cost.residual.reference = target
    solver.solve(xs, us, 4)
    fresh = crocopy.SolverFDDP(_reach(30.0, target))
    fresh.solve(xs, us, 4)
    assert (solver.iter, solver.cost) == (fresh.iter, fresh.cost)
    for a, b in zip(solver.xs, fresh.xs):
        assert np.array_equal(a, b)


def test_a_selection_reused_by_the_next_solve_spends_the_stamps():
    """Every node stamped at exactly the next solve's warm start: the next solve's selection (which reuses the
    problem's, :class:`crocopy.solvers.compiled_nodes.Selection`) spends the stamps, so that a value the Python path
    or an in-place change left in between is never taken for current."""
    from crocopy.solvers import compiled_nodes

    problem = _reach(10.0, np.array([0.4, 0.2, 0.5]))
    solver = crocopy.SolverFDDP(problem)
    solver.solve([], [], 6)
    xs, us = solver.xs, solver.us
    selection = compiled_nodes._SELECTIONS[problem]
    evaluators = [e for e, _ in selection.evaluators]
    assert len(evaluators) == problem.T + 1
    for t, e in enumerate(evaluators):
        e.calc(xs[t], us[t] if t < problem.T else None)
    assert all(e.stamp[0] == 1.0 for e in evaluators)
    compiled_nodes.select(solver)
    assert compiled_nodes._SELECTIONS[problem] is selection  # reused
    assert not any(e.stamp[0] for e in evaluators)
