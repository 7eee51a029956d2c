"""Compiled nodes evaluate their constraint manager (:mod:`crocopy.models.rbd.constraint_rows`).

The rows ``g, Gx, Gu, h, Hx, Hu`` a compiled node writes (into the action data and the differential data) equal the
Python node's for every residual kind a constraint may have, inequalities and equalities interleaved by name, an
inactive constraint, and the terminal node (only ``T_constraint`` constraints); ``Gx``/``Gu``/``Hx``/``Hu`` equal
central differences of the compiled ``g``/``h``; CSQP solves take the same iterations and costs with kernels on and
off; a mutated problem (bounds, status, references) solves as a fresh one; nodes the lowering cannot take are
declined with their reason.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from robots import QUADRUPED_FEET, frame, load

import crocopy
from crocopy.models.rbd import constraint_rows_kernel
from crocopy.problems.user_residual import python_frame_translation

ROW_FIELDS = ("g", "Gx", "Gu", "h", "Hx", "Hu")


def _constraint(state, residual, kind: str, T_constraint: bool = True):
    """``residual`` as an inequality in a box around its value at the neutral state (``kind == "g"``), or an
    equality (``"h"``)."""
    if kind == "h":
        return crocopy.ConstraintModelResidual(state, residual, T_constraint)
    half = np.linspace(0.2, 0.9, residual.nr)
    return crocopy.ConstraintModelResidual(state, residual, -half, half, T_constraint)


def arm_manager(state, nu: int, names: tuple[str, ...]) -> crocopy.ConstraintModelManager:
    """A manager on the kinova arm with the constraints ``names`` (of :data:`ARM_CONSTRAINTS`)."""
    manager = crocopy.ConstraintModelManager(state, nu)
    fid = state.pinocchio.getFrameId(frame("kinova"))
    make = {
        "control": lambda: _constraint(state, crocopy.ResidualModelControl(state, np.full(nu, 0.1)), "g"),
        "translation": lambda: _constraint(
            state, crocopy.ResidualModelFrameTranslation(state, fid, np.array([0.3, 0.2, 0.5]), nu), "g"),
        "state": lambda: _constraint(state, crocopy.ResidualModelState(
            state, state.integrate(state.zero(), np.full(state.ndx, 0.05)), nu), "h"),
        "placement": lambda: _constraint(
            state, crocopy.ResidualModelFramePlacement(state, fid, pin.SE3(pin.utils.rotate("z", 0.3),
                                                                           np.array([0.3, 0.2, 0.5])), nu), "h"),
        "rotation": lambda: _constraint(state, crocopy.ResidualModelFrameRotation(state, fid, np.eye(3), nu), "g"),
        "velocity": lambda: _constraint(state, crocopy.ResidualModelFrameVelocity(
            state, fid, pin.Motion(np.full(6, 0.1)), pin.LOCAL_WORLD_ALIGNED, nu), "g"),
        "com": lambda: _constraint(state, crocopy.ResidualModelCoMPosition(state, np.array([0.0, 0.1, 0.4]), nu), "h"),
        "state not terminal": lambda: _constraint(state, crocopy.ResidualModelState(state, state.zero(), nu), "g",
                                                  False),
    }
    for name in names:
        manager.addConstraint(name, make[name]())
    return manager


ARM_CONSTRAINTS = ("control", "translation", "state", "placement", "rotation", "velocity", "com", "state not terminal")
CASES = {name: (name,) for name in ARM_CONSTRAINTS} | {"all": ARM_CONSTRAINTS}


def arm_node(names: tuple[str, ...], dt: float = 0.01, costs=None, inactive: tuple[str, ...] = ()):
    model = load("kinova")
    state = crocopy.StateMultibody(model)
    actuation = crocopy.ActuationModelFull(state)
    nu = actuation.nu
    if costs is None:
        costs = crocopy.CostModelSum(state, nu)
        costs.addCost("x", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, state.zero(), nu)), 1.0)
        costs.addCost("u", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, nu)), 1e-3)
    manager = arm_manager(state, nu, names)
    for name in inactive:
        manager.changeConstraintStatus(name, False)
    dam = crocopy.DifferentialActionModelFreeFwdDynamics(state, actuation, costs, manager)
    return crocopy.IntegratedActionModelEuler(dam, dt)


def solo_node(terminal: bool = False):
    """Solo12 on four 3D contacts, its CoM pushed forward by a cost, with joint-position limits (inequalities), the
    CoM kept in a box on the running nodes (inequality) and held 2 cm forward at the terminal node (equality); on the
    running nodes a friction cone on one foot and torque bounds (inequalities)."""
    model = load("solo12")
    state = crocopy.StateMultibody(model)
    actuation = crocopy.ActuationModelFloatingBase(state)
    nu = actuation.nu
    q0 = np.array(model.referenceConfigurations["standing"])
    data = model.createData()
    pin.framesForwardKinematics(model, data, q0)
    contacts = crocopy.ContactModelMultiple(state, nu)
    for name in QUADRUPED_FEET["solo12"]:
        fid = model.getFrameId(name)
        contacts.addContact(name, crocopy.ContactModel3D(state, fid, data.oMf[fid].translation,
                                                         pin.LOCAL_WORLD_ALIGNED, nu, np.array([0.0, 50.0])))
    costs = crocopy.CostModelSum(state, nu)
    costs.addCost("x", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, np.r_[q0, np.zeros(18)],
                                                                                   nu)), 1.0)
    com = pin.centerOfMass(model, data, q0)
    costs.addCost("com", crocopy.CostModelResidual(
        state, crocopy.ResidualModelCoMPosition(state, com + np.array([0.04, 0.0, 0.0]), nu)), 1e2)
    if not terminal:
        costs.addCost("u", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, nu)), 1e-2)
    manager = crocopy.ConstraintModelManager(state, nu)
    lower = np.r_[-np.inf * np.ones(6), q0[7:] - 0.15, -np.inf * np.ones(model.nv)]
    upper = np.r_[np.inf * np.ones(6), q0[7:] + 0.15, np.inf * np.ones(model.nv)]
    manager.addConstraint("joints", crocopy.ConstraintModelResidual(
        state, crocopy.ResidualModelState(state, state.zero(), nu), lower, upper))
    if terminal:
        manager.addConstraint("com", crocopy.ConstraintModelResidual(
            state, crocopy.ResidualModelCoMPosition(state, com + np.array([0.02, 0.0, 0.0]), nu)))
    else:
        manager.addConstraint("com", crocopy.ConstraintModelResidual(
            state, crocopy.ResidualModelCoMPosition(state, com, nu), np.full(3, -0.01), np.array([0.03, 0.01, 0.01])))
    if not terminal:
        cone = crocopy.FrictionCone(np.eye(3), 0.7, 4, False)
        friction = crocopy.ResidualModelContactFrictionCone(state, model.getFrameId("FL_FOOT"), cone, nu)
        manager.addConstraint("cone", crocopy.ConstraintModelResidual(state, friction, cone.lb, cone.ub))
        manager.addConstraint("torques", crocopy.ConstraintModelResidual(
            state, crocopy.ResidualModelControl(state, nu), -np.full(nu, 2.0), np.full(nu, 2.0)))
    dam = crocopy.DifferentialActionModelContactFwdDynamics(state, actuation, contacts, costs, manager, 0.0, True)
    return crocopy.IntegratedActionModelEuler(dam, 0.0 if terminal else 0.02), np.r_[q0, np.zeros(18)]


def random_point(iam, rng, x0=None):
    state = iam.state
    x = state.integrate(state.zero() if x0 is None else x0, 0.3 * rng.standard_normal(state.ndx))
    return x, rng.standard_normal(iam.nu)


def compare_rows(iam, x, u, terminal: bool) -> None:
    """The compiled node's ``calcDiff``/``calc`` rows equal the Python node's, in both datas."""
    fast, slow = iam.createData(), iam.createData()
    evaluator = iam._compiled_node(fast, terminal, {})
    assert evaluator is not None
    uu = None if terminal else u
    for step in ("calcDiff", "calc"):
        fast.g[:], fast.Gx[:], fast.h[:] = np.nan, np.nan, np.nan
        if step == "calcDiff":
            evaluator.calcDiff(x, uu, False)
            iam.calc(slow, x, uu)
            iam.calcDiff(slow, x, uu)
        else:
            evaluator.calc(x + 0.0, uu)
        names = ROW_FIELDS if step == "calcDiff" else ("g", "h")
        for name in names:
            for a, b in ((getattr(fast, name), getattr(slow, name)),
                         (getattr(fast.differential, name), getattr(slow.differential, name))):
                np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-9 * max(1.0, np.abs(b).max(initial=0.0)),
                                           err_msg=f"{step} {name}")
        assert fast.cost == pytest.approx(slow.cost, rel=1e-9)


@pytest.mark.parametrize("case", list(CASES))
@pytest.mark.parametrize("terminal", [False, True])
def test_arm_rows_equal_the_python_node(case, terminal):
    iam = arm_node(CASES[case])
    rng = np.random.default_rng(7)
    x, u = random_point(iam, rng)
    compare_rows(iam, x, u, terminal)
    expected = (iam.ng_T, iam.nh_T) if terminal else (iam.ng, iam.nh)
    data = iam.createData()
    iam._compiled_node(data, terminal, {}).calc(x, None if terminal else u)
    assert np.count_nonzero(data.g[expected[0]:]) == 0 and np.count_nonzero(data.h[expected[1]:]) == 0


def test_inactive_constraints_leave_no_rows():
    iam = arm_node(("control", "translation", "state"), inactive=("translation",))
    assert (iam.ng, iam.nh) == (iam.nu, iam.state.ndx)
    x, u = random_point(iam, np.random.default_rng(3))
    compare_rows(iam, x, u, False)


@pytest.mark.parametrize("terminal", [False, True])
def test_contact_rows_equal_the_python_node(terminal):
    iam, x0 = solo_node(terminal)
    rng = np.random.default_rng(11)
    state = iam.state
    x = state.integrate(x0, 0.05 * rng.standard_normal(state.ndx))
    compare_rows(iam, x, rng.standard_normal(iam.nu), terminal)


@pytest.mark.parametrize("terminal", [False, True])
def test_row_jacobians_equal_central_differences(terminal):
    iam = arm_node(ARM_CONSTRAINTS)
    state, nu = iam.state, iam.nu
    x, u = random_point(iam, np.random.default_rng(5))
    uu = None if terminal else u
    data = iam.createData()
    evaluator = iam._compiled_node(data, terminal, {})
    evaluator.calcDiff(x, uu, False)
    jac = {name: getattr(data, name).copy() for name in ROW_FIELDS}
    assert np.abs(jac["Gx"]).max() > 0.1 and np.abs(jac["Hx"]).max() > 0.1

    def rows(dx, du):
        evaluator.calc(state.integrate(x, dx), None if terminal else u + du)
        return data.g.copy(), data.h.copy()

    step = 1e-6
    for j in range(state.ndx + (0 if terminal else nu)):
        e = np.zeros(state.ndx + nu)
        e[j] = step
        (gp, hp), (gm, hm) = rows(e[:state.ndx], e[state.ndx:]), rows(-e[:state.ndx], -e[state.ndx:])
        for name, column in (("G", (gp - gm) / (2 * step)), ("H", (hp - hm) / (2 * step))):
            analytic = jac[name + "x"][:, j] if j < state.ndx else jac[name + "u"][:, j - state.ndx]
            np.testing.assert_allclose(column, analytic, rtol=1e-5, atol=1e-6, err_msg=f"{name} column {j}")
    if terminal:
        assert not jac["Gu"].any() and not jac["Hu"].any()


def arm_problem(T: int = 12):
    """A kinova reach (goal cost) whose running nodes bound the torques and keep the end effector in a box that the
    unconstrained motion leaves, and whose terminal node holds the end effector at a point by an equality."""
    model = load("kinova")
    state = crocopy.StateMultibody(model)
    actuation = crocopy.ActuationModelFull(state)
    nu = actuation.nu
    fid = model.getFrameId(frame("kinova"))
    x0 = np.r_[model.referenceConfigurations["arm_up"], np.zeros(model.nv)]

    def node(terminal: bool):
        costs = crocopy.CostModelSum(state, nu)
        goal = crocopy.ResidualModelFrameTranslation(state, fid, np.array([0.4, 0.3, 0.6]), nu)
        costs.addCost("goal", crocopy.CostModelResidual(state, goal), 1e3 if terminal else 1e1)
        costs.addCost("x", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, x0, nu)), 1e-1)
        manager = crocopy.ConstraintModelManager(state, nu)
        if terminal:
            manager.addConstraint("point", crocopy.ConstraintModelResidual(
                state, crocopy.ResidualModelFrameTranslation(state, fid, np.array([0.4, 0.3, 0.55]), nu)))
        else:
            costs.addCost("u", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, nu)), 1e-3)
            manager.addConstraint("control", crocopy.ConstraintModelResidual(
                state, crocopy.ResidualModelControl(state, nu), np.full(nu, -25.0), np.full(nu, 25.0)))
            manager.addConstraint("translation", crocopy.ConstraintModelResidual(
                state, crocopy.ResidualModelFrameTranslation(state, fid, np.zeros(3), nu),
                np.array([-1.0, -0.05, 0.45]), np.array([1.0, 1.0, 0.58])))
        dam = crocopy.DifferentialActionModelFreeFwdDynamics(state, actuation, costs, manager)
        return crocopy.IntegratedActionModelEuler(dam, 0.0 if terminal else 0.05)

    return crocopy.ShootingProblem(x0, [node(False) for _ in range(T)], node(True))


def csqp(problem, maxiter: int = 25, tolerance: float = 2e-3) -> tuple[int, float, float]:
    solver = crocopy.SolverCSQP(problem)
    solver.termination_tolerance = tolerance
    solver.solve([problem.x0] * (problem.T + 1), [np.zeros(m.nu) for m in problem.runningModels], maxiter)
    return solver.iter, solver.cost, solver.constraint_norm


@pytest.mark.parametrize("which", ["arm", "solo"])
def test_csqp_solves_alike_with_kernels_on_and_off(which):
    def build():
        if which == "arm":
            return arm_problem()
        running, x0 = solo_node(False)
        return crocopy.ShootingProblem(x0, [running] * 8, solo_node(True)[0])

    results = []
    for kernels in (True, False):
        with crocopy.use_kernels(kernels):
            problem = build()
            if kernels:
                assert all(c.compiled for c in crocopy.compiled_coverage(problem))
            results.append(csqp(problem, 25, 2e-3 if which == "arm" else 1e-5))
    assert results[0][0] == results[1][0] > 1
    assert results[0][1] == pytest.approx(results[1][1], rel=1e-9)
    assert results[0][2] == pytest.approx(results[1][2], rel=1e-6, abs=1e-10)


def _bounds(problem):
    for m in problem.runningModels:
        constraint = m.differential.constraints.constraints["translation"].constraint
        constraint.updateBounds(constraint.lb - 0.02, constraint.ub - 0.05)


def _off(problem):
    for m in problem.runningModels:
        m.differential.constraints.changeConstraintStatus("translation", False)


def _on(problem):
    for m in problem.runningModels:
        m.differential.constraints.changeConstraintStatus("translation", True)


def _reference(problem):
    for m in (*problem.runningModels, problem.terminalModel):
        for item in m.differential.constraints.constraints.values():
            residual = item.constraint.residual
            if isinstance(residual, crocopy.ResidualModelFrameTranslation):
                residual.reference = residual.reference + np.array([0.05, -0.02, 0.03])


MUTATIONS = {"bounds": (None, _bounds), "off": (None, _off), "on": (_off, _on), "reference": (None, _reference)}


@pytest.mark.parametrize("case", list(MUTATIONS))
def test_mutation_after_a_solve_gives_a_fresh_problems_solve(case):
    prepare, mutate = MUTATIONS[case]

    def prepared():
        problem = arm_problem(T=8)
        if prepare is not None:
            prepare(problem)
            problem = crocopy.ShootingProblem(problem.x0, problem.runningModels, problem.terminalModel)
        return problem

    results = {}
    for kernels in (True, False):
        with crocopy.use_kernels(kernels):
            baseline = csqp(prepared(), 8)
            problem = prepared()
            csqp(problem, 2)
            xs = [problem.x0] * (problem.T + 1)
            us = [np.zeros(m.nu) for m in problem.runningModels]
            problem.calc(xs, us)
            problem.calcDiff(xs, us)
            mutate(problem)
            mutated = csqp(problem, 8)
            fresh_problem = prepared()
            mutate(fresh_problem)
            fresh = csqp(crocopy.ShootingProblem(fresh_problem.x0, fresh_problem.runningModels,
                                                 fresh_problem.terminalModel), 8)
        assert mutated[:2] == pytest.approx(fresh[:2], rel=1e-9), (kernels, mutated, fresh)
        assert mutated[1] != pytest.approx(baseline[1], rel=1e-6)
        results[kernels] = fresh
    assert results[True][0] == results[False][0]
    assert results[True][1] == pytest.approx(results[False][1], rel=1e-9)


@pytest.mark.parametrize("kernels", [True, False])
@pytest.mark.parametrize("case", list(MUTATIONS))
def test_a_solver_solving_again_after_a_mutation_gives_a_new_solvers_solve(case, kernels):
    """The same SolverCSQP follows bounds changed by ``updateBounds`` and constraints switched on or off (its QP rows
    and their bounds), as a solver made after the change does (both reset their multipliers and ρ at each QP, so
    that nothing else carries over from the first solve)."""
    prepare, mutate = MUTATIONS[case]

    def solver_for(problem):
        solver = crocopy.SolverCSQP(problem)
        solver.termination_tolerance = 2e-3
        solver.reset_y = solver.reset_rho = True
        return solver

    def solve(solver):
        problem = solver.problem
        solver.solve([problem.x0] * (problem.T + 1), [np.zeros(m.nu) for m in problem.runningModels], 8)
        return solver.iter, solver.cost, solver.constraint_norm

    with crocopy.use_kernels(kernels):
        problem = arm_problem(T=8)
        if prepare is not None:
            prepare(problem)
        solver = solver_for(problem)
        before = solve(solver)
        mutate(problem)
        again = solve(solver)
        fresh = solve(solver_for(problem))
    assert again[0] == fresh[0]
    assert again[1:] == pytest.approx(fresh[1:], rel=1e-9, abs=1e-12)
    assert again[1] != pytest.approx(before[1], rel=1e-6)


class UserConstraint(crocopy.ConstraintModelResidual):
    """A user's subclass: it may override ``calc``, so its node keeps the Python path."""


def test_nodes_the_lowering_cannot_take_are_declined_with_their_reason():
    base = arm_node(("control",))
    state, nu = base.state, base.nu
    dam = base.differential
    python = python_frame_translation(crocopy)(state, state.pinocchio.nframes - 1, np.zeros(3), nu)
    cases = {
        "user Python subclass: constraint UserConstraint": crocopy.ConstraintModelResidual,
        "user Python subclass: constraint residual PythonFrameTranslation": None,
    }
    reasons = []
    for cls in cases.values():
        manager = crocopy.ConstraintModelManager(state, nu)
        if cls is None:
            manager.addConstraint("python", crocopy.ConstraintModelResidual(state, python))
        else:
            manager.addConstraint("user", UserConstraint(state, crocopy.ResidualModelControl(state, nu)))
        iam = crocopy.IntegratedActionModelEuler(
            crocopy.DifferentialActionModelFreeFwdDynamics(state, dam.actuation, dam.costs, manager), 0.01)
        problem = crocopy.ShootingProblem(state.zero(), [iam], base)
        reasons.append(crocopy.compiled_coverage(problem)[0].reason)
    assert reasons == list(cases)


def test_a_node_without_constraints_skips_the_rows():
    for names, rows in (((), False), (("control",), True)):
        iam = arm_node(names)
        evaluator = iam._compiled_node(iam.createData(), False, {})
        assert bool(constraint_rows_kernel.has_rows(evaluator.ints)) is rows


@pytest.mark.parametrize("name", ["SolverIntro", "SolverProjection"])
def test_equality_solvers_take_compiled_nodes_with_rows(name):
    """Intro and projection read the action datas' equality rows, which compiled nodes write: the same iterations
    and cost with compiled nodes, with the models' own evaluations, and with kernels off."""
    from node_checks import make_solver

    from crocopy.solvers import compiled_nodes

    def build():
        running, terminal = arm_node(("control", "translation"), dt=0.02), arm_node((), dt=0.0)
        manager = running.differential.constraints
        reference = crocopy.ResidualModelControl(running.state, np.full(running.nu, 0.3))
        manager.removeConstraint("control")
        manager.addConstraint("control", crocopy.ConstraintModelResidual(running.state, reference))
        x0 = running.state.integrate(running.state.zero(), np.full(running.state.ndx, 0.1))
        return crocopy.ShootingProblem(x0, [running] * 10, terminal)

    results = []
    for kernels, compiled in ((True, True), (True, False), (False, False)):
        with crocopy.use_kernels(kernels):
            problem = build()
            assert problem.runningModels[0].nh == problem.runningModels[0].nu
            solver = make_solver(name, problem, compiled)
            if kernels and compiled:
                assert compiled_nodes.select(solver) is not None
            solver.solve([problem.x0] * (problem.T + 1), [np.zeros(m.nu) for m in problem.runningModels], 20)
            us = np.array(solver.us)
            results.append((solver.iter, solver.cost, us))
    for iters, cost, _ in results[1:]:
        assert iters == results[0][0] > 0
        assert cost == pytest.approx(results[0][1], rel=1e-9)
    np.testing.assert_allclose(results[0][2], 0.3, atol=1e-6)


def test_two_threads_give_one_threads_rows_and_solve():
    """Each node fills its own constraint table from the table of the thread evaluating it: bit-identical solves."""
    results = []
    for nthreads in (1, 2):
        problem = arm_problem()
        problem.nthreads = nthreads
        solver = crocopy.SolverCSQP(problem)
        solver.termination_tolerance = 2e-3
        solver.solve([problem.x0] * (problem.T + 1), [np.zeros(m.nu) for m in problem.runningModels], 10)
        results.append((solver.iter, solver.cost, np.array([d.g.copy() for d in problem.runningDatas])))
    assert results[0][0] == results[1][0] and results[0][1] == results[1][1]
    np.testing.assert_array_equal(results[0][2], results[1][2])


@pytest.mark.parametrize("manager_nu", [0, 12])
def test_impulse_rows_equal_the_python_node(manager_nu):
    """An impulse node's manager: every active constraint when its ``nu`` is 0, else the ``T_constraint`` ones (as
    the Python model evaluates it)."""
    from test_impulse_node import impulse_model

    model = impulse_model("anymal-lwa")
    state = model.state
    foot = state.pinocchio.getFrameId("LF_FOOT")
    manager = crocopy.ConstraintModelManager(state, manager_nu)
    manager.addConstraint("com", crocopy.ConstraintModelResidual(
        state, crocopy.ResidualModelCoMPosition(state, np.array([0.0, 0.0, 0.4]), manager_nu)))
    manager.addConstraint("foot", _constraint(
        state, crocopy.ResidualModelFrameTranslation(state, foot, np.array([0.3, 0.2, 0.0]), manager_nu), "g"))
    manager.addConstraint("x", _constraint(state, crocopy.ResidualModelState(state, state.zero(), manager_nu), "g",
                                           False))
    constrained = crocopy.ActionModelImpulseFwdDynamics(state, model.impulses, model.costs, manager)
    rng = np.random.default_rng(2)
    x = state.integrate(state.zero(), 0.2 * rng.standard_normal(state.ndx))
    fast, slow = constrained.createData(), constrained.createData()
    evaluator = constrained._compiled_node(fast, False, {})
    assert evaluator is not None
    for step in ("calcDiff", "calc"):
        fast.g[:], fast.h[:] = np.nan, np.nan
        if step == "calcDiff":
            evaluator.calcDiff(x, np.zeros(0), False)
            constrained.calc(slow, x, np.zeros(0))
            constrained.calcDiff(slow, x, np.zeros(0))
        else:
            evaluator.calc(x, np.zeros(0))
        for name in ROW_FIELDS if step == "calcDiff" else ("g", "h"):
            a, b = getattr(fast, name), getattr(slow, name)
            np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-9 * max(1.0, np.abs(b).max(initial=0.0)),
                                       err_msg=f"{step} {name}")
    rows = state.ndx if manager_nu == 0 else 0
    assert np.count_nonzero(fast.g[3 + rows:]) == 0 and np.abs(fast.g[:3 + rows]).max() > 0


@pytest.mark.parametrize("terminal", [False, True])
def test_user_numba_residual_rows_equal_the_python_node(terminal):
    """A user's ``ResidualModelNumba`` as a constraint (an orientation equality and, on running nodes, a
    velocity-and-control box whose ``Ru`` goes to ``Gu``) beside a built-in one."""
    from test_residual_numba import UpAxis, VelocityControl

    iam = arm_node(("translation",))
    state, nu = iam.state, iam.nu
    manager = iam.differential.constraints
    fid = state.pinocchio.getFrameId(frame("kinova"))
    manager.addConstraint("up", crocopy.ConstraintModelResidual(state, UpAxis(state, fid, nu)))
    manager.addConstraint("vu", _constraint(state, VelocityControl(state, nu), "g"))
    iam = crocopy.IntegratedActionModelEuler(iam.differential, 0.01)
    x, u = random_point(iam, np.random.default_rng(9))
    compare_rows(iam, x, u, terminal)
    data = iam.createData()
    iam._compiled_node(data, terminal, {}).calcDiff(x, None if terminal else u, False)
    assert np.abs(data.Hx).max() > 0.1 and (terminal or np.abs(data.Gu).max() > 0.1)
