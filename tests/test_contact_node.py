"""Compiled Euler nodes of contact forward dynamics against the Python node and finite differences.

Factories cross robots (ANYmal with four or two 3D contacts in LOCAL_WORLD_ALIGNED or LOCAL coordinates, Talos
legs with two 6D feet), Baumgarte gains, armature and damping with every force-aware residual (friction and
wrench cones, centre of mass) and the frame and state residuals.  Tolerances: the Python node's state residual
uses Pinocchio's ``dDifference``, whose ``Jlog6`` loses up to 1e-7 for small angles (see
:mod:`crocopy.models.rbd.lie_kernel`), so the comparisons are to 1e-7 relative.
"""

from __future__ import annotations

import re

import numpy as np
import pinocchio as pin
import pytest
from node_checks import (
    check_finite_differences,
    check_new_evaluator,
    compare_with_python_node,
    failed_solve,
    make_solver,
)
from robots import load

import crocopy
from crocopy.problems import registry
from crocopy.solvers import compiled_nodes

pytestmark = pytest.mark.skipif(not crocopy.kernels_enabled(), reason="compiled nodes need numba")

FEET = {"anymal": ("LF_FOOT", "RF_FOOT", "LH_FOOT", "RH_FOOT"), "talos_legs": ("left_sole_link", "right_sole_link")}
CASES = {
    "anymal-lwa": ("anymal", 4, pin.LOCAL_WORLD_ALIGNED, (0.0, 50.0)),
    "anymal-local-gains": ("anymal", 4, pin.LOCAL, (20.0, 10.0)),
    "anymal-two-feet": ("anymal", 2, pin.LOCAL_WORLD_ALIGNED, (5.0, 50.0)),
    "talos-6d": ("talos_legs", 2, pin.LOCAL, (10.0, 30.0)),
    "talos-6d-lwa": ("talos_legs", 2, pin.LOCAL_WORLD_ALIGNED, (0.0, 40.0)),
}


def contact_node(case: str, armature: bool = False, damping: float = 0.0, seed: int = 0, dt: float = 0.01):
    """An Euler node of contact dynamics of ``case`` with state, control, swing-foot, cone (and, on 6D contacts,
    centre-of-pressure), contact-force, CoM, joint-effort, joint-acceleration and gravity-and-contact-force
    compensating control costs."""
    robot, nfeet, reference, gains = CASES[case]
    rng = np.random.default_rng(seed)
    model = load(robot)
    state = crocopy.StateMultibody(model)
    actuation = crocopy.ActuationModelFloatingBase(state)
    nu = actuation.nu
    data = model.createData()
    q0 = pin.neutral(model)
    pin.framesForwardKinematics(model, data, q0)
    contacts = crocopy.ContactModelMultiple(state, nu)
    costs = crocopy.CostModelSum(state, nu)
    feet = FEET[robot]
    for name in feet[:nfeet]:
        fid = model.getFrameId(name)
        placement = data.oMf[fid]
        if robot == "anymal":
            contact = crocopy.ContactModel3D(state, fid, placement.translation + 0.01, reference, nu, np.array(gains))
            cone = crocopy.FrictionCone(np.eye(3), 0.7, 4, False)
            residual = crocopy.ResidualModelContactFrictionCone(state, fid, cone, nu)
        else:
            contact = crocopy.ContactModel6D(state, fid, placement * pin.SE3.Random(), reference, nu, np.array(gains))
            cone = crocopy.WrenchCone(np.eye(3), 0.7, np.array([0.1, 0.05]), 4, False)
            residual = crocopy.ResidualModelContactWrenchCone(state, fid, cone, nu)
            cop = crocopy.ResidualModelContactCoPPosition(state, fid, crocopy.CoPSupport(np.eye(3),
                                                                                         np.array([0.2, 0.1])), nu)
            costs.addCost(name + "_cop", crocopy.CostModelResidual(state, cop), 0.5)
        contacts.addContact(name, contact)
        barrier = crocopy.ActivationModelQuadraticBarrier(crocopy.ActivationBounds(cone.lb, cone.ub))
        costs.addCost(name + "_cone", crocopy.CostModelResidual(state, barrier, residual), rng.uniform(0.5, 2.0))
    np.random.seed(seed)
    xref = state.rand()
    weights = crocopy.ActivationModelWeightedQuad(rng.uniform(0.5, 2.0, state.ndx))
    costs.addCost("state", crocopy.CostModelResidual(state, weights, crocopy.ResidualModelState(state, xref, nu)), 1.0)
    costs.addCost("control", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, nu)), 0.1)
    swing = model.getFrameId(feet[-1])
    translation = crocopy.ResidualModelFrameTranslation(state, swing, rng.standard_normal(3), nu)
    costs.addCost("swing", crocopy.CostModelResidual(state, translation), 2.0)
    com = crocopy.ResidualModelCoMPosition(state, rng.standard_normal(3), nu)
    costs.addCost("com", crocopy.CostModelResidual(state, com), 3.0)
    loaded = model.getFrameId(feet[1])  # a foot the tests below keep in contact
    force = crocopy.ResidualModelContactForce(state, loaded, pin.Force(rng.standard_normal(6)),
                                              3 if robot == "anymal" else 6, nu)
    costs.addCost("force", crocopy.CostModelResidual(state, force), 1e-3)
    effort = crocopy.ResidualModelJointEffort(state, actuation, rng.standard_normal(nu), nu)
    costs.addCost("effort", crocopy.CostModelResidual(state, effort), 0.01)
    acceleration = crocopy.ResidualModelJointAcceleration(state, rng.standard_normal(state.nv), nu)
    costs.addCost("acceleration", crocopy.CostModelResidual(state, acceleration), 1e-3)
    gravity = crocopy.ResidualModelContactControlGrav(state, nu)
    costs.addCost("gravity", crocopy.CostModelResidual(state, gravity), 1e-3)
    dam = crocopy.DifferentialActionModelContactFwdDynamics(state, actuation, contacts, costs, damping, True)
    if armature:
        dam.armature = np.linspace(0.01, 0.1, state.nv)
    return crocopy.IntegratedActionModelEuler(dam, dt), state


def point(state, nu: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(200 + seed)
    np.random.seed(200 + seed)
    x = state.rand()
    x[state.nq:] = rng.standard_normal(state.nv)
    return x, 10.0 * rng.standard_normal(nu)


def compare(iam, state, terminal: bool, seed: int = 0) -> None:
    """The compiled node's outputs equal the Python node's at a random point."""
    x, u = point(state, iam.nu, seed)
    compare_with_python_node(iam, x, u, terminal, rtol=1e-7, atol=1e-7, cost_rel=1e-9)


@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("terminal", [False, True])
def test_contact_node_matches_the_python_node(case, terminal):
    iam, state = contact_node(case)
    compare(iam, state, terminal)


@pytest.mark.parametrize(("case", "armature", "damping"),
                         [("anymal-lwa", True, 0.0), ("anymal-local-gains", False, 1e-3), ("talos-6d", True, 1e-4)])
def test_armature_and_damping(case, armature, damping):
    iam, state = contact_node(case, armature, damping, seed=1)
    compare(iam, state, False, seed=1)


@pytest.mark.parametrize("case", ["anymal-local-gains", "talos-6d-lwa"])
def test_derivatives_match_finite_differences(case):
    """``Fx, Fu, Lx, Lu`` of the compiled contact node against central differences of its own ``calc``."""
    iam, state = contact_node(case, armature=True, seed=2)
    x, u = point(state, iam.nu, 2)
    # the costs reach 1e4 here: a step of 1e-5 keeps the differences above round-off
    check_finite_differences(iam, state, x, u, h=1e-5, atol=1e-5, roundoff=1e-10)


def test_contact_nodes_that_do_not_qualify():
    iam, state = contact_node("anymal-lwa")
    dam = iam.differential
    nu = iam.nu
    assert iam._compiled_node(iam.createData(), False, {}) is not None
    foot = state.pinocchio.getFrameId("LF_FOOT")
    dam.contacts.addContact("twice", crocopy.ContactModel3D(state, foot, np.zeros(3), pin.LOCAL, nu))
    shared = crocopy.IntegratedActionModelEuler(dam, 0.01)
    assert shared._compiled_node(shared.createData(), False, {}) is None  # a redundant set: least squares
    dam.JMinvJt_damping = 1e-6
    assert shared._compiled_node(shared.createData(), False, {}) is not None
    dam.contacts.removeContact("twice")
    dam.JMinvJt_damping = 0.0
    dam.contacts.addContact("line", crocopy.ContactModel1D(state, foot, 0.0, pin.LOCAL, np.eye(3), nu))
    dam.contacts.changeContactStatus("LF_FOOT", False)
    one_d = crocopy.IntegratedActionModelEuler(dam, 0.01)  # the LF cone reads the 1D contact on its foot
    assert one_d._compiled_node(one_d.createData(), False, {}) is None
    dam.costs.changeCostStatus("LF_FOOT_cone", False)
    assert one_d._compiled_node(one_d.createData(), False, {}) is not None  # see test_contact_node_1d2d.py
    dam.costs.changeCostStatus("LF_FOOT_cone", True)
    dam.contacts.removeContact("line")
    inactive = crocopy.IntegratedActionModelEuler(dam, 0.01)  # the LF cone reads an inactive contact
    assert inactive._compiled_node(inactive.createData(), False, {}) is None
    dam.costs.changeCostStatus("LF_FOOT_cone", False)
    assert inactive._compiled_node(inactive.createData(), False, {}) is not None

    class Contact(crocopy.DifferentialActionModelContactFwdDynamics):
        pass

    sub = crocopy.IntegratedActionModelEuler(Contact(state, dam.actuation, dam.contacts, dam.costs), 0.01)
    assert sub._compiled_node(sub.createData(), False, {}) is None


def test_a_contact_status_change_rebuilds_the_evaluator():
    iam, state = contact_node("anymal-lwa", seed=4)
    data = iam.createData()
    first = iam._compiled_node(data, False, {})
    iam.differential.costs.changeCostStatus("RH_FOOT_cone", False)
    iam.differential.contacts.changeContactStatus("RH_FOOT", False)
    second = iam._compiled_node(data, False, {})
    assert second is not first and second.contacts.nc == 9
    x, u = point(state, iam.nu, 4)
    slow = iam.createData()
    second.calcDiff(x, u, False)
    iam.calc(slow, x, u)
    iam.calcDiff(slow, x, u)
    np.testing.assert_allclose(data.Fx, slow.Fx, rtol=1e-7, atol=1e-7 * np.abs(slow.Fx).max())
    assert data.cost == pytest.approx(slow.cost, rel=1e-9)


def test_contact_references_are_read_again_at_each_solve():
    iam, state = contact_node("talos-6d", seed=5)
    data = iam.createData()
    x, u = point(state, iam.nu, 5)
    iam._compiled_node(data, False, {})
    contact = iam.differential.contacts.contacts["left_sole_link"].contact
    contact.reference = pin.SE3.Random()
    contact.gains = np.array([3.0, 7.0])
    iam.differential.costs.costs["com"].cost.residual.reference = np.array([0.1, 0.2, 0.3])
    check_new_evaluator(iam, data, x, u)


def _standing_problem(T: int = 12):
    """ANYmal on four feet (the walk's first node, friction cones and state costs) from a bent posture."""
    problem, xs, us = registry.build("walk")
    x0 = problem.x0.copy()
    x0[2] -= 0.02
    x0[7:19] += 0.05
    running = [problem.runningModels[0]] * T
    return crocopy.ShootingProblem(x0, running, problem.terminalModel), [x0] * (T + 1), [us[0]] * T


@pytest.mark.parametrize("solver", ["SolverDDP", "SolverFDDP", "SolverBoxDDP", "SolverBoxFDDP"])
def test_solves_with_compiled_contact_nodes_match_the_python_nodes(solver):
    outcomes = []
    for compiled in (True, False):
        problem, xs, us = _standing_problem()
        s = make_solver(solver, problem, compiled)
        if compiled:
            assert compiled_nodes.select(s).horizon is not None
        s.solve(xs, us, 30)
        outcomes.append((s.iter, s.cost, [x.copy() for x in s.xs]))
    assert outcomes[0][0] == outcomes[1][0] and outcomes[0][0] > 1
    assert outcomes[0][1] == pytest.approx(outcomes[1][1], rel=1e-9)
    for a, b in zip(outcomes[0][2], outcomes[1][2]):
        np.testing.assert_allclose(a, b, rtol=1e-7, atol=1e-8)


def test_a_diverging_contact_solve_stops_as_without_compiled_nodes():
    """Ten times the time step (the standing problem's nodes share one model): every trial rollout overflows; both
    paths stop the same way, with a finite iterate.  Where a rollout overflows, the node a kernel's acceleration
    first stops being finite is evaluated on the Python path, whose overflow may come one node later: the reasons
    agree but for that node's index.  The first ``Quu`` (at ``preg = 1``) is positive definite by a round-off margin
    here: on an AMD EPYC the kernels' Cholesky accepts it where LAPACK's refuses it, and that path spends one more
    iteration (no step accepted) before both raise ``preg`` the same way, iteration for iteration."""
    outcomes = []
    for compiled in (True, False):
        problem, xs, us = _standing_problem()
        problem.runningModels[0].dt = 0.1
        outcomes.append(failed_solve(problem, xs, us, compiled, 15))
    assert outcomes[0][0] is outcomes[1][0] is False
    assert abs(outcomes[0][1] - outcomes[1][1]) <= 1
    assert [re.sub(r"node \d+", "node t", o[2]) for o in outcomes] == [
        "no step accepted and regularization reached reg_max = 1e+09 (last trial: non-finite cost at node t in the "
        "rollout)"] * 2
