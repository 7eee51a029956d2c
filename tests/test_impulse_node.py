"""Compiled impulse nodes (``ActionModelImpulseFwdDynamics``, :mod:`crocopy.models.rbd.impulse_node`) against the
Python node, finite differences and whole solves, and the nodes they decline.

Factories cross robots (ANYmal with four or two 3D impulses, Talos legs with two 6D feet or a 3D and a 6D one),
the impulses' reference frames (LOCAL, LOCAL_WORLD_ALIGNED, WORLD), the restitution coefficient, the damping, the
armature and costs built with or without control, with every residual kind an impulse node compiles (state, frame
translation, placement, rotation, velocity, centre of mass).  Tolerances: as in ``tests/test_contact_node.py`` (the
Python state residual's ``dDifference`` loses up to 1e-7 for small angles).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from node_checks import check_finite_differences, compare_with_python_node, make_solver
from robots import load
from test_residual_numba import user_residuals

import crocopy
from crocopy.models.rbd.impulse_node import ImpulseNode
from crocopy.not_compiled import REASON
from crocopy.problems import registry
from crocopy.solvers import compiled_nodes

pytestmark = pytest.mark.skipif(not crocopy.kernels_enabled(), reason="compiled nodes need numba")

FEET = {"anymal": ("LF_FOOT", "RF_FOOT", "LH_FOOT", "RH_FOOT"), "talos_legs": ("left_sole_link", "right_sole_link")}
LOCAL, LWA, WORLD = pin.LOCAL, pin.LOCAL_WORLD_ALIGNED, pin.WORLD
CASES = {
    "anymal-lwa": ("anymal", "3333", LWA, 0.0, 0.0),
    "anymal-local-restitution": ("anymal", "3333", LOCAL, 0.4, 0.0),
    "anymal-two-feet-world-damped": ("anymal", "33", WORLD, 0.0, 1e-3),
    "talos-6d": ("talos_legs", "66", LOCAL, 0.0, 0.0),
    "talos-6d-lwa-restitution": ("talos_legs", "66", LWA, 0.7, 0.0),
    "talos-3d-6d-damped": ("talos_legs", "36", LWA, 0.2, 1e-2),
}


def impulse_model(case: str, armature: bool = False, costs_nu: int = 0, seed: int = 0):
    """The impulse node of ``case`` (robot, impulse sizes, reference frame, ``r_coeff``, damping) with state, swing
    foot, placement, rotation, velocity, centre-of-mass, centroidal momentum and centre-of-mass velocity jump costs
    and, on the first foot's impulse, a force and a friction cone (3D) or a wrench cone and a centre of pressure (6D)
    (built with ``costs_nu`` controls)."""
    robot, kinds, reference, r_coeff, damping = CASES[case]
    rng = np.random.default_rng(seed)
    model = load(robot)
    state = crocopy.StateMultibody(model)
    impulses = crocopy.ImpulseModelMultiple(state)
    for name, kind in zip(FEET[robot], kinds):
        cls = crocopy.ImpulseModel3D if kind == "3" else crocopy.ImpulseModel6D
        impulses.addImpulse(name, cls(state, model.getFrameId(name), reference))
    costs = crocopy.CostModelSum(state, costs_nu)
    nu = costs_nu
    xref = state.integrate(state.zero(), rng.uniform(-0.2, 0.2, state.ndx))
    weights = np.concatenate([np.full(6, 10.0), np.ones(state.nv - 6), np.full(state.nv, 0.1)])
    costs.addCost("x", crocopy.CostModelResidual(
        state, crocopy.ActivationModelWeightedQuad(weights), crocopy.ResidualModelState(state, xref, nu)), 1e-1)
    foot = model.getFrameId(FEET[robot][-1])
    target = pin.SE3(pin.exp3(rng.uniform(-0.3, 0.3, 3)), rng.uniform(-0.3, 0.3, 3))
    costs.addCost("p", crocopy.CostModelResidual(
        state, crocopy.ResidualModelFrameTranslation(state, foot, target.translation, nu)), 1e2)
    costs.addCost("M", crocopy.CostModelResidual(state, crocopy.ResidualModelFramePlacement(state, foot, target, nu)),
                  1e1)
    costs.addCost("R", crocopy.CostModelResidual(
        state, crocopy.ResidualModelFrameRotation(state, foot, target.rotation, nu)), 3.0)
    bounds = crocopy.ActivationBounds(-0.1 * np.ones(6), 0.1 * np.ones(6))
    costs.addCost("v", crocopy.CostModelResidual(
        state, crocopy.ActivationModelQuadraticBarrier(bounds),
        crocopy.ResidualModelFrameVelocity(state, foot, pin.Motion(rng.uniform(-1, 1, 6)), LWA, nu)), 2.0)
    costs.addCost("com", crocopy.CostModelResidual(
        state, crocopy.ResidualModelCoMPosition(state, rng.uniform(-0.2, 0.2, 3), nu)), 5.0)
    costs.addCost("h", crocopy.CostModelResidual(
        state, crocopy.ResidualModelCentroidalMomentum(state, rng.uniform(-1.0, 1.0, 6), nu)), 0.7)
    first = model.getFrameId(FEET[robot][0])
    nc = 3 if kinds[0] == "3" else 6
    force = crocopy.ResidualModelContactForce(state, first, pin.Force(rng.uniform(-5.0, 5.0, 6)), nc, nu)
    costs.addCost("f", crocopy.CostModelResidual(state, force), 1e-3)
    if nc == 3:
        cone = crocopy.ResidualModelContactFrictionCone(state, first, crocopy.FrictionCone(np.eye(3), 0.7), nu)
    else:
        cone = crocopy.ResidualModelContactWrenchCone(state, first, crocopy.WrenchCone(np.eye(3), 0.7,
                                                                                          np.array([0.1, 0.05])), nu)
        costs.addCost("cop", crocopy.CostModelResidual(state, crocopy.ResidualModelContactCoPPosition(
            state, first, crocopy.CoPSupport(np.eye(3), np.array([0.2, 0.1])), nu)), 1e-2)
    costs.addCost("cone", crocopy.CostModelResidual(state, cone), 1e-2)
    if nu == 0:  # the residual has no control
        costs.addCost("jump", crocopy.CostModelResidual(state, crocopy.ResidualModelImpulseCoM(state)), 0.5)
    model_ = crocopy.ActionModelImpulseFwdDynamics(state, impulses, costs, r_coeff, damping, True)
    if armature:
        model_.armature = rng.uniform(0.0, 0.1, state.nv)
    return model_


def random_x(model, seed: int = 1) -> np.ndarray:
    rng = np.random.default_rng(seed)
    q = pin.integrate(model.state.pinocchio, pin.neutral(model.state.pinocchio), rng.uniform(-0.4, 0.4, model.state.nv))
    return np.concatenate([q, rng.uniform(-1.0, 1.0, model.state.nv)])


@pytest.mark.parametrize("case", list(CASES))
def test_the_compiled_impulse_node_is_the_python_node(case):
    model = impulse_model(case)
    for seed in (1, 2):
        compare_with_python_node(model, random_x(model, seed), np.zeros(0), False, 1e-7, 1e-9, 1e-10)


@pytest.mark.parametrize(("case", "costs_nu", "terminal"), [("anymal-lwa", 12, False), ("talos-6d", 0, True)])
def test_armature_costs_with_controls_and_the_terminal_node(case, costs_nu, terminal):
    model = impulse_model(case, armature=True, costs_nu=costs_nu)
    compare_with_python_node(model, random_x(model, 3), np.zeros(0), terminal, 1e-7, 1e-9, 1e-10)


@pytest.mark.parametrize("case", ["anymal-local-restitution", "talos-3d-6d-damped"])
def test_the_derivatives_are_those_of_the_compiled_values(case):
    model = impulse_model(case, armature=True)
    check_finite_differences(model, model.state, random_x(model, 4), np.zeros(0), 1e-6, 1e-5, 1e-9)


def test_without_impulses_the_velocity_passes_through():
    model = impulse_model("anymal-lwa")
    for name in FEET["anymal"]:
        model.impulses.changeImpulseStatus(name, False)
    problem = crocopy.ShootingProblem(model.state.zero(), [model], model)
    assert "without its active impulse" in crocopy.compiled_coverage(problem)[0].reason  # the force and cone costs
    for name in ("f", "cone"):
        model.costs.changeCostStatus(name, False)
    x = random_x(model)
    compare_with_python_node(model, x, np.zeros(0), False, 1e-7, 1e-9, 1e-10)
    data = model.createData()
    model._compiled_node(data, False, {}).calcDiff(x, np.zeros(0), False)
    np.testing.assert_array_equal(data.xnext, x)


def test_the_node_follows_its_parameters_between_solves():
    """``r_coeff``, the damping, the armature and a reference are read again at every offer."""
    model = impulse_model("anymal-lwa")
    data, x = model.createData(), random_x(model)
    first = model._compiled_node(data, False, {})
    model.r_coeff = 0.5
    model.JMinvJt_damping = 1e-2
    model.armature = np.full(model.state.nv, 0.05)
    model.costs.costs["p"].cost.residual.reference = np.array([0.1, 0.2, 0.3])
    evaluator = model._compiled_node(data, False, {})
    assert evaluator is first
    evaluator.calcDiff(x, np.zeros(0), False)
    slow = model.createData()
    model.calc(slow, x, np.zeros(0))
    model.calcDiff(slow, x, np.zeros(0))
    assert data.cost == pytest.approx(slow.cost, rel=1e-9)
    np.testing.assert_allclose(data.Fx, slow.Fx, rtol=1e-7, atol=1e-9 * np.abs(slow.Fx).max())


def _declined(model) -> str | None:
    memo: dict = {}
    assert model._compiled_node(model.createData(), False, memo) is None
    return memo[REASON]


def test_the_nodes_it_declines_say_why():
    model = impulse_model("anymal-lwa")
    state = model.state
    # two impulses on one joint, without damping: the Python model's least-squares path
    foot = state.pinocchio.getFrameId("LF_FOOT")
    model.impulses.addImpulse("again", crocopy.ImpulseModel3D(state, foot, LOCAL))
    assert _declined(model) == "redundant impulses"
    model.JMinvJt_damping = 1e-3
    assert model._compiled_node(model.createData(), False, {}) is not None
    costs = crocopy.CostModelSum(state, 0)
    costs.addCost("user", crocopy.CostModelResidual(state, user_residuals(state, foot, 0)["com height"]), 1.0)
    other = crocopy.ActionModelImpulseFwdDynamics(state, model.impulses, costs, inv_damping=1e-3)
    assert _declined(other) == "user Python subclass: residual CoMHeight in an impulse node"
    manager = crocopy.ConstraintModelManager(state, 0)
    constrained = crocopy.ActionModelImpulseFwdDynamics(state, model.impulses, model.costs, manager, inv_damping=1e-3)
    assert constrained._compiled_node(constrained.createData(), False, {}) is not None  # no rows: compiles
    manager.addConstraint("user", crocopy.ConstraintModelResidual(state, user_residuals(state, foot, 0)["com height"]))
    constrained = crocopy.ActionModelImpulseFwdDynamics(state, model.impulses, model.costs, manager, inv_damping=1e-3)
    assert _declined(constrained) == "user Python subclass: constraint residual CoMHeight in an impulse node"

    class UserImpulse(crocopy.ActionModelImpulseFwdDynamics):
        pass

    user = UserImpulse(state, model.impulses, model.costs)
    assert _declined(user) == "user Python subclass: action UserImpulse"


@pytest.mark.parametrize("case", ["anymal-lwa", "anymal-local-restitution", "talos-6d-lwa-restitution"])
def test_force_and_com_jump_constraints_match_the_python_node(case):
    """The centre-of-mass velocity jump as an equality, the first foot's impulse and its friction or wrench cone as
    inequalities: their Jacobians follow the impulses' derivatives (the constraint table's late Jacobians)."""
    model = impulse_model(case)
    state = model.state
    foot = state.pinocchio.getFrameId(FEET[CASES[case][0]][0])
    six = CASES[case][1][0] == "6"
    manager = crocopy.ConstraintModelManager(state, 0)
    manager.addConstraint("jump", crocopy.ConstraintModelResidual(state, crocopy.ResidualModelImpulseCoM(state)))
    force = crocopy.ResidualModelContactForce(state, foot, pin.Force(np.arange(6.0)), 6 if six else 3, 0)
    manager.addConstraint("f", crocopy.ConstraintModelResidual(state, force, -np.ones(force.nr), np.ones(force.nr)))
    cone = (crocopy.ResidualModelContactWrenchCone(state, foot, crocopy.WrenchCone(np.eye(3), 0.7,
                                                                                  np.array([0.1, 0.05])), 0)
            if six else crocopy.ResidualModelContactFrictionCone(state, foot, crocopy.FrictionCone(np.eye(3), 0.7), 0))
    manager.addConstraint("cone", crocopy.ConstraintModelResidual(state, cone, np.full(cone.nr, -np.inf),
                                                                  np.zeros(cone.nr)))
    constrained = crocopy.ActionModelImpulseFwdDynamics(state, model.impulses, model.costs, manager,
                                                        model.r_coeff, model.JMinvJt_damping, True)
    x = random_x(constrained)
    fast, slow = constrained.createData(), constrained.createData()
    constrained._compiled_node(fast, False, {}).calcDiff(x, None, False)
    constrained.calc(slow, x)
    constrained.calcDiff(slow, x)
    assert constrained.ng > 0 and constrained.nh == 3
    for name in ("g", "Gx", "h", "Hx", "Fx", "Lx"):
        a, b = getattr(fast, name), getattr(slow, name)
        np.testing.assert_allclose(a, b, rtol=1e-8, atol=1e-8 * max(1.0, np.abs(b).max(initial=0.0)), err_msg=name)


def test_impulse_nodes_stay_out_of_the_euler_horizon():
    problem, _, _ = registry.build("jump")
    nodes = compiled_nodes.select(crocopy.SolverFDDP(problem))
    impulses = [t for t, m in enumerate(problem.runningModels) if isinstance(m, crocopy.ActionModelImpulseFwdDynamics)]
    assert impulses and nodes.horizon is not None
    for t in impulses:
        assert isinstance(nodes.calcs[t].__self__, ImpulseNode) and not nodes.in_horizon[t]
    assert sum(nodes.in_horizon) == problem.T - len(impulses)
    assert all(c.compiled for c in crocopy.compiled_coverage(problem))


def _same_solves(name: str, solver: str, maxiter: int) -> None:
    """Same iterations, costs to 1e-9 and states to 1e-6 (the compiled Euler nodes alone already move a gait's
    states by some 1e-7 from the Python path's: round-off, amplified over the solve)."""
    outcomes = []
    for compiled in (True, False):
        problem, xs, us = registry.build(name)
        s = make_solver(solver, problem, compiled)
        s.solve(xs, us, maxiter)
        outcomes.append((s.iter, s.cost, [x.copy() for x in s.xs]))
    assert outcomes[0][0] == outcomes[1][0] and outcomes[0][0] > 1
    assert outcomes[0][1] == pytest.approx(outcomes[1][1], rel=1e-9)
    for a, b in zip(outcomes[0][2], outcomes[1][2]):
        np.testing.assert_allclose(a, b, rtol=1e-6, atol=1e-6)


@pytest.mark.parametrize("solver", ["SolverFDDP", "SolverBoxFDDP"])
def test_jump_solves_with_and_without_compiled_nodes_match(solver):
    _same_solves("jump", solver, 15)


@pytest.mark.slow
@pytest.mark.parametrize(("name", "solver"), [("trot", "SolverFDDP"), ("hop", "SolverBoxFDDP"),
                                              ("biped-walk", "SolverDDP")])
def test_gait_solves_with_and_without_compiled_nodes_match(name, solver):
    _same_solves(name, solver, 30)


def test_a_mutated_impulse_node_gives_the_python_answer():
    """After a compiled solve, one impulse switched off and ``r_coeff`` changed: the next solve's compiled impulse
    node is that of the mutated model (same iterations and cost as the Python path)."""
    outcomes = []
    for compiled in (True, False):
        problem, xs, us = registry.build("jump")
        make_solver("SolverFDDP", problem, compiled).solve(xs, us, 2)
        t = next(t for t, m in enumerate(problem.runningModels) if isinstance(m, crocopy.ActionModelImpulseFwdDynamics))
        model = problem.runningModels[t]
        model.impulses.changeImpulseStatus(next(iter(model.impulses.impulses)), False)
        model.r_coeff = 0.3
        s = make_solver("SolverFDDP", problem, compiled)
        if compiled:
            assert isinstance(compiled_nodes.select(s).calcs[t].__self__, ImpulseNode)
        s.solve(xs, us, 10)
        outcomes.append((s.iter, s.cost))
    assert outcomes[0][0] == outcomes[1][0]
    assert outcomes[0][1] == pytest.approx(outcomes[1][1], rel=1e-9)
