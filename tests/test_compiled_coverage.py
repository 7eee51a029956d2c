"""``crocopy.compiled_coverage``: the nodes it reports compiled are exactly those a solve compiles
(``compiled_nodes.select``), and the others carry the reason the evaluator's offer recorded (``crocopy.not_compiled``):
one constructed node per reason; the ``crocopy bench --coverage`` table."""

from __future__ import annotations

import importlib.util

import numpy as np
import pinocchio as pin
import pytest
from node_checks import make_solver

import crocopy
from crocopy.bench import coverage
from crocopy.cli import main
from crocopy.problems import quadruped, registry
from crocopy.problems.user_residual import build_user_reach, python_frame_translation
from crocopy.solvers import compiled_nodes

pytestmark = pytest.mark.skipif(not crocopy.kernels_enabled(), reason="compiled nodes need numba")
HAS_CROCODDYL = importlib.util.find_spec("crocoddyl") is not None


class UserActuation(crocopy.ActuationModelFull):
    """A user's subclass of a built-in actuation (it may override a step: its node keeps the Python path)."""


class UserRK(crocopy.IntegratedActionModelRK):
    """A user's subclass of the Runge-Kutta integrator (its node keeps the Python path)."""


def solver_compiles(problem) -> list[bool]:
    """Per node, whether a solve's compiled nodes give it a compiled evaluator (not the model's own methods)."""
    nodes = compiled_nodes.select(crocopy.SolverFDDP(problem))
    if nodes is None:
        return [False] * (problem.T + 1)
    return [getattr(calc, "__self__", None) is not None for calc in nodes.calcs]


def free_reasons_problem():
    """The kinova reach (T = 7) with one node per reason a free-dynamics node is not compiled."""
    problem, _, _ = build_user_reach(crocopy, "builtin", robot="kinova", nodes=7)
    models = list(problem.runningModels)
    dam = models[1].differential
    state, costs, nu = dam.state, dam.costs, dam.nu
    models[1] = crocopy.IntegratedActionModelRK(dam, crocopy.RKType.four, 0.01)
    manager = crocopy.ConstraintModelManager(state, nu)
    bounds = crocopy.ConstraintModelResidual(state, crocopy.ResidualModelControl(state, nu), -np.ones(nu), np.ones(nu))
    manager.addConstraint("u", bounds)
    tip = state.pinocchio.nframes - 1
    user_costs = crocopy.CostModelSum(state, nu)
    user_costs.addCost("user", crocopy.CostModelResidual(
        state, python_frame_translation(crocopy)(state, tip, np.zeros(3), nu)), 1.0)
    models[2] = crocopy.IntegratedActionModelRK(
        crocopy.DifferentialActionModelFreeFwdDynamics(state, dam.actuation, user_costs), crocopy.RKType.four, 0.01)
    manager.addConstraint("v", crocopy.ConstraintModelResidual(
        state, python_frame_translation(crocopy)(state, tip, np.zeros(3), nu)))
    constrained = crocopy.DifferentialActionModelFreeFwdDynamics(state, dam.actuation, costs, manager)
    models[3] = crocopy.IntegratedActionModelEuler(constrained, 0.01)
    user = crocopy.DifferentialActionModelFreeFwdDynamics(state, UserActuation(state), costs)
    models[4] = crocopy.IntegratedActionModelEuler(user, 0.01)
    grav = crocopy.CostModelSum(state, nu)
    numdiff = crocopy.ActivationModelNumDiff(crocopy.ActivationModelQuad(6))
    momentum = crocopy.ResidualModelCentroidalMomentum(state, np.zeros(6), nu)
    grav.addCost("grav", crocopy.CostModelResidual(state, numdiff, momentum), 1.0)
    models[5] = crocopy.IntegratedActionModelEuler(
        crocopy.DifferentialActionModelFreeFwdDynamics(state, dam.actuation, grav), 0.01)
    models[6] = UserRK(dam, crocopy.RKType.two, 0.01)
    return crocopy.ShootingProblem(problem.x0, models, problem.terminalModel)


FREE_REASONS = [None, None, "user Python residual in a Runge-Kutta node",
                "user Python subclass: constraint residual PythonFrameTranslation",
                "user Python subclass: actuation UserActuation", "activation ActivationModelNumDiff",
                "user Python subclass: integrator UserRK", None]


def contact_reasons_problem():
    """A short ANYmal walk (its impulse nodes compile too) with a 1D contact on a foot already in contact in one node
    (a redundant set: the least-squares path) and a user's Python residual in another."""
    problem, _, _ = quadruped.build_gait(crocopy, "walk", step_knots=2, support_knots=1, cycles=1)
    models = list(problem.runningModels)
    first, second = models[0].differential, models[1].differential
    assert first is not second and first.contacts is not second.contacts and first.costs is not second.costs
    state, nu = first.state, first.nu
    foot = state.pinocchio.getFrameId("LF_FOOT")
    first.contacts.addContact("z", crocopy.ContactModel1D(state, foot, 0.0, pin.LOCAL_WORLD_ALIGNED, None, nu))
    user = python_frame_translation(crocopy)(state, foot, np.zeros(3), nu)
    second.costs.addCost("user", crocopy.CostModelResidual(state, user), 1.0)
    return crocopy.ShootingProblem(problem.x0, models, problem.terminalModel)


def test_every_reason_of_a_free_node():
    problem = free_reasons_problem()
    assert [c.reason for c in crocopy.compiled_coverage(problem)] == FREE_REASONS
    assert [c.compiled for c in crocopy.compiled_coverage(problem)] == [r is None for r in FREE_REASONS]


def test_contact_nodes_redundant_contacts_user_residual_and_compiled_impulses():
    problem = contact_reasons_problem()
    cov = crocopy.compiled_coverage(problem)
    assert cov[0] == (False, "redundant contacts")
    assert cov[1] == (False, "user Python subclass: residual PythonFrameTranslation in a contact node")
    impulses = [t for t, m in enumerate(problem.runningModels) if isinstance(m, crocopy.ActionModelImpulseFwdDynamics)]
    assert impulses
    assert all(c.compiled for t, c in enumerate(cov) if t not in (0, 1))


def test_a_joint_the_kernels_do_not_lower():
    model = pin.Model()
    joint = model.addJoint(0, pin.JointModelSphericalZYX(), pin.SE3.Identity(), "ball")
    model.appendBodyToJoint(joint, pin.Inertia.Random(), pin.SE3.Identity())
    state = crocopy.StateMultibody(model)
    actuation = crocopy.ActuationModelFull(state)
    costs = crocopy.CostModelSum(state, actuation.nu)
    costs.addCost("x", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, actuation.nu)), 1.0)
    dam = crocopy.DifferentialActionModelFreeFwdDynamics(state, actuation, costs)
    iam = crocopy.IntegratedActionModelEuler(dam, 0.01)
    problem = crocopy.ShootingProblem(state.zero(), [iam] * 2, iam)
    assert crocopy.compiled_coverage(problem) == [(False, "joint type JointModelSphericalZYX")] * 3


@pytest.mark.parametrize("build", [free_reasons_problem, contact_reasons_problem,
                                   lambda: registry.build("trot-short")[0], lambda: registry.build("quad-goal")[0]],
                         ids=["free-reasons", "contact-reasons", "trot-short", "quad-goal"])
def test_the_report_is_what_the_solver_compiles(build):
    problem = build()
    reported = [c.compiled for c in crocopy.compiled_coverage(problem)]
    assert reported == solver_compiles(problem)
    assert any(reported)


def test_a_problem_is_required():
    with pytest.raises(TypeError, match="problem must be a ShootingProblem, got list"):
        crocopy.compiled_coverage([])


def test_the_table_counts_nodes_and_reasons(capsys):
    assert main(["bench", "--coverage", "--problems", "trot-short", "pend"]) == 0
    out = capsys.readouterr().out
    rows = {line.split(" | ")[0][2:]: line for line in out.splitlines() if line.startswith("| ")}
    trot = registry.build("trot-short")[0]
    assert rows["trot-short"].endswith(f"| {trot.T + 1}/{trot.T + 1} | — |")
    assert rows["pend"].endswith("| 101/101 | — |")
    assert f"| crocopy builder (2) | {trot.T + 102}/{trot.T + 102} | 0 |" in out
    assert "why not compiled" not in out


def test_a_failed_job_keeps_its_coverage_so_far():
    row = coverage.Row("job", "Crocoddyl example", [None, "impulse dynamics", None], 1, ["SolverFDDP"],
                       "ValueError: bad | input")
    assert coverage.format_row(row) == ("| job | Crocoddyl example | 1 | SolverFDDP | 2/3 | 1 impulse dynamics; "
                                        "the job stopped: ValueError: bad \\| input |")


@pytest.mark.skipif(not HAS_CROCODDYL, reason="needs the bench extra (Crocoddyl 3.2.1)")
def test_shipped_scripts_run_with_crocopy_and_report_their_nodes():
    forward = coverage.job_row("quadrotor_fwddyn")
    assert forward.error is None and forward.solvers == ["SolverFDDP"] and forward.problems == 1
    assert len(forward.reasons) > 1 and forward.compiled == len(forward.reasons)
    inverse = coverage.job_row("arm_manipulation_invdyn")
    assert inverse.error is None and inverse.solvers == ["SolverIntro"] and len(inverse.reasons) > 1
    assert inverse.compiled == len(inverse.reasons)


def test_a_node_whose_constraint_manager_has_no_rows_compiles_and_solves_as_without():
    """An empty (or all inactive) constraint manager adds no rows: the node compiles, with the same solve; with the
    row switched on, the datas are made again and the node compiles with its rows."""
    outcomes = []
    for compiled in (True, False):
        problem, xs, us = build_user_reach(crocopy, "builtin", robot="kinova", nodes=20)
        models = list(problem.runningModels)
        dam = models[0].differential
        manager = crocopy.ConstraintModelManager(dam.state, dam.nu)
        bounds = crocopy.ConstraintModelResidual(dam.state, crocopy.ResidualModelControl(dam.state, dam.nu),
                                                 -np.ones(dam.nu), np.ones(dam.nu))
        manager.addConstraint("u", bounds, False)
        node = crocopy.IntegratedActionModelEuler(
            crocopy.DifferentialActionModelFreeFwdDynamics(dam.state, dam.actuation, dam.costs, manager), models[0].dt)
        problem = crocopy.ShootingProblem(problem.x0, [node] * len(models), problem.terminalModel)
        if compiled:
            assert all(c.compiled for c in crocopy.compiled_coverage(problem))
        solver = make_solver("SolverFDDP", problem, compiled)
        solver.solve(xs, us, 30)
        outcomes.append((solver.iter, solver.cost))
        if compiled:
            manager.changeConstraintStatus("u", True)
            assert all(c.compiled for c in crocopy.compiled_coverage(problem))
            assert problem.runningDatas[0].g.shape == (dam.nu,)
    assert outcomes[0][0] == outcomes[1][0] and outcomes[0][1] == pytest.approx(outcomes[1][1], rel=1e-9)
