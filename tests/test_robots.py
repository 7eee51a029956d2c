"""Every example-robot-data robot that loads: a short free-dynamics problem (and, on robots with feet, a contact
problem) solves alike with and without compiled nodes, and no exception comes out of ``solve()``; the compiled node
equals the Python node.

Robots whose mass matrix is singular (massless finger or gripper joints) give the same documented refusal on both
paths: ``solve()`` returns False, the reason naming the joints.  Redundant contact sets take the least-squares route
(on the Python node).  The sweep over all robots is ``slow``; a representative subset runs by default: continuous
joints, a singular mass matrix, a rank-deficient contact set, a humanoid with 6D contacts.
"""

from __future__ import annotations

import example_robot_data
import numpy as np
import pinocchio as pin
import pytest
from node_checks import FIELDS, make_solver
from robots import BIPED_SOLES, QUADRUPED_FEET

import crocopy
from crocopy.models.dynamics_options import massless_joints

pytestmark = pytest.mark.skipif(not crocopy.kernels_enabled(), reason="compiled nodes need numba")

FAST = ("double_pendulum_continuous", "bravo7_gripper", "solo8", "talos_legs", "kinova")
"""Continuous joints (RUBX, RUBZ), massless gripper fingers, 3D contacts of deficient rank, 6D soles."""
UNLOADABLE = {"cassie": ImportError}
"""Robots example-robot-data lists that do not load here, with the error (cassie needs an SDF parser this
Pinocchio build lacks); :func:`test_the_unloadable_robots_still_fail_to_load` notices when one starts loading."""
ALL = tuple(name for name in example_robot_data.ROBOTS if name not in FAST and name not in UNLOADABLE)
T, MAXITER = 5, 4


def robot(name: str) -> tuple[pin.Model, np.ndarray]:
    """The model of ``name`` and its reference posture (``q0``)."""
    wrapper = example_robot_data.load(name)
    q0 = wrapper.q0 if wrapper.q0 is not None else pin.neutral(wrapper.model)
    return wrapper.model, np.asarray(q0, dtype=float)


def floating(model: pin.Model) -> bool:
    return model.njoints > 1 and model.joints[1].shortname() == "JointModelFreeFlyer"


def costs(state, nu: int, x0: np.ndarray, terminal: bool, tip: int | None) -> crocopy.CostModelSum:
    """Posture, control and (free dynamics) a tip position: residuals that all compile."""
    stack = crocopy.CostModelSum(state, nu)
    stack.addCost("x", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, x0, nu)), 1.0)
    if not terminal:
        stack.addCost("u", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, nu)), 1e-3)
    if tip is not None:
        goal = crocopy.ResidualModelFrameTranslation(state, tip, np.array([0.1, 0.1, 0.4]), nu)
        stack.addCost("tip", crocopy.CostModelResidual(state, goal), 1.0)
    return stack


def free_problem(model: pin.Model, q0: np.ndarray) -> crocopy.ShootingProblem:
    """Reach a point with the last frame; a floating base is unactuated unless it is the only joint (iris, hector:
    a wrench on the body)."""
    state = crocopy.StateMultibody(model)
    underactuated = floating(model) and model.njoints > 2
    act = crocopy.ActuationModelFloatingBase(state) if underactuated else crocopy.ActuationModelFull(state)
    x0 = np.concatenate([q0, np.zeros(model.nv)])
    nodes = [crocopy.IntegratedActionModelEuler(crocopy.DifferentialActionModelFreeFwdDynamics(
        state, act, costs(state, act.nu, x0, terminal, model.nframes - 1)), 0.0 if terminal else 0.01)
        for terminal in (False, True)]
    return crocopy.ShootingProblem(x0, [nodes[0]] * T, nodes[1])


def contact_problem(model: pin.Model, q0: np.ndarray, feet: tuple, six: bool) -> crocopy.ShootingProblem:
    """Standing on ``feet`` (6D contacts if ``six``, else 3D), references at their placements in ``q0``."""
    state = crocopy.StateMultibody(model)
    act = crocopy.ActuationModelFloatingBase(state)
    x0 = np.concatenate([q0, np.zeros(model.nv)])
    data = model.createData()
    pin.framesForwardKinematics(model, data, q0)

    def dam(terminal: bool):
        contacts = crocopy.ContactModelMultiple(state, act.nu)
        for foot in feet:
            fid = model.getFrameId(foot)
            gains = np.array([0.0, 50.0])
            contact = (crocopy.ContactModel6D(state, fid, data.oMf[fid], pin.LOCAL, act.nu, gains) if six else
                       crocopy.ContactModel3D(state, fid, data.oMf[fid].translation, pin.LOCAL_WORLD_ALIGNED, act.nu,
                                              gains))
            contacts.addContact(foot, contact)
        return crocopy.DifferentialActionModelContactFwdDynamics(state, act, contacts,
                                                                 costs(state, act.nu, x0, terminal, None))

    running = crocopy.IntegratedActionModelEuler(dam(False), 0.01)
    return crocopy.ShootingProblem(x0, [running] * T, crocopy.IntegratedActionModelEuler(dam(True), 0.0))


def solve_both_ways(problem: crocopy.ShootingProblem) -> tuple:
    """``(solved, iter, reason, cost)`` of FDDP with and without compiled nodes, from the posture held still: equal
    (costs to 1e-8).  (Not from the default guess: its neutral states may be a configuration where the contact
    Jacobian loses rank, centauro's, or a base rotation of exactly π from ``q0``, icub's, where the logarithm's
    branch is decided by round-off.)"""
    results = []
    xs, us = [problem.x0] * (problem.T + 1), [np.zeros(m.nu) for m in problem.runningModels]
    for compiled in (True, False):
        s = make_solver("SolverFDDP", problem, compiled)
        solved = s.solve(xs, us, MAXITER)
        assert np.isfinite(s.cost) and all(np.isfinite(x).all() for x in s.xs)
        results.append((solved, s.iter, s.reason, s.cost))
    assert results[0][:3] == results[1][:3]
    assert results[0][3] == pytest.approx(results[1][3], rel=1e-8, abs=1e-12)
    return results[0]


def check_node(problem: crocopy.ShootingProblem, singular: bool) -> None:
    """The running node compiles unless its contact set is redundant; where it compiles and the mass matrix is
    regular, it equals the Python node at a random state."""
    iam = problem.runningModels[0]
    dam = iam.differential
    redundant = hasattr(dam, "_redundant_contacts") and dam._redundant_contacts()
    assert (iam._compiled_node(iam.createData(), False, {}) is None) == redundant
    if redundant or singular:
        return
    np.random.seed(1)
    x = dam.state.rand()
    x[dam.state.nq:] = np.random.default_rng(1).normal(size=dam.state.nv)
    u = np.random.default_rng(2).normal(size=iam.nu)
    compare_nodes(iam, x, u)


def compare_nodes(iam, x: np.ndarray, u: np.ndarray) -> None:
    """The compiled node's ``calc``/``calcDiff`` against the Python node's, to ``1e-8`` or ``1e-15`` times the
    condition number of the mass matrix at ``x`` if larger (icub's point-mass head makes it 1e10 and more)."""
    state = iam.differential.state
    model = state.pinocchio
    M = pin.crba(model, model.createData(), x[:state.nq])
    tol = max(1e-8, 1e-15 * float(np.linalg.cond(M)))
    fast, slow = iam.createData(), iam.createData()
    evaluator = iam._compiled_node(fast, False, {})
    evaluator.calcDiff(x, u, False)
    iam.calc(slow, x, u)
    iam.calcDiff(slow, x, u)
    assert fast.cost == pytest.approx(slow.cost, rel=tol)
    for name in FIELDS:
        a, b = getattr(fast, name), getattr(slow, name)
        np.testing.assert_allclose(a, b, rtol=tol, atol=tol * max(1.0, np.abs(b).max()), err_msg=name)


def check_robot(name: str) -> None:
    model, q0 = robot(name)
    singular = massless_joints(model, np.zeros(model.nv))
    problems = [free_problem(model, q0)]
    if name in QUADRUPED_FEET or name in BIPED_SOLES:
        six = name in BIPED_SOLES
        problems.append(contact_problem(model, q0, BIPED_SOLES[name] if six else QUADRUPED_FEET[name], six))
    for problem in problems:
        check_node(problem, bool(singular))
        solved, _, reason, _ = solve_both_ways(problem)
        if singular:
            assert not solved and "the mass matrix is singular" in reason


@pytest.mark.parametrize("name", FAST)
def test_representative_robots(name):
    check_robot(name)


@pytest.mark.slow
@pytest.mark.parametrize("name", ALL)
def test_every_robot(name):
    check_robot(name)


@pytest.mark.parametrize("name", sorted(UNLOADABLE))
def test_the_unloadable_robots_still_fail_to_load(name):
    with pytest.raises(UNLOADABLE[name]):
        example_robot_data.load(name)


@pytest.mark.parametrize("at_neutral", [False, True], ids=["guess-neutral", "x0-neutral"])
def test_a_contact_set_singular_at_some_states_solves_as_without_compiled_nodes(at_neutral):
    """centauro's four wheels lose rank at its neutral posture: there the KKT system is singular, the Python path
    takes least squares, and the compiled nodes evaluate those nodes on their Python path (values, derivatives and
    rollout steps), so the solve equals the one without compiled nodes.  From the standing posture with the neutral
    guess (the derivatives at the guess), or from the neutral posture itself (every rollout starts there).  Near that
    posture the KKT system is ill-conditioned, and Pinocchio's factorisation stays finite at states where the
    kernel's pivot vanishes (those nodes then take the Python path): the iterates agree to the conditioning (1e-4)
    there, to 1e-8 from the standing posture.  Without the per-node fallback the compiled solve stopped on NaN."""
    model, q0 = robot("centauro")
    start = pin.neutral(model) if at_neutral else q0
    results = []
    for compiled in (True, False):
        problem = contact_problem(model, start, QUADRUPED_FEET["centauro"], False)
        solver = make_solver("SolverFDDP", problem, compiled)
        solver.solve([], [], MAXITER)
        assert np.isfinite(solver.cost) and all(np.isfinite(x).all() for x in solver.xs)
        results.append((solver.iter, solver.reason, solver.cost, [x.copy() for x in solver.xs]))
    assert results[0][:2] == results[1][:2] and results[0][0] == MAXITER
    tolerance = 1e-4 if at_neutral else 1e-8
    assert results[0][2] == pytest.approx(results[1][2], rel=tolerance)
    for a, b in zip(results[0][3], results[1][3], strict=True):
        np.testing.assert_allclose(a, b, rtol=tolerance, atol=tolerance)
