"""Compiled Euler nodes of free and contact inverse dynamics (:mod:`crocopy.models.rbd.invdyn_node`) against the Python
node: values, every derivative and the constraint rows; solves with and without kernels; mutations between solves;
the reasons a node keeps its Python path.

Factories cross actuations (full: the arm; linear with an unactuated joint: kinova; floating base: ANYmal, whose
``"tau"`` equality has six rows; thrusters: the quadrotor), 3D contacts (LOCAL and LOCAL_WORLD_ALIGNED, Baumgarte
gains) and 6D contacts (Talos legs), with every residual kind the scripts use (state, control, frame placement and
velocity, centre of mass, friction and wrench cones, joint effort, also with ``fwddyn=True``, joint acceleration,
the actuation and contact-acceleration residuals as costs) and a frame-translation inequality beside the models' own
equalities.  The Python derivatives are checked
against finite differences in ``tests/test_invdyn.py``; here the compiled ones equal them to ``1e-10`` relative to
each field's largest entry.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from node_checks import make_solver
from robots import frame, load
from test_invdyn import _thrusters
from test_residual_numba import user_residuals

import crocopy
from crocopy.solvers import compiled_nodes

pytestmark = pytest.mark.skipif(not crocopy.kernels_enabled(), reason="compiled nodes need numba")

FIELDS = ("xnext", "Fx", "Fu", "Lx", "Lu", "Lxx", "Lxu", "Luu", "g", "Gx", "Gu", "h", "Hx", "Hu")
TERMINAL_FIELDS = ("xnext", "Fx", "Lx", "Lxx", "g", "Gx", "h", "Hx")
FREE = ("talos_arm", "kinova", "anymal", "iris")
CONTACT = ("anymal-local", "anymal-lwa", "talos-6d", "talos-6d-lwa", "anymal-1d")
RTOL = 1e-10
FEET = {"anymal": ("LF_FOOT", "RF_FOOT", "LH_FOOT"), "talos_legs": ("left_sole_link", "right_sole_link")}


def _actuation(robot: str, state):
    if robot == "iris":
        return _thrusters(state)
    if robot == "talos_arm":
        return crocopy.ActuationModelFull(state)
    if robot == "kinova":  # a linear actuation that leaves the first joint unactuated: one "tau" row
        S = np.eye(state.nv)[:, 1:] + 0.1 * np.eye(state.nv, state.nv - 1, -1)
        S[0] = 0.0
        return crocopy.ActuationModelLinear(state, S)
    return crocopy.ActuationModelFloatingBase(state)


def _costs(state, actuation, nu: int, fid: int, terminal: bool, contact: tuple | None = None):
    """Every residual kind the node takes (the running-only ones when not ``terminal``)."""
    costs = crocopy.CostModelSum(state, nu)
    rng = np.random.default_rng(3)
    items = {
        "x": crocopy.ResidualModelState(state, state.rand(), nu),
        "u": crocopy.ResidualModelControl(state, rng.normal(size=nu)),
        "place": crocopy.ResidualModelFramePlacement(state, fid, pin.SE3(pin.exp3(np.ones(3)), np.ones(3)), nu),
        "vel": crocopy.ResidualModelFrameVelocity(state, fid, pin.Motion(np.arange(6.0)), pin.LOCAL_WORLD_ALIGNED, nu),
        "effort": crocopy.ResidualModelJointEffort(state, actuation, np.linspace(-1, 1, actuation.nu), nu),
        "effort-fwd": crocopy.ResidualModelJointEffort(state, actuation, np.zeros(actuation.nu), nu, True),
        "acc": crocopy.ResidualModelJointAcceleration(state, np.linspace(-1, 1, state.nv), nu),
        "com": crocopy.ResidualModelCoMPosition(state, np.ones(3), nu),
        "h": crocopy.ResidualModelCentroidalMomentum(state, np.linspace(-1, 1, 6), nu),
    }
    nc_total = nu - state.nv
    if not terminal and actuation.nu < state.nv:
        residual = (crocopy.DifferentialActionModelContactInvDynamics.ResidualModelActuation(
            state, actuation.nu, nc_total) if contact else
            crocopy.DifferentialActionModelFreeInvDynamics.ResidualModelActuation(state, actuation.nu))
        items["tau"] = residual
    if contact is not None:
        cfid, nc = contact
        if nc == 3:
            cone = crocopy.FrictionCone(np.eye(3), 0.7, 4, False)
            items["cone"] = crocopy.ResidualModelContactFrictionCone(state, cfid, cone, nu)
        else:
            cone = crocopy.WrenchCone(np.eye(3), 0.7, np.array([0.1, 0.05]), 4, False)
            items["cone"] = crocopy.ResidualModelContactWrenchCone(state, cfid, cone, nu)
        if not terminal:
            items["acc-c"] = crocopy.DifferentialActionModelContactInvDynamics.ResidualModelContact(
                state, cfid, nc, nc_total)
    for i, (name, residual) in enumerate(items.items()):
        costs.addCost(name, crocopy.CostModelResidual(state, residual), 0.1 * (i + 1))
    return costs


def _box(state, nu: int, fid: int):
    constraints = crocopy.ConstraintModelManager(state, nu)
    bound = crocopy.ResidualModelFrameTranslation(state, fid, np.zeros(3), nu)
    constraints.addConstraint("box", crocopy.ConstraintModelResidual(state, bound, -np.ones(3), np.ones(3)))
    return constraints


def free_node(robot: str, terminal: bool = False, dt: float = 0.01):
    """An Euler node of free inverse dynamics of ``robot`` (``"iris"``: the quadrotor with thrusters)."""
    model = load(robot)
    state = crocopy.StateMultibody(model)
    actuation = _actuation(robot, state)
    fid = model.getFrameId(frame(robot)) if robot != "iris" else model.nframes - 1
    costs = _costs(state, actuation, state.nv, fid, terminal)
    dam = crocopy.DifferentialActionModelFreeInvDynamics(state, actuation, costs, _box(state, state.nv, fid))
    return crocopy.IntegratedActionModelEuler(dam, dt)


def contact_node(case: str, terminal: bool = False, inactive: bool = False, dt: float = 0.01):
    """An Euler node of contact inverse dynamics: ANYmal on three 3D feet (``case`` ``anymal-local``: the first in
    LOCAL coordinates; ``anymal-1d``: the first a 1D contact along a rotated axis; the model takes no 2D contact) or
    Talos legs on two 6D soles, with Baumgarte gains."""
    robot = "talos_legs" if case.startswith("talos") else "anymal"
    model = load(robot)
    state = crocopy.StateMultibody(model)
    actuation = crocopy.ActuationModelFloatingBase(state)
    six = robot == "talos_legs"
    names = FEET[robot]
    nc = 6 if six else 3
    mixed = case == "anymal-1d"
    nu = state.nv + (7 if mixed else nc * len(names))
    contacts = crocopy.ContactModelMultiple(state, nu)
    rng = np.random.default_rng(7)
    lwa = case.endswith("lwa")
    gains = ((0.0, 40.0), (10.0, 5.0), (3.0, 0.0))
    for i, name in enumerate(names):
        fid = model.getFrameId(name)
        reference = pin.LOCAL_WORLD_ALIGNED if lwa or i > 0 else pin.LOCAL
        if six:
            ref = pin.SE3(pin.exp3(0.3 * rng.normal(size=3)), rng.normal(size=3))
            contact = crocopy.ContactModel6D(state, fid, ref, reference, nu, np.array(gains[i]))
        elif mixed and i == 0:
            axis = pin.rpy.rpyToMatrix(0.3, -0.2, 0.4)
            contact = crocopy.ContactModel1D(state, fid, rng.normal(), pin.LOCAL_WORLD_ALIGNED, axis, nu,
                                             np.array(gains[i]))
        else:
            contact = crocopy.ContactModel3D(state, fid, rng.normal(size=3), reference, nu, np.array(gains[i]))
        contacts.addContact(f"{name}_contact", contact, not (inactive and i == len(names) - 1))
    cfid = model.getFrameId(names[1])
    fid = model.getFrameId(frame(robot))
    costs = _costs(state, actuation, nu, fid, terminal, (cfid, nc))
    dam = crocopy.DifferentialActionModelContactInvDynamics(state, actuation, contacts, costs, _box(state, nu, fid))
    return crocopy.IntegratedActionModelEuler(dam, dt)


def point(iam, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    m = iam.state.pinocchio
    q = pin.integrate(m, pin.neutral(m), 0.4 * rng.normal(size=m.nv))
    return np.concatenate([q, rng.normal(size=m.nv)]), 2.0 * rng.normal(size=iam.nu)


def assert_as_python(iam, data, x, u, terminal: bool, rtol: float) -> None:
    """``data`` (written by a compiled node at ``(x, u)``) equals the Python node's values, derivatives and rows."""
    slow = iam.createData()
    uu = None if terminal else u
    iam.calc(slow, x, uu)
    iam.calcDiff(slow, x, uu)
    assert data.cost == pytest.approx(slow.cost, rel=1e-10, abs=1e-12)
    for name in TERMINAL_FIELDS if terminal else FIELDS:
        a, b = getattr(data, name), getattr(slow, name)
        np.testing.assert_allclose(a, b, rtol=rtol, atol=rtol * max(1.0, np.abs(b).max(initial=0.0)), err_msg=name)


def _compare(iam, terminal: bool, seed: int = 0) -> None:
    x, u = point(iam, seed)
    data = iam.createData()
    evaluator = iam._compiled_node(data, terminal, {})
    assert type(evaluator).__name__ == "InvDynNode"
    uu = None if terminal else u
    evaluator.calcDiff(x, uu, False)
    assert_as_python(iam, data, x, u, terminal, RTOL)
    other = iam.createData()
    evaluator.calc(x, uu)
    iam.calc(other, x, uu)
    assert data.cost == pytest.approx(other.cost, rel=1e-12, abs=1e-14)
    for name in ("xnext", "g", "h"):
        np.testing.assert_allclose(getattr(data, name), getattr(other, name), rtol=1e-12, atol=1e-12, err_msg=name)


@pytest.mark.parametrize("terminal", [False, True], ids=["running", "terminal"])
@pytest.mark.parametrize("robot", FREE)
def test_free_node_equals_the_python_node(robot, terminal):
    iam = free_node(robot, terminal)
    for seed in range(2):
        _compare(iam, terminal, seed)


@pytest.mark.parametrize("terminal", [False, True], ids=["running", "terminal"])
@pytest.mark.parametrize("case", CONTACT)
def test_contact_node_equals_the_python_node(case, terminal):
    iam = contact_node(case, terminal)
    for seed in range(2):
        _compare(iam, terminal, seed)


@pytest.mark.parametrize("name", ["translation", "up axis", "com height"])
def test_a_users_numba_residual_stays_compiled(name):
    """A user's ``ResidualModelNumba`` (C callbacks, kind ``USER``) as a cost and as an inequality."""
    for robot in ("talos_arm", "anymal-lwa"):
        for terminal in (False, True):
            iam = free_node(robot, terminal) if robot == "talos_arm" else contact_node(robot, terminal)
            dam = iam.differential
            state, frame = dam.state, dam.state.pinocchio.nframes - 1
            dam.costs.addCost("user", crocopy.CostModelResidual(state, user_residuals(state, frame, dam.nu)[name]), 3.0)
            bound = user_residuals(state, frame, dam.nu)[name]
            dam.constraints.addConstraint("user", crocopy.ConstraintModelResidual(
                state, bound, -np.ones(bound.nr), np.ones(bound.nr)))
            _compare(iam, terminal)


def test_the_actuation_and_contact_rows_are_equalities_of_the_node():
    """The models' own equalities (``"tau"``: six rows on a floating base; ``"<contact>_acc"``) are the node's ``h``."""
    iam = contact_node("anymal-lwa")
    x, u = point(iam, 1)
    data = iam.createData()
    iam._compiled_node(data, False, {}).calcDiff(x, u, False)
    assert data.h.shape == (6 + 3 * 3,) and data.g.shape == (3,)
    assert np.abs(data.Hu).max() > 0 and np.abs(data.Hx).max() > 0
    assert_as_python(iam, data, x, u, False, RTOL)


@pytest.mark.parametrize("build", [lambda: contact_node("talos-6d"), lambda: free_node("anymal")],
                         ids=["contact", "free"])
def test_values_after_another_node_are_those_from_scratch(build):
    """A ``calc`` here, another node's evaluation (same lowered model: shared workspace and scratch), then
    ``calcDiff`` here at the same point (which skips the values: its stamp): the numbers, to the bit, of a
    ``calcDiff`` of a node evaluated nowhere else; then a ``calcDiff`` at another point evaluates its values."""
    iam = build()
    x, u = point(iam, 2)
    y, w = point(iam, 3)
    data, other, fresh = iam.createData(), iam.createData(), iam.createData()
    node, between, alone = (iam._compiled_node(d, False, {}) for d in (data, other, fresh))
    node.calc(x, u)
    assert node.stamp[0] == 1.0
    between.calcDiff(y, w, False)
    node.calcDiff(x, u, True)
    assert node.stamp[0] == 0.0
    alone.calcDiff(x, u, False)
    for name in (*FIELDS, "cost"):
        np.testing.assert_array_equal(getattr(data, name), getattr(fresh, name), err_msg=name)
    node.calc(x, u)
    node.calcDiff(y, w, False)
    alone.calcDiff(y, w, False)
    for name in (*FIELDS, "cost"):
        np.testing.assert_array_equal(getattr(data, name), getattr(fresh, name), err_msg=name)


def test_a_live_reread_spends_the_stamp():
    """An in-place write to a writeable reference (no setter: read again by ``refresh_live``, as a solve that keeps its
    compiled nodes does) between a ``calc`` and a ``calcDiff`` at the same point: the new values, not the stamped
    ones."""
    iam = free_node("talos_arm")
    x, u = point(iam, 6)
    data = iam.createData()
    node = iam._compiled_node(data, False, {})
    node.calc(x, u)
    effort = iam.differential.costs.costs["effort"].cost.residual
    effort.reference[:] = 2.0
    assert node.refresh_live({})
    node.calcDiff(x, u, True)
    assert_as_python(iam, data, x, u, False, RTOL)


@pytest.mark.parametrize("build", [lambda: contact_node("talos-6d"), lambda: free_node("anymal")],
                         ids=["contact", "free"])
def test_a_python_calc_of_the_data_in_between_spends_the_stamp(build):
    """The model's own ``calc`` on the node's data at another point between the compiled ``calc`` and ``calcDiff`` at
    one point (``data.compiled_stamp``): the ``calcDiff`` evaluates the values again."""
    iam = build()
    (x, u), (y, w) = point(iam, 7), point(iam, 8)
    data = iam.createData()
    node = iam._compiled_node(data, False, {})
    node.calc(x, u)
    iam.calc(data, y, w)
    assert node.stamp[0] == 0.0
    node.calcDiff(x, u, True)
    assert_as_python(iam, data, x, u, False, RTOL)


def test_the_rollout_step_is_the_feedback_control_then_calc():
    iam = free_node("anymal")
    data = iam.createData()
    node = iam._compiled_node(data, False, {})
    x_ref, u_ref = point(iam, 4)
    x, _ = point(iam, 5)
    nu, ndx = iam.nu, iam.state.ndx
    rng = np.random.default_rng(0)
    k, K = rng.normal(size=nu), 0.1 * rng.normal(size=(nu, ndx))
    lb, ub = -np.full(nu, 1.5), np.full(nu, 1.5)
    u, dx, x_next, f = np.zeros(nu), np.zeros(ndx), np.zeros(iam.state.nx), rng.normal(size=ndx)
    cost = node.rollout_step(x_ref, x, u_ref, k, K, 0.5, lb, ub, u, dx, x_next, f, True)
    dx_expected = iam.state.diff(x_ref, x)
    np.testing.assert_allclose(dx, dx_expected, atol=1e-12)
    np.testing.assert_allclose(u, np.clip(u_ref - 0.5 * k - K @ dx_expected, lb, ub), atol=1e-12)
    slow = iam.createData()
    iam.calc(slow, x, u)
    assert cost == pytest.approx(slow.cost, rel=1e-12)
    np.testing.assert_allclose(x_next, iam.state.integrate(slow.xnext, -0.5 * f), atol=1e-10)


# ----------------------------------------------------------------------------------------------------- problems
def arm_problem(T: int = 12):
    """The arm's reach under free inverse dynamics (as Crocoddyl's ``arm_manipulation_invdyn``): placement, state and
    joint-effort costs, the terminal placement and state costs."""
    model = load("talos_arm")
    state = crocopy.StateMultibody(model)
    actuation = crocopy.ActuationModelFull(state)
    nu = state.nv
    fid = model.getFrameId(frame("talos_arm"))
    goal = pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.4]))

    def dam(terminal: bool):
        costs = crocopy.CostModelSum(state, nu)
        costs.addCost("goal", crocopy.CostModelResidual(state, crocopy.ResidualModelFramePlacement(
            state, fid, goal, nu)), 1e3 if terminal else 1.0)
        costs.addCost("x", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, nu)), 1e-1)
        if not terminal:
            costs.addCost("u", crocopy.CostModelResidual(state, crocopy.ResidualModelJointEffort(
                state, actuation, nu)), 1e-2)
        return crocopy.DifferentialActionModelFreeInvDynamics(state, actuation, costs)

    running = crocopy.IntegratedActionModelEuler(dam(False), 1e-2)
    terminal = crocopy.IntegratedActionModelEuler(dam(True), 0.0)
    x0 = np.concatenate([pin.neutral(model) + 0.2, np.zeros(state.nv)])
    return crocopy.ShootingProblem(x0, [running] * T, terminal)


def quadruped_problem(T: int = 6):
    """ANYmal standing on four 3D feet under contact inverse dynamics (as the gaits of Crocoddyl's
    ``quadrupedal_gaits_invdyn``): CoM, state, joint-effort and friction-cone costs, the ``"tau"`` and
    ``"<foot>_acc"`` equalities."""
    model = load("anymal")
    state = crocopy.StateMultibody(model)
    actuation = crocopy.ActuationModelFloatingBase(state)
    feet = ("LF_FOOT", "RF_FOOT", "LH_FOOT", "RH_FOOT")
    nu = state.nv + 3 * len(feet)
    q0 = model.referenceConfigurations["standing"].copy()
    data = model.createData()
    pin.framesForwardKinematics(model, data, q0)
    com = pin.centerOfMass(model, data, q0)

    def dam(terminal: bool):
        contacts = crocopy.ContactModelMultiple(state, nu)
        costs = crocopy.CostModelSum(state, nu)
        for name in feet:
            fid = model.getFrameId(name)
            contacts.addContact(name, crocopy.ContactModel3D(state, fid, data.oMf[fid].translation,
                                                             pin.LOCAL_WORLD_ALIGNED, nu, np.array([5.0, 50.0])))
            cone = crocopy.FrictionCone(np.eye(3), 0.7, 4, False)
            residual = crocopy.ResidualModelContactFrictionCone(state, fid, cone, nu, False)
            bounds = crocopy.ActivationBounds(cone.lb, cone.ub)
            costs.addCost(name + "_cone", crocopy.CostModelResidual(
                state, crocopy.ActivationModelQuadraticBarrier(bounds), residual), 1e1)
        costs.addCost("com", crocopy.CostModelResidual(state, crocopy.ResidualModelCoMPosition(
            state, com + np.array([0.05, 0.0, -0.02]), nu)), 1e4 if terminal else 1e2)
        weights = np.array([0.0] * 3 + [500.0] * 3 + [0.01] * (state.nv - 6) + [10.0] * 6 + [1.0] * (state.nv - 6))
        x0 = np.concatenate([q0, np.zeros(state.nv)])
        costs.addCost("x", crocopy.CostModelResidual(state, crocopy.ActivationModelWeightedQuad(weights ** 2),
                                                     crocopy.ResidualModelState(state, x0, nu)), 1e1)
        costs.addCost("u", crocopy.CostModelResidual(state, crocopy.ResidualModelJointEffort(
            state, actuation, nu)), 1e-1)
        return crocopy.DifferentialActionModelContactInvDynamics(state, actuation, contacts, costs)

    running = crocopy.IntegratedActionModelEuler(dam(False), 1e-2)
    terminal = crocopy.IntegratedActionModelEuler(dam(True), 0.0)
    x0 = np.concatenate([q0, np.zeros(state.nv)])
    return crocopy.ShootingProblem(x0, [running] * T, terminal)


def _solve(problem, solver: str, kernels: bool, maxiter: int = 20):
    with crocopy.use_kernels(kernels):
        s = make_solver(solver, problem)
        guess = [problem.x0] * (problem.T + 1)
        s.solve(guess, problem.quasiStatic(guess[:-1]), maxiter)
    return s


@pytest.mark.parametrize(("build", "solver"), [(arm_problem, "SolverIntro"), (arm_problem, "SolverFDDP"),
                                               (quadruped_problem, "SolverIntro")])
def test_solves_with_and_without_kernels_are_the_same(build, solver):
    problem = build()
    assert all(type(e).__name__ == "InvDynNode" for e in
               [compiled_nodes.select(make_solver(solver, problem)).calcs[t].__self__ for t in range(problem.T + 1)])
    fast = _solve(problem, solver, True)
    slow = _solve(build(), solver, False)
    assert fast.iter == slow.iter > 1
    assert fast.cost == pytest.approx(slow.cost, rel=1e-9)
    for a, b in zip([*fast.xs, *fast.us], [*slow.xs, *slow.us]):
        np.testing.assert_allclose(a, b, rtol=1e-6, atol=1e-7)


def _effort(problem):
    return problem.runningModels[0].differential.costs.costs["u"].cost.residual


@pytest.mark.parametrize("mutation", ["setter", "in-place", "dt", "contact"])
def test_a_mutation_between_solves_is_read(mutation):
    """A second solve after a change equals a solve of a problem built with that change (never stale)."""
    build = quadruped_problem if mutation == "contact" else arm_problem

    def mutate(problem):
        if mutation == "setter":
            _effort(problem).reference = np.full(_effort(problem).nr, 0.3)
        elif mutation == "in-place":
            _effort(problem).reference[:] = 0.3
        elif mutation == "dt":
            problem.runningModels[0].dt = 2e-2
        else:
            contact = problem.runningModels[0].differential.contacts.contacts["LF_FOOT"].contact
            contact.reference = contact.reference + np.array([0.0, 0.0, 0.02])

    problem = build()
    before = _solve(problem, "SolverIntro", True, maxiter=3).cost
    mutate(problem)
    again = _solve(problem, "SolverIntro", True, maxiter=3)
    fresh = build()
    mutate(fresh)
    expected = _solve(fresh, "SolverIntro", False, maxiter=3)
    assert again.iter == expected.iter
    assert again.cost == pytest.approx(expected.cost, rel=1e-9)
    assert again.cost != pytest.approx(before, rel=1e-6)


# ------------------------------------------------------------------------------------------------------ reasons
def test_the_reasons_a_node_keeps_its_python_path():
    inactive = contact_node("anymal-lwa", inactive=True)
    grav = free_node("talos_arm")
    state = grav.state
    grav.differential.costs.addCost("grav", crocopy.CostModelResidual(
        state, crocopy.ResidualModelControlGrav(state, state.nv)), 1.0)
    terminal = contact_node("talos-6d")
    problem = crocopy.ShootingProblem(inactive.state.zero(), [inactive], contact_node("anymal-lwa", True))
    assert [c.reason for c in crocopy.compiled_coverage(problem)] == [
        "inactive contact in an inverse-dynamics node", None]
    problem = crocopy.ShootingProblem(state.zero(), [grav], free_node("talos_arm", True))
    assert [c.reason for c in crocopy.compiled_coverage(problem)] == ["residual ResidualModelControlGrav", None]
    problem = crocopy.ShootingProblem(terminal.state.zero(), [terminal], terminal)
    assert [c.reason for c in crocopy.compiled_coverage(problem)] == [
        None, "residual ResidualModelContact at the terminal node"]
