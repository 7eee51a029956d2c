"""A problem mutated through a public setter or an in-place write gives a freshly built problem's solve.

Each case crosses one public mutation with a free-dynamics arm and a contact quadruped walk (contacts, impulses,
cones, CoM and swing-foot costs): problem A is built, solved from the warm start (compiled nodes read their
parameters), evaluated on the Python path (``problem.calc``/``calcDiff``), mutated and solved again from the same
warm start; problem B is built, mutated, and wrapped in a fresh ``ShootingProblem`` (new datas) before its only
solve.  Both run with kernels on and off: the same iterations and costs to 1e-9, and kernels on and off agree.
An in-place write into an array a getter handed out either raises (a read-only array) or takes effect on every
path (a live one); it is never silently ignored.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pinocchio as pin
import pytest

import crocopy
from crocopy.problems import arm, quadruped

MAXITER = 6


def build_arm():
    return arm.build_arm_reaching(crocopy, nodes=10)


def build_walk():
    return quadruped.build_gait(crocopy, "walk", step_knots=3, support_knots=1, cycles=1)


def build_quadrotor():
    from crocopy.problems.quadrotor import build_quadrotor

    return build_quadrotor(crocopy, "goal")


PROBLEMS = {"arm": build_arm, "walk": build_walk, "quadrotor": build_quadrotor}


def dams(problem) -> list:
    """The differential models of the problem's nodes that have one (running and terminal)."""
    models = [*problem.runningModels, problem.terminalModel]
    return [m.differential for m in models if hasattr(m, "differential")]


def residuals(problem, cls) -> list:
    """Every residual of class ``cls`` in the problem's cost sums (running and terminal, impulse nodes too)."""
    found = []
    for m in [*problem.runningModels, problem.terminalModel]:
        costs = getattr(getattr(m, "differential", m), "costs", None)
        for item in costs.costs.values():
            residual = getattr(item.cost, "residual", None)
            if type(residual) is cls:
                found.append(residual)
    return found


def first_running_dam(problem):
    return problem.runningModels[0].differential


def frame(problem, name: str) -> int:
    return problem.runningModels[0].state.pinocchio.getFrameId(name)


def in_place(write: Callable[[], None]) -> None:
    """An in-place write into a getter's array: allowed when the array is live, ValueError when read-only."""
    try:
        write()
    except ValueError as error:
        assert "read-only" in str(error)


# ---------------------------------------------------------------------------------------------------- mutations
def set_frame_id(p):
    for r in residuals(p, crocopy.ResidualModelFrameTranslation):
        r.id = frame(p, "LF_FOOT") if "LF_FOOT" in [f.name for f in r.state.pinocchio.frames] else r.id - 1


def switched(dam) -> str:
    """The cost the status cases switch: the walk's joint-limit barrier, the arm's goal (switching the arm's state
    regularisation off leaves a problem so ill-conditioned that round-off alone separates kernels on and off)."""
    return "limits" if "limits" in dam.costs.costs else "goal"


def deactivate_cost(p):
    for dam in dams(p):
        dam.costs.changeCostStatus(switched(dam), False)


def activate_cost(p):
    for dam in dams(p):
        dam.costs.changeCostStatus(switched(dam), True)


def scale_weights(p):
    for dam in dams(p):
        for item in dam.costs.costs.values():
            item.weight = 3.0 * item.weight


def replace_cost(p):
    for dam in dams(p):
        state, nu = dam.state, dam.nu
        dam.costs.removeCost("state")
        residual = crocopy.ResidualModelState(state, state.zero(), nu)
        dam.costs.addCost("state", crocopy.CostModelResidual(state, residual), 1e-2)


def add_cost(p):
    for dam in dams(p):
        state, nu = dam.state, dam.nu
        dam.costs.addCost("extra", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, nu)), 1.0)


def remove_cost(p):
    for dam in dams(p):
        dam.costs.removeCost(switched(dam))


def set_translation_reference(p):
    for r in residuals(p, crocopy.ResidualModelFrameTranslation):
        r.reference = r.reference + np.array([0.02, -0.01, 0.03])


def write_translation_reference(p):
    for r in residuals(p, crocopy.ResidualModelFrameTranslation):
        ref = r.reference
        in_place(lambda ref=ref: ref.__iadd__(np.array([0.02, -0.01, 0.03])))


def set_state_reference(p):
    for r in residuals(p, crocopy.ResidualModelState):
        xref = r.reference.copy()
        xref[-1] += 0.1
        r.reference = xref


def write_state_reference(p):
    for r in residuals(p, crocopy.ResidualModelState):
        ref = r.reference
        in_place(lambda ref=ref: ref.__setitem__(-1, ref[-1] + 0.1))


def set_control_reference(p):
    for r in residuals(p, crocopy.ResidualModelControl):
        r.reference = np.full(r.nu, 0.5)


def set_dt(p):
    for m in p.runningModels:
        if hasattr(m, "differential"):
            m.dt = 0.8 * m.dt


def set_armature(p):
    for dam in dams(p):
        dam.armature = np.full(dam.state.nv, 0.05)


def write_armature(p):
    for dam in dams(p):
        armature = dam.armature
        in_place(lambda a=armature: a.__setitem__(slice(None), 0.05))


def set_state_weights(p):
    for dam in dams(p):
        for item in dam.costs.costs.values():
            activation = item.cost.activation
            if type(activation) is crocopy.ActivationModelWeightedQuad:
                activation.weights = 2.0 * activation.weights


def write_state_weights(p):
    for dam in dams(p):
        for item in dam.costs.costs.values():
            activation = item.cost.activation
            if type(activation) is crocopy.ActivationModelWeightedQuad:
                w = activation.weights
                in_place(lambda w=w: w.__imul__(2.0))


def set_barrier_bounds(p):
    for dam in dams(p):
        for item in dam.costs.costs.values():
            activation = item.cost.activation
            if type(activation) is crocopy.ActivationModelQuadraticBarrier:
                lb, ub = activation.bounds.lb, activation.bounds.ub
                activation.bounds = crocopy.ActivationBounds(0.5 * lb, 0.5 * ub)


def set_com_reference(p):
    for r in residuals(p, crocopy.ResidualModelCoMPosition):
        r.reference = r.reference + np.array([0.01, 0.0, -0.02])


def set_friction_cone(p):
    for r in residuals(p, crocopy.ResidualModelContactFrictionCone):
        cone = r.reference
        r.reference = crocopy.FrictionCone(cone.R, 0.5, cone.nf, cone.inner_appr)


def contacts_of(p) -> list:
    return [dam.contacts for dam in dams(p) if hasattr(dam, "contacts")]


def switch_contact_off(p):
    for contacts in contacts_of(p):
        if len(contacts.active_set) == 4:
            contacts.changeContactStatus("LF_FOOT_contact", False)


def set_contact_reference(p):
    for contacts in contacts_of(p):
        for item in contacts.contacts.values():
            item.contact.reference = item.contact.reference + np.array([0.0, 0.0, 0.01])


def write_contact_reference(p):
    for contacts in contacts_of(p):
        for item in contacts.contacts.values():
            ref = item.contact.reference
            in_place(lambda ref=ref: ref.__iadd__(np.array([0.0, 0.0, 0.01])))


def set_contact_gains(p):
    for contacts in contacts_of(p):
        for item in contacts.contacts.values():
            item.contact.gains = np.array([0.0, 30.0])


def set_damping(p):
    for dam in dams(p):
        if hasattr(dam, "JMinvJt_damping"):
            dam.JMinvJt_damping = 1e-3


# the arm gets extra residual kinds (placement, rotation, velocity) for the cases on them
def add_arm_kinds(p):
    for dam in dams(p):
        state, nu = dam.state, dam.nu
        fid = state.pinocchio.nframes - 1
        placement = crocopy.ResidualModelFramePlacement(state, fid, pin.SE3(np.eye(3), np.array([0.4, 0.3, 0.6])), nu)
        rotation = crocopy.ResidualModelFrameRotation(state, fid, np.eye(3), nu)
        velocity = crocopy.ResidualModelFrameVelocity(state, fid, pin.Motion(np.full(6, 0.1)), pin.LOCAL, nu)
        for name, residual in (("placement", placement), ("rotation", rotation), ("velocity", velocity)):
            dam.costs.addCost(name, crocopy.CostModelResidual(state, residual), 1.0)


def write_placement_reference(p):
    for r in residuals(p, crocopy.ResidualModelFramePlacement):
        r.reference.translation = np.array([0.3, 0.2, 0.5])


def set_placement_reference(p):
    for r in residuals(p, crocopy.ResidualModelFramePlacement):
        r.reference = pin.SE3(pin.utils.rotate("z", 0.3), np.array([0.3, 0.2, 0.5]))


def set_rotation_reference(p):
    for r in residuals(p, crocopy.ResidualModelFrameRotation):
        r.reference = pin.utils.rotate("x", 0.4)


def write_rotation_reference(p):
    for r in residuals(p, crocopy.ResidualModelFrameRotation):
        ref = r.reference
        in_place(lambda ref=ref: ref.__setitem__(slice(None), pin.utils.rotate("x", 0.4)))


def set_velocity_type(p):
    for r in residuals(p, crocopy.ResidualModelFrameVelocity):
        r.type = pin.LOCAL_WORLD_ALIGNED


def write_velocity_reference(p):
    for r in residuals(p, crocopy.ResidualModelFrameVelocity):
        r.reference.linear = np.array([0.2, -0.1, 0.0])


def set_velocity_reference(p):
    for r in residuals(p, crocopy.ResidualModelFrameVelocity):
        r.reference = pin.Motion(np.array([0.2, -0.1, 0.0, 0.0, 0.1, 0.0]))


def set_control_bounds(p):
    for m in p.runningModels:
        if m.nu:
            m.u_lb = 0.5 * m.u_lb
            m.u_ub = 0.5 * m.u_ub


def set_thrusters(p):
    for m in p.runningModels:
        actuation = m.differential.actuation
        thrusters = [crocopy.Thruster(t.pose, 1.05 * t.ctorque, t.type, t.min_thrust, t.max_thrust)
                     for t in actuation.thrusters]
        actuation.thrusters = thrusters


CASES = {
    # name: (problems, prepare (on both, before the fresh ShootingProblem), mutation)
    "frame id": (("arm", "walk"), None, set_frame_id),
    "cost off": (("arm", "walk"), None, deactivate_cost),
    "cost on": (("arm", "walk"), deactivate_cost, activate_cost),
    "cost weights": (("arm", "walk"), None, scale_weights),
    "cost replaced": (("arm", "walk"), None, replace_cost),
    "cost added": (("arm", "walk"), None, add_cost),
    "cost removed": (("arm", "walk"), None, remove_cost),
    "translation reference": (("arm", "walk"), None, set_translation_reference),
    "translation reference in place": (("arm", "walk"), None, write_translation_reference),
    "state reference": (("arm", "walk"), None, set_state_reference),
    "state reference in place": (("arm", "walk"), None, write_state_reference),
    "control reference": (("arm",), None, set_control_reference),
    "dt": (("arm", "walk"), None, set_dt),
    "armature": (("arm", "walk"), None, set_armature),
    "armature in place": (("arm", "walk"), None, write_armature),
    "activation weights": (("walk",), None, set_state_weights),
    "activation weights in place": (("walk",), None, write_state_weights),
    "barrier bounds": (("walk",), None, set_barrier_bounds),
    "com reference": (("walk",), None, set_com_reference),
    "friction cone": (("walk",), None, set_friction_cone),
    "contact off": (("walk",), None, switch_contact_off),
    "contact on": (("walk",), switch_contact_off, lambda p: [c.changeContactStatus(n, True) for c in contacts_of(p)
                                                           for n in c.inactive_set]),
    "contact reference": (("walk",), None, set_contact_reference),
    "contact reference in place": (("walk",), None, write_contact_reference),
    "contact gains": (("walk",), None, set_contact_gains),
    "contact damping": (("walk",), None, set_damping),
    "placement reference": (("arm",), add_arm_kinds, set_placement_reference),
    "placement reference in place": (("arm",), add_arm_kinds, write_placement_reference),
    "rotation reference": (("arm",), add_arm_kinds, set_rotation_reference),
    "rotation reference in place": (("arm",), add_arm_kinds, write_rotation_reference),
    "velocity type": (("arm",), add_arm_kinds, set_velocity_type),
    "velocity reference": (("arm",), add_arm_kinds, set_velocity_reference),
    "velocity reference in place": (("arm",), add_arm_kinds, write_velocity_reference),
    "control bounds": (("arm", "quadrotor"), None, set_control_bounds),
    "thrusters": (("quadrotor",), None, set_thrusters),
}


def prepared(name: str, prepare):
    problem, xs, us = PROBLEMS[name]()
    if prepare is not None:
        prepare(problem)
        problem = crocopy.ShootingProblem(problem.x0, problem.runningModels, problem.terminalModel)
    return problem, xs, us


def solve(problem, xs, us, maxiter: int) -> tuple[int, float]:
    """A Box-FDDP solve (it reads the control bounds; without active bounds its steps are FDDP's)."""
    solver = crocopy.SolverBoxFDDP(problem)
    solver.solve([x.copy() for x in xs], [u.copy() for u in us], maxiter)
    return solver.iter, solver.cost


def mutated_then_solved(name: str, prepare, mutate, kernels: bool) -> tuple[int, float]:
    with crocopy.use_kernels(kernels):
        problem, xs, us = prepared(name, prepare)
        solve(problem, xs, us, 2)
        problem.calc(xs, us)
        problem.calcDiff(xs, us)
        mutate(problem)
        return solve(problem, xs, us, MAXITER)


def fresh_solve(name: str, prepare, mutate, kernels: bool) -> tuple[int, float]:
    with crocopy.use_kernels(kernels):
        problem, xs, us = prepared(name, prepare)
        mutate(problem)
        fresh = crocopy.ShootingProblem(problem.x0, problem.runningModels, problem.terminalModel)
        return solve(fresh, xs, us, MAXITER)


@pytest.mark.parametrize(("problem", "case"), [(p, c) for c, (ps, _, _) in CASES.items() for p in ps])
def test_mutation_gives_a_fresh_problems_solve(problem, case):
    _, prepare, mutate = CASES[case]
    results = {}
    for kernels in (True, False):
        mutated = mutated_then_solved(problem, prepare, mutate, kernels)
        fresh = fresh_solve(problem, prepare, mutate, kernels)
        assert mutated[0] == fresh[0], (kernels, mutated, fresh)
        assert mutated[1] == pytest.approx(fresh[1], rel=1e-9), (kernels, mutated, fresh)
        results[kernels] = fresh
    assert results[True][0] == results[False][0]
    assert results[True][1] == pytest.approx(results[False][1], rel=1e-7)


def mpc_targets(steps: int) -> list[np.ndarray]:
    """A reference that moves every step (a circle in front of the arm)."""
    s = np.linspace(0.0, 2.0 * np.pi, steps)
    return [np.array([0.4 + 0.1 * np.cos(a), 0.3 + 0.1 * np.sin(a), 0.6]) for a in s]


def mpc_fresh(target: np.ndarray, x0: np.ndarray, weight: float, dt_scale: float):
    problem, _, _ = arm.build_arm_reaching(crocopy, target=target, nodes=10)
    problem.x0 = x0
    for dam in dams(problem):
        dam.costs.costs["goal"].weight = weight * dam.costs.costs["goal"].weight
    for m in problem.runningModels:
        m.dt = dt_scale * m.dt
    return problem


@pytest.mark.parametrize(("kernels", "steps"), [(True, 500), (False, 60)])
def test_mpc_loop_equals_fresh_problems(kernels, steps):
    """Receding horizon: every step moves x0 and the goal reference (setters: values only), every seventh step the
    time step (a value too) and every tenth step the goal weight (a value of the cost stack, re-read in place), then
    solves from the previous solution; each step equals a problem built afresh with those values."""
    with crocopy.use_kernels(kernels):
        problem, xs, us = build_arm()
        solver = crocopy.SolverFDDP(problem)
        weight, dt_scale, dt = 1.0, 1.0, problem.runningModels[0].dt
        for step, target in enumerate(mpc_targets(steps)):
            if step % 10 == 9:
                weight = 2.0 if weight == 1.0 else 1.0
                for dam in dams(problem):
                    item = dam.costs.costs["goal"]
                    item.weight = (1e4 if dam is dams(problem)[-1] else 1e1) * weight
            if step % 7 == 6:
                dt_scale = 0.9 if dt_scale == 1.0 else 1.0
                for m in problem.runningModels:
                    m.dt = dt_scale * dt
            for r in residuals(problem, crocopy.ResidualModelFrameTranslation):
                r.reference = target
            warm_xs, warm_us = [x.copy() for x in xs], [u.copy() for u in us]
            solver.solve(warm_xs, warm_us, 2)
            fresh = crocopy.SolverFDDP(mpc_fresh(target, problem.x0, weight, dt_scale))
            fresh.solve(warm_xs, warm_us, 2)
            assert solver.iter == fresh.iter, step
            assert solver.cost == pytest.approx(fresh.cost, rel=1e-9), step
            assert np.isfinite(solver.cost)
            xs = [*solver.xs[1:], solver.xs[-1].copy()]
            us = [*solver.us[1:], solver.us[-1].copy()]
            problem.x0 = solver.xs[1].copy()


@pytest.mark.parametrize("kernels", [True, False], ids=["kernels", "python"])
@pytest.mark.parametrize("name", sorted(PROBLEMS))
def test_evaluations_and_solves_touch_no_parameter(name, kernels):
    """Neither a solve nor a Python-path evaluation assigns a model's public attribute: the parameter clock, read
    by compiled nodes and the cost stacks, stays where it was (else every solve would re-read every node)."""
    from crocopy.versioning import STRUCTURE, ParametersVersion

    with crocopy.use_kernels(kernels):
        problem, xs, us = PROBLEMS[name]()
        solve(problem, xs, us, 2)
        clock, structure = ParametersVersion.value, STRUCTURE[0]
        problem.calc(xs, us)
        problem.calcDiff(xs, us)
        solve(problem, xs, us, 2)
        assert (ParametersVersion.value, STRUCTURE[0]) == (clock, structure)


def test_read_only_attributes_as_in_crocoddyl():
    problem, _, _ = build_arm()
    iam = problem.runningModels[0]
    dam = iam.differential
    for owner, name, value in ((dam, "actuation", dam.actuation), (iam, "differential", dam), (dam, "state", dam.state),
                               (dam, "costs", dam.costs), (dam.costs.costs["goal"].cost, "residual",
                                                           dam.costs.costs["goal"].cost.residual)):
        with pytest.raises(AttributeError, match="read-only"):
            setattr(owner, name, value)


def test_constructors_copy_their_references():
    problem, _, _ = build_arm()
    state = problem.runningModels[0].state
    xref = state.zero()
    residual = crocopy.ResidualModelState(state, xref, state.nv)
    xref[-1] += 0.5
    assert residual.reference[-1] == xref[-1] - 0.5
    with pytest.raises(ValueError, match="read-only"):
        residual.reference[0] = 1.0
