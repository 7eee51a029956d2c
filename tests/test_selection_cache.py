"""A problem's compiled nodes are kept from one solve to the next (``compiled_nodes.Selection``), never stale.

Between two solves of the same solver, or of a new solver on the same problem, each mutation below changes nothing
the parameter clock sees (no setter): an in-place write into a Pinocchio model, a ``pin.SE3``/``pin.Motion``
reference, a friction cone, a user residual's ``parameters()``, a writeable reference of a deep-copied model.  The
second solve equals a freshly built problem's with the same mutation, and differs from the unmutated solve.
"""

from __future__ import annotations

import copy

import numpy as np
import pinocchio as pin
import pytest

import crocopy
from crocopy.problems import arm, quadruped
from crocopy.problems.user_residual import build_user_reach
from crocopy.solvers import compiled_nodes

MAXITER = 5
SOLVERS = {"boxfddp": crocopy.SolverBoxFDDP, "sqp": crocopy.SolverSQP}


def arm_with_frames():
    """The arm reach with placement and velocity costs (``pin.SE3``/``pin.Motion`` references) on every node."""
    problem, xs, us = arm.build_arm_reaching(crocopy, nodes=10)
    for m in [*problem.runningModels, problem.terminalModel]:
        dam = m.differential
        state, nu = dam.state, dam.nu
        fid = state.pinocchio.nframes - 1
        placement = crocopy.ResidualModelFramePlacement(state, fid, pin.SE3(np.eye(3), np.array([0.4, 0.3, 0.6])), nu)
        velocity = crocopy.ResidualModelFrameVelocity(state, fid, pin.Motion(np.full(6, 0.1)), pin.LOCAL, nu)
        dam.costs.addCost("placement", crocopy.CostModelResidual(state, placement), 1.0)
        dam.costs.addCost("velocity", crocopy.CostModelResidual(state, velocity), 1.0)
    return problem, xs, us


def walk():
    return quadruped.build_gait(crocopy, "walk", step_knots=3, support_knots=1, cycles=1)


def user_reach():
    return build_user_reach(crocopy, "numba", robot="kinova", nodes=10)


def deep_copied_arm():
    """The arm reach, deep-copied: its references are writeable copies (no longer read-only)."""
    problem, xs, us = arm.build_arm_reaching(crocopy, nodes=10)
    return copy.deepcopy(problem), xs, us


def items(problem, name: str) -> list:
    """The residuals of the cost ``name`` on every node that has it."""
    found = []
    for m in [*problem.runningModels, problem.terminalModel]:
        costs = getattr(m, "differential", m).costs.costs
        if name in costs:
            found.append(costs[name].cost.residual)
    return found


def cones(problem) -> list:
    found = []
    for m in [*problem.runningModels, problem.terminalModel]:
        for item in getattr(m, "differential", m).costs.costs.values():
            if type(item.cost.residual) is crocopy.ResidualModelContactFrictionCone:
                found.append(item.cost.residual)
    return found


def pinocchio_model(problem) -> pin.Model:
    return problem.runningModels[0].state.pinocchio


def heavier_link(p):
    inertia = pinocchio_model(p).inertias[3]
    inertia.mass = 1.5 * inertia.mass


def weaker_gravity(p):
    pinocchio_model(p).gravity.linear[2] = -5.0


def joint_armature(p):
    pinocchio_model(p).armature[:] = 0.05


def placement_in_place(p):
    for r in items(p, "placement"):
        r.reference.translation = np.array([0.3, 0.2, 0.5])


def velocity_in_place(p):
    for r in items(p, "velocity"):
        r.reference.linear = np.array([0.2, -0.1, 0.0])


def cone_in_place(p):
    for r in cones(p):
        r.reference.mu = 0.3
        r.reference.update()


def user_parameters_in_place(p):
    for r in items(p, "goal"):
        r.reference[:] = [0.3, 0.1, 0.5]


def copied_reference_in_place(p):
    """In place where the reference is writeable (deep-copied), else through the setter (the fresh build)."""
    for r in items(p, "goal"):
        if r.reference.flags.writeable:
            r.reference[:] = [0.3, 0.1, 0.5]
        else:
            r.reference = np.array([0.3, 0.1, 0.5])


def reference_set_and_armature_in_place(p):
    """The state references through their setter (only residuals touched: the nodes re-read those and their live
    sources) and, in place where it is writeable (deep-copied), the dynamics' armature, a live source."""
    for r in items(p, "state"):
        r.reference = np.asarray(r.reference) + 0.01
    for m in p.runningModels:
        armature = m.differential.armature
        if armature.flags.writeable:
            armature[:] = 0.05
        else:
            m.differential.armature = np.full(armature.shape, 0.05)


def reference_and_time_step_set(p):
    """A state reference and the time step through their setters: a residual and a model touched."""
    for r in items(p, "state"):
        r.reference = np.asarray(r.reference) + 0.01
    for m in p.runningModels:
        m.dt = 0.8 * m.dt


CASES = {
    "pinocchio inertia": (arm_with_frames, heavier_link),
    "pinocchio gravity": (arm_with_frames, weaker_gravity),
    "pinocchio armature": (arm_with_frames, joint_armature),
    "placement reference": (arm_with_frames, placement_in_place),
    "velocity reference": (arm_with_frames, velocity_in_place),
    "friction cone": (walk, cone_in_place),
    "pinocchio inertia (contacts)": (walk, heavier_link),
    "user residual parameters": (user_reach, user_parameters_in_place),
    "deep-copied reference": (deep_copied_arm, copied_reference_in_place),
    "reference set, armature in place": (deep_copied_arm, reference_set_and_armature_in_place),
    "reference and time step set": (arm_with_frames, reference_and_time_step_set),
}


def solve(solver, xs, us, maxiter: int) -> tuple[int, float]:
    solver.solve([x.copy() for x in xs], [u.copy() for u in us], maxiter)
    return solver.iter, solver.cost


def mutated_between_solves(build, mutate, solver_class, same_solver: bool) -> tuple[int, float]:
    problem, xs, us = build()
    solver = solver_class(problem)
    solve(solver, xs, us, 2)
    mutate(problem)
    return solve(solver if same_solver else solver_class(problem), xs, us, MAXITER)


def fresh(build, mutate, solver_class) -> tuple[int, float]:
    problem, xs, us = build()
    if mutate is not None:
        mutate(problem)
    problem = crocopy.ShootingProblem(problem.x0, problem.runningModels, problem.terminalModel)
    return solve(solver_class(problem), xs, us, MAXITER)


@pytest.mark.parametrize("same_solver", [True, False], ids=["same solver", "new solver"])
@pytest.mark.parametrize("solver", sorted(SOLVERS))
@pytest.mark.parametrize("case", sorted(CASES))
def test_unannounced_mutation_between_solves_gives_a_fresh_problems_solve(case, solver, same_solver):
    build, mutate = CASES[case]
    solver_class = SOLVERS[solver]
    mutated = mutated_between_solves(build, mutate, solver_class, same_solver)
    expected = fresh(build, mutate, solver_class)
    assert mutated == expected
    assert mutated[1] != fresh(build, None, solver_class)[1]  # the mutation matters


def test_selection_is_kept_after_a_value_setter_and_made_again_after_a_layout_setter():
    """A value attribute assigned (``dt``, a residual's ``reference``) is re-read into the kept selection's
    parameters in place; a frame changed (the node's layout) makes the selection again, as a new problem does."""
    problem, xs, us = arm.build_arm_reaching(crocopy, nodes=10)
    solver = crocopy.SolverFDDP(problem)
    first = compiled_nodes.select(solver)
    assert compiled_nodes.select(crocopy.SolverDDP(problem)) is first
    problem.runningModels[0].dt = 0.5 * problem.runningModels[0].dt
    goal = problem.runningModels[3].differential.costs.costs["goal"].cost.residual
    goal.reference = goal.reference + 0.25
    assert compiled_nodes.select(solver) is first
    horizon = first.horizon
    assert horizon.par[horizon.poff[0]] == problem.runningModels[0].dt
    assert 0.25 + problem.runningModels[2].differential.costs.costs["goal"].cost.residual.reference[0] in \
        horizon.par[horizon.poff[3]:horizon.poff[4]]
    goal.id = goal.id - 1
    second = compiled_nodes.select(solver)
    assert second is not first
    assert compiled_nodes.select(solver) is second
    copied = crocopy.ShootingProblem(problem.x0, problem.runningModels, problem.terminalModel)
    assert compiled_nodes.select(crocopy.SolverFDDP(copied)) is not second


def arm_with_weights():
    """The arm reach with a posture cost of weighted activation on every node."""
    problem, xs, us = arm.build_arm_reaching(crocopy, nodes=10)
    for m in [*problem.runningModels, problem.terminalModel]:
        dam = m.differential
        weights = np.linspace(1.0, 2.0, dam.state.ndx)
        posture = crocopy.CostModelResidual(dam.state, crocopy.ActivationModelWeightedQuad(weights),
                                            crocopy.ResidualModelState(dam.state, problem.x0, dam.nu))
        dam.costs.addCost("posture", posture, 0.5)
    return problem, xs, us


def test_weights_assigned_keep_the_selection_and_its_items():
    """A cost item's ``weight`` and an activation's ``weights`` assigned between solves are re-read in place: the
    selection and its nodes' items are kept, and the solve equals a fresh problem's with those weights; switching a
    cost off makes the selection again."""
    def reweight(p):
        for m in [*p.runningModels, p.terminalModel]:
            costs = m.differential.costs.costs
            costs["goal"].weight = 3.0 * costs["goal"].weight
            activation = costs["posture"].cost.activation
            activation.weights = 2.0 * activation.weights[::-1]

    problem, xs, us = arm_with_weights()
    solver = crocopy.SolverFDDP(problem)
    solve(solver, xs, us, 2)
    first = compiled_nodes.select(solver)
    items = [node._residuals for node in first.horizon.nodes]
    reweight(problem)
    assert compiled_nodes.select(solver) is first
    assert all(node._residuals is kept for node, kept in zip(first.horizon.nodes, items))
    assert solve(solver, xs, us, MAXITER) == fresh(arm_with_weights, reweight, crocopy.SolverFDDP)
    assert solve(solver, xs, us, MAXITER) != fresh(arm_with_weights, None, crocopy.SolverFDDP)
    problem.runningModels[2].differential.costs.changeCostStatus("goal", False)
    assert compiled_nodes.select(solver) is not first


def test_a_running_node_evaluated_as_terminal_between_solves():
    """``model.calc(data, x)`` on a running node switches its cost stack to a terminal node's: the next solve
    switches it back (same solve as without that evaluation)."""
    expected = fresh(arm_with_frames, None, crocopy.SolverBoxFDDP)

    def evaluate_as_terminal(p):
        for m, d in zip(p.runningModels, p.runningDatas):
            m.calc(d, p.x0)

    for same_solver in (True, False):
        assert mutated_between_solves(arm_with_frames, evaluate_as_terminal, crocopy.SolverBoxFDDP,
                                      same_solver) == expected


def test_another_problem_built_keeps_the_selection_and_a_held_stale_data_costs_one_selection(monkeypatch):
    """Building another problem moves the structure clock without making a data stale: the selection is kept.  A
    data made stale by an item-set change that the user still holds makes the next selection anew, once."""
    import weakref

    from crocopy import versioning

    monkeypatch.setattr(versioning, "_STALE", weakref.WeakSet())  # no stale data of other tests
    problem, xs, us = arm.build_arm_reaching(crocopy, nodes=10)
    solver = crocopy.SolverFDDP(problem)
    first = compiled_nodes.select(solver)
    arm.build_arm_reaching(crocopy, nodes=10)
    assert compiled_nodes.select(solver) is first
    held = problem.runningDatas[0]
    problem.runningModels[0].differential.costs.removeCost("control")
    assert problem.refresh_datas() == [0] and held.differential.costs.structure_stale
    second = compiled_nodes.select(solver)
    assert second is not first and compiled_nodes.select(solver) is second
    arm.build_arm_reaching(crocopy, nodes=10)
    third = compiled_nodes.select(solver)
    assert third is not second and compiled_nodes.select(solver) is third
    solver.solve(xs, us, 3)
    fresh = crocopy.SolverFDDP(crocopy.ShootingProblem(problem.x0, problem.runningModels, problem.terminalModel))
    fresh.solve(xs, us, 3)
    assert solver.cost == fresh.cost and held is not problem.runningDatas[0]
