"""Compiled Runge-Kutta nodes (RK2, RK3, RK4) and nodes with a control parametrization (Euler and Runge-Kutta with
``PolyOne``, ``PolyTwoRK``) equal the Python node, finite differences and the Python solves.

Factory: the free-dynamics nodes of ``test_euler_node.py`` (five robots, every compiled residual kind, the
activations it cycles through) and the contact nodes of ``test_contacts_1d2d.py`` (1D to 6D contacts, with and
without gains), each under every Runge-Kutta order, running and terminal; three robots under every integrator with
a polynomial control parametrization.
"""

from __future__ import annotations

import numpy as np
import pytest
from node_checks import check_finite_differences, compare_with_python_node, failed_solve, make_solver
from test_contacts_1d2d import CASES, IDS, make_dam
from test_euler_node import KINDS, ROBOTS, node, point

import crocopy
from crocopy.models.rbd.rk_node import RKNode
from crocopy.problems import registry
from crocopy.solvers import compiled_nodes

pytestmark = pytest.mark.skipif(not crocopy.kernels_enabled(), reason="compiled nodes need numba")

ORDERS = (crocopy.RKType.two, crocopy.RKType.three, crocopy.RKType.four)
GOAL = "goal"


def rk(dam, order=crocopy.RKType.four, dt: float = 0.01):
    return crocopy.IntegratedActionModelRK(dam, order, dt)


@pytest.mark.parametrize("order", ORDERS, ids=["rk2", "rk3", "rk4"])
@pytest.mark.parametrize("robot", ROBOTS)
@pytest.mark.parametrize("terminal", [False, True])
def test_every_residual_kind_under_every_order_matches_the_python_node(robot, order, terminal):
    iam, state = node(robot, KINDS)
    model = rk(iam.differential, order)
    assert type(model._compiled_node(model.createData(), terminal, {})) is RKNode
    x, u = point(state, model.nu, 0)
    compare_with_python_node(model, x, u, terminal, rtol=1e-8, atol=1e-9, cost_rel=1e-10)


@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_contact_nodes_under_rk4_match_the_python_node(case):
    dam = make_dam(*case)
    model = rk(dam)
    rng = np.random.default_rng(7)
    np.random.seed(7)
    x = dam.state.rand()
    x[dam.state.nq:] = 0.5 * rng.standard_normal(dam.state.nv)
    compare_with_python_node(model, x, 0.5 * rng.standard_normal(model.nu), False, rtol=1e-7, atol=1e-7,
                             cost_rel=1e-9)


@pytest.mark.parametrize("order", ORDERS, ids=["rk2", "rk3", "rk4"])
@pytest.mark.parametrize("robot", ["iris", "kinova"])
def test_derivatives_match_finite_differences(robot, order):
    """``Fx, Fu, Lx, Lu`` of the compiled node against central differences of its own ``calc``."""
    iam, state = node(robot, KINDS, seed=5)
    model = rk(iam.differential, order)
    x, u = point(state, model.nu, 5)
    check_finite_differences(model, state, x, u, h=1e-6, atol=1e-5, roundoff=1e-10)


def test_contact_derivatives_match_finite_differences():
    dam = make_dam(*CASES[4], seed=1)
    rng = np.random.default_rng(8)
    np.random.seed(8)
    x = dam.state.rand()
    x[dam.state.nq:] = 0.5 * rng.standard_normal(dam.state.nv)
    check_finite_differences(rk(dam), dam.state, x, 0.5 * rng.standard_normal(dam.nu), h=1e-6, atol=1e-5,
                             roundoff=1e-10)


def constrained_kinova(equality: bool):
    """``(state, nu, dam)``: a kinova free-dynamics model with control bounds and a frame box as constraints (and a
    control equality)."""
    iam, state = node("kinova", ("state", "control"))
    dam = iam.differential
    nu = dam.nu
    manager = crocopy.ConstraintModelManager(state, nu)
    manager.addConstraint("u", crocopy.ConstraintModelResidual(
        state, crocopy.ResidualModelControl(state, nu), -np.ones(nu), np.ones(nu)))
    tip = state.pinocchio.nframes - 1
    manager.addConstraint("p", crocopy.ConstraintModelResidual(
        state, crocopy.ResidualModelFrameTranslation(state, tip, np.array([0.1, 0.2, 0.3]), nu),
        -np.ones(3), np.ones(3)))
    if equality:
        manager.addConstraint("eq", crocopy.ConstraintModelResidual(
            state, crocopy.ResidualModelControl(state, 0.1 * np.ones(nu)), False))
    return state, nu, crocopy.DifferentialActionModelFreeFwdDynamics(state, dam.actuation, dam.costs, manager)


def test_the_first_stage_gives_the_constraint_rows():
    """A node with control bounds and a frame translation as constraints: ``g``, ``Gx``, ``Gu`` of the compiled
    node are the Python node's (those of its first stage)."""
    state, nu, dam = constrained_kinova(equality=False)
    model = rk(dam)
    x, u = point(state, nu, 2)
    fast, slow = model.createData(), model.createData()
    model._compiled_node(fast, False, {}).calcDiff(x, u, False)
    model.calc(slow, x, u)
    model.calcDiff(slow, x, u)
    for name in ("g", "Gx", "Gu"):
        np.testing.assert_allclose(getattr(fast, name), getattr(slow, name), rtol=1e-9, atol=1e-12, err_msg=name)


def test_a_python_write_between_calc_and_calc_diff_is_not_taken_for_the_compiled_values():
    """The model's own ``calc`` at another point after a compiled ``calc``: the compiled ``calcDiff`` at the first
    point evaluates its stages again (the Python path spent the node's stamp) and equals the Python node there."""
    iam, state = node("anymal", ("state", "control", "translation"))
    model = rk(iam.differential)
    data = model.createData()
    evaluator = model._compiled_node(data, False, {})
    x, u = point(state, model.nu, 1)
    y, w = point(state, model.nu, 2)
    evaluator.calc(x, u)
    model.calc(data, y, w)
    evaluator.calcDiff(x, u, True)
    slow = model.createData()
    model.calc(slow, x, u)
    model.calcDiff(slow, x, u)
    for name in ("Fx", "Fu", "Lx", "Lxx", "Luu"):
        np.testing.assert_allclose(getattr(data, name), getattr(slow, name), rtol=1e-9, atol=1e-10, err_msg=name)


def problem_of(order=crocopy.RKType.four, dt: float = 0.01, T: int = 12):
    """crocopy's arm reach (``crocopy solve arm``), its first ``T`` nodes' differential models under Runge-Kutta
    integrators of time step ``dt``."""
    problem, _, _ = registry.build("arm")
    running = [rk(m.differential, order, dt) for m in problem.runningModels[:T]]
    return crocopy.ShootingProblem(problem.x0, running, rk(problem.terminalModel.differential, order, 0.0))


@pytest.mark.parametrize("solver", ["SolverFDDP", "SolverBoxFDDP"])
@pytest.mark.parametrize("order", ORDERS, ids=["rk2", "rk3", "rk4"])
def test_solves_with_compiled_rk_nodes_match_the_python_nodes(solver, order):
    outcomes = []
    for compiled in (True, False):
        problem = problem_of(order)
        s = make_solver(solver, problem, compiled)
        if compiled:
            assert all(entry.compiled for entry in crocopy.compiled_coverage(problem))
            nodes = compiled_nodes.select(s)
            assert all(getattr(calc, "__self__", None) is not None for calc in nodes.calcs)
        s.solve([], [], 8)
        assert np.abs(s.xs[-1]).max() < 1e3
        outcomes.append((s.iter, s.cost, [x.copy() for x in s.xs]))
    assert outcomes[0][0] == outcomes[1][0] and outcomes[0][0] > 1
    assert outcomes[0][1] == pytest.approx(outcomes[1][1], rel=1e-9)
    np.testing.assert_allclose(outcomes[0][2][-1], outcomes[1][2][-1], rtol=1e-7, atol=1e-9)


def test_an_sqp_solve_with_compiled_rk_nodes_converges_as_with_the_python_nodes():
    """SolverSQP (the trial points on the Python loop over the compiled nodes) on the whole arm reach under RK4:
    converged, the same iterations and cost."""
    outcomes = []
    for compiled in (True, False):
        solver = make_solver("SolverSQP", problem_of(T=100), compiled)
        assert solver.solve([], [], 40)
        outcomes.append((solver.iter, solver.cost))
    assert outcomes[0][0] == outcomes[1][0]
    assert outcomes[0][1] == pytest.approx(outcomes[1][1], rel=1e-9)


def test_the_datas_after_a_solve_are_those_of_the_python_calc():
    """``fill``: after a compiled solve, the nested datas hold what the model's ``calc`` leaves at the solution."""
    problem = problem_of()
    solver = crocopy.SolverFDDP(problem)
    solver.solve([], [], 5)
    for model, data, x, u in zip(problem.runningModels, problem.runningDatas, solver.xs, solver.us):
        other = model.createData()
        model.calc(other, x, u)
        assert data.cost == pytest.approx(other.cost, rel=1e-12)
        for i in range(model.ni):
            np.testing.assert_allclose(data.differential[i].xout, other.differential[i].xout, rtol=1e-12, atol=1e-12)
            np.testing.assert_allclose(data.ki[i], other.ki[i], rtol=1e-12, atol=1e-12)


def test_parameters_set_between_solves_give_a_fresh_builds_answer():
    """The time step, a residual's reference and a cost weight assigned between two solves: the second solve takes
    the iterations and cost of a problem built with those values (One answer)."""
    problem = problem_of()
    solver = crocopy.SolverFDDP(problem)
    solver.solve([], [], 3)
    model = problem.runningModels[0]
    model.dt = 0.03
    costs = model.differential.costs
    costs.costs[GOAL].cost.residual.reference = np.array([0.2, -0.1, 0.4])
    costs.costs["state"].weight = 2.5
    solver.solve([], [], 8)
    fresh = problem_of()
    fresh_model = fresh.runningModels[0]
    fresh_model.dt = 0.03
    fresh_costs = fresh_model.differential.costs
    fresh_costs.costs[GOAL].cost.residual.reference = np.array([0.2, -0.1, 0.4])
    fresh_costs.costs["state"].weight = 2.5
    other = make_solver("SolverFDDP", fresh, compiled=False)
    other.solve([], [], 8)
    assert solver.iter == other.iter
    assert solver.cost == pytest.approx(other.cost, rel=1e-9)


def test_nodes_that_keep_the_python_path():
    iam, state = node("kinova", ("state", "control"))
    dam = iam.differential

    class UserRK(crocopy.IntegratedActionModelRK):
        pass

    memo: dict = {}
    user = UserRK(dam, crocopy.RKType.four, 0.01)
    assert user._compiled_node(user.createData(), False, memo) is None
    assert "integrator UserRK" in memo["why not compiled"]

    class UserControl(crocopy.ControlParametrizationModelPolyOne):
        pass

    poly = crocopy.IntegratedActionModelRK(dam, UserControl(dam.nu), crocopy.RKType.four, 0.01)
    assert poly._compiled_node(poly.createData(), False, memo) is None
    assert memo["why not compiled"] == "control parametrization UserControl"

    class PythonResidual(crocopy.ResidualModelAbstract):
        def __init__(self):
            super().__init__(state, 1, dam.nu, True, True, False)

        def calc(self, data, x, u=None):
            data.r[0] = x[0]

        def calcDiff(self, data, x, u=None):
            data.Rx[0, 0] = 1.0

    costs = crocopy.CostModelSum(state, dam.nu)
    costs.addCost("user", crocopy.CostModelResidual(state, PythonResidual()), 1.0)
    model = rk(crocopy.DifferentialActionModelFreeFwdDynamics(state, dam.actuation, costs))
    assert model._compiled_node(model.createData(), False, memo) is None
    assert memo["why not compiled"] == "user Python residual in a Runge-Kutta node"
    euler = crocopy.IntegratedActionModelEuler(model.differential, 0.01)
    assert euler._compiled_node(euler.createData(), False, {}) is not None


CONTROLLED = (
    ("rk2-polyone", lambda dam: crocopy.IntegratedActionModelRK(
        dam, crocopy.ControlParametrizationModelPolyOne(dam.nu), crocopy.RKType.two, 0.01)),
    ("rk4-polyone", lambda dam: crocopy.IntegratedActionModelRK(
        dam, crocopy.ControlParametrizationModelPolyOne(dam.nu), crocopy.RKType.four, 0.01)),
    ("rk3-polytwo", lambda dam: crocopy.IntegratedActionModelRK(
        dam, crocopy.ControlParametrizationModelPolyTwoRK(dam.nu, crocopy.RKType.three), crocopy.RKType.three, 0.01)),
    ("rk4-polytwo", lambda dam: crocopy.IntegratedActionModelRK(
        dam, crocopy.ControlParametrizationModelPolyTwoRK(dam.nu, crocopy.RKType.four), crocopy.RKType.four, 0.01)),
    ("euler-polyone", lambda dam: crocopy.IntegratedActionModelEuler(
        dam, crocopy.ControlParametrizationModelPolyOne(dam.nu), 0.01)),
    ("euler-polytwo", lambda dam: crocopy.IntegratedActionModelEuler(
        dam, crocopy.ControlParametrizationModelPolyTwoRK(dam.nu, crocopy.RKType.four), 0.01)),
)
"""Integrators with crocopy's polynomial control parametrizations (stage ``i`` reads ``w(cᵢ, u)``)."""


@pytest.mark.parametrize("make", [m for _, m in CONTROLLED], ids=[n for n, _ in CONTROLLED])
@pytest.mark.parametrize("robot", ["kinova", "anymal", "iris"])
@pytest.mark.parametrize("terminal", [False, True])
def test_control_parametrizations_match_the_python_node(robot, make, terminal):
    iam, state = node(robot, KINDS)
    model = make(iam.differential)
    assert model.nu > iam.nu
    assert model._compiled_node(model.createData(), terminal, {}) is not None
    x, u = point(state, model.nu, 0)
    compare_with_python_node(model, x, u, terminal, rtol=1e-8, atol=1e-9, cost_rel=1e-10)


@pytest.mark.parametrize("make", [m for _, m in CONTROLLED], ids=[n for n, _ in CONTROLLED])
def test_control_parametrization_derivatives_match_finite_differences(make):
    iam, state = node("iris", KINDS, seed=5)
    model = make(iam.differential)
    x, u = point(state, model.nu, 5)
    check_finite_differences(model, state, x, u, h=1e-6, atol=1e-5, roundoff=1e-10)


@pytest.mark.parametrize("name", ["euler-polyone", "rk4-polytwo"])
def test_solves_with_control_parametrizations_match_the_python_nodes(name):
    make = dict(CONTROLLED)[name]
    outcomes = []
    for compiled in (True, False):
        arm, _, _ = registry.build("arm")
        running = [make(m.differential) for m in arm.runningModels[:12]]
        problem = crocopy.ShootingProblem(arm.x0, running, make(arm.terminalModel.differential))
        solver = make_solver("SolverFDDP", problem, compiled)
        if compiled:
            assert all(entry.compiled for entry in crocopy.compiled_coverage(problem))
        solver.solve([], [], 8)
        outcomes.append((solver.iter, solver.cost))
    assert outcomes[0][0] == outcomes[1][0] and outcomes[0][0] > 1
    assert outcomes[0][1] == pytest.approx(outcomes[1][1], rel=1e-9)


@pytest.mark.parametrize("make", [m for _, m in CONTROLLED], ids=[n for n, _ in CONTROLLED])
def test_constraint_rows_with_a_control_parametrization_match_the_python_node(make):
    """Control bounds, an equality and a frame box as constraints: the node's ``g, Gx, Gu, h, Hx, Hu`` are the Python
    node's (the first stage's, ``Gu``, ``Hu`` mapped to ``u``)."""
    state, nu, dam = constrained_kinova(equality=True)
    model = make(dam)
    assert model.nh > 0 and model.ng > 0
    x, u = point(state, model.nu, 2)
    fast, slow = model.createData(), model.createData()
    model._compiled_node(fast, False, {}).calcDiff(x, u, False)
    model.calc(slow, x, u)
    model.calcDiff(slow, x, u)
    for name in ("g", "Gx", "Gu", "h", "Hx", "Hu", "Fu", "Luu"):
        np.testing.assert_allclose(getattr(fast, name), getattr(slow, name), rtol=1e-9, atol=1e-12, err_msg=name)


@pytest.mark.parametrize("make", [m for _, m in CONTROLLED], ids=[n for n, _ in CONTROLLED])
def test_a_second_offer_refreshes_the_same_stage_nodes(make):
    """A node offered again (a new selection) keeps its stage datas and their Euler nodes, controls sized by ``w``."""
    iam, _ = node("kinova", ("state", "control"))
    model = make(iam.differential)
    data = model.createData()
    first = model._compiled_node(data, False, {})
    stages = list(first.stages)
    again = model._compiled_node(data, False, {})
    assert again is first and again.refreshes == 2
    assert all(a is b for a, b in zip(stages, again.stages))


@pytest.mark.parametrize("compiled", [True, False], ids=["compiled", "python"])
def test_a_diverging_rk_solve_returns_false_with_finite_iterates(compiled):
    """Huge initial velocities and a long step: the solve fails, says why, and keeps a finite iterate (compiled or
    not; where states overflow, the two paths may fail at different iterations)."""
    problem = problem_of(crocopy.RKType.four, 0.5)
    nq = problem.runningModels[0].state.nq
    problem.x0 = np.concatenate([problem.x0[:nq], 50.0 * np.ones(problem.x0.shape[0] - nq)])
    solved, iters, reason = failed_solve(problem, [], [], compiled, 20)
    assert not solved and reason and iters >= 1


def test_euler_running_nodes_with_a_runge_kutta_terminal_node():
    """The arm's Euler horizon ends on an RK4 terminal node (not of the horizon's class: its own calls): the same
    iterations and cost as the Python nodes."""
    outcomes = []
    for compiled in (True, False):
        arm, _, _ = registry.build("arm")
        problem = crocopy.ShootingProblem(arm.x0, list(arm.runningModels), rk(arm.terminalModel.differential, dt=0.0))
        solver = make_solver("SolverFDDP", problem, compiled)
        if compiled:
            nodes = compiled_nodes.select(solver)
            assert nodes.horizon is not None and type(nodes.terminal) is RKNode
        solver.solve([], [], 30)
        outcomes.append((solver.iter, solver.cost))
    assert outcomes[0][0] == outcomes[1][0] and outcomes[0][0] > 1
    assert outcomes[0][1] == pytest.approx(outcomes[1][1], rel=1e-9)
