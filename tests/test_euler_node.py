"""The compiled Euler node of free forward dynamics equals the Python node and finite differences.

Factory: robots (free flyer with thrusters or a floating base, unbounded revolute joints, armature,
fixed base) x every compiled residual kind x quadratic-family activations, running and terminal.
"""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pinocchio as pin
import pytest
from node_checks import FIELDS, check_finite_differences, compare_with_python_node, make_solver
from robots import frame, load

import crocopy

pytestmark = pytest.mark.skipif(not crocopy.kernels_enabled(), reason="compiled nodes need numba")

ROBOTS = ("iris", "kinova", "talos_arm", "anymal", "double_pendulum")
FRAMES = {"iris": "iris__rotor_2", "double_pendulum": "link2"}
KINDS = ("state", "control", "placement", "translation", "rotation", "velocity_local", "velocity_world",
         "velocity_lwa", "effort", "acceleration", "control_grav", "centroidal")


ACTIVATIONS = (
    lambda nr, rng: crocopy.ActivationModelQuad(nr),
    lambda nr, rng: crocopy.ActivationModelWeightedQuad(rng.uniform(0.5, 2.0, nr)),
    lambda nr, rng: crocopy.ActivationModelQuadraticBarrier(crocopy.ActivationBounds(-0.1 * np.ones(nr),
                                                                                     0.1 * np.ones(nr))),
    lambda nr, rng: crocopy.ActivationModelSmooth1Norm(nr, rng.uniform(0.1, 2.0)),
    lambda nr, rng: crocopy.ActivationModelQuadFlatExp(nr, rng.uniform(1.0, 10.0), bool(rng.integers(2))),
    lambda nr, rng: crocopy.ActivationModelQuadFlatLog(nr, rng.uniform(1.0, 10.0), bool(rng.integers(2))),
    lambda nr, rng: crocopy.ActivationModelSmooth2Norm(nr, rng.uniform(0.1, 2.0)),
    lambda nr, rng: crocopy.ActivationModel2NormBarrier(nr, rng.uniform(2.0, 20.0), bool(rng.integers(2))),
)
"""The activations the node factory cycles through: the fused quadratic-barrier family, then those with an item form
(evaluated item by item in the node's kernel)."""


def robot_frame(robot: str) -> str:
    return FRAMES[robot] if robot in FRAMES else frame(robot)


def actuation(robot: str, state):
    if robot == "iris":
        thrusters = [crocopy.Thruster(pin.SE3(np.eye(3), np.array([0.2 * np.cos(a), 0.2 * np.sin(a), 0.0])),
                                      0.02, crocopy.ThrusterType.CW if i % 2 else crocopy.ThrusterType.CCW)
                     for i, a in enumerate(np.linspace(0.3, 6.0, 4))]
        return crocopy.ActuationModelFloatingBaseThrusters(state, thrusters)
    if robot == "anymal":
        return crocopy.ActuationModelFloatingBase(state)
    if robot == "double_pendulum":
        return crocopy.ActuationModelLinear(state, [[0.3], [1.0]])
    return crocopy.ActuationModelFull(state)


def residual(kind: str, state, act, fid: int, rng: np.random.Generator):
    nu = act.nu
    if kind == "state":
        np.random.seed(int(rng.integers(1 << 30)))
        return crocopy.ResidualModelState(state, state.rand(), nu)
    if kind == "control":
        return crocopy.ResidualModelControl(state, rng.standard_normal(nu))
    if kind == "placement":
        return crocopy.ResidualModelFramePlacement(state, fid, pin.SE3.Random(), nu)
    if kind == "translation":
        return crocopy.ResidualModelFrameTranslation(state, fid, rng.standard_normal(3), nu)
    if kind == "rotation":
        return crocopy.ResidualModelFrameRotation(state, fid, pin.SE3.Random().rotation, nu)
    if kind == "effort":
        return crocopy.ResidualModelJointEffort(state, act, rng.standard_normal(nu), nu)
    if kind == "acceleration":
        return crocopy.ResidualModelJointAcceleration(state, rng.standard_normal(state.nv), nu)
    if kind == "control_grav":
        return crocopy.ResidualModelControlGrav(state, nu)
    if kind == "centroidal":
        return crocopy.ResidualModelCentroidalMomentum(state, rng.standard_normal(6), nu)
    reference = {"local": pin.LOCAL, "world": pin.WORLD, "lwa": pin.LOCAL_WORLD_ALIGNED}[kind.split("_")[1]]
    return crocopy.ResidualModelFrameVelocity(state, fid, pin.Motion.Random(), reference, nu)


def node(robot: str, kinds: tuple, seed: int = 0, dt: float = 0.01):
    """An Euler node of ``robot`` with one cost per kind (activations cycling through :data:`ACTIVATIONS`; the
    acceleration cost weighted 1e-4, so that the cost's central differences are not lost in its round-off)."""
    rng = np.random.default_rng(seed)
    model = load(robot) if robot not in ("iris", "double_pendulum") else _extra(robot)
    state = crocopy.StateMultibody(model)
    act = actuation(robot, state)
    fid = model.getFrameId(robot_frame(robot))
    costs = crocopy.CostModelSum(state, act.nu)
    for n, kind in enumerate(kinds):
        res = residual(kind, state, act, fid, rng)
        activation = ACTIVATIONS[n % len(ACTIVATIONS)](res.nr, rng)
        weight = rng.uniform(0.5, 3.0) * (1e-4 if kind == "acceleration" else 1.0)  # accelerations reach 1e2 here
        costs.addCost(kind, crocopy.CostModelResidual(state, activation, res), weight)
    dam = crocopy.DifferentialActionModelFreeFwdDynamics(state, act, costs)
    if robot == "talos_arm":
        dam.armature = 0.05 * np.ones(state.nv)
    return crocopy.IntegratedActionModelEuler(dam, dt), state


def _extra(robot: str) -> pin.Model:
    import example_robot_data

    return example_robot_data.load(robot).model


def point(state, nu: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(100 + seed)
    np.random.seed(100 + seed)
    x = state.rand()
    x[state.nq:] = rng.standard_normal(state.nv)
    return x, rng.standard_normal(nu)


def compare(iam, state, terminal: bool, seed: int = 0) -> None:
    """The compiled node's outputs equal the Python node's at a random point."""
    x, u = point(state, iam.nu, seed)
    compare_with_python_node(iam, x, u, terminal, rtol=1e-8, atol=1e-9, cost_rel=1e-10)


@pytest.mark.parametrize("robot", ROBOTS)
@pytest.mark.parametrize("terminal", [False, True])
def test_every_residual_kind_matches_the_python_node(robot, terminal):
    iam, state = node(robot, KINDS)
    compare(iam, state, terminal)


@pytest.mark.parametrize("kind", KINDS)
def test_each_kind_alone_on_a_floating_base(kind):
    iam, state = node("anymal", (kind,), seed=3)
    compare(iam, state, False, seed=3)


@pytest.mark.parametrize("robot", ["iris", "kinova"])
def test_derivatives_match_finite_differences(robot):
    """``Fx, Fu, Lx, Lu`` of the compiled node against central differences of its own ``calc``."""
    iam, state = node(robot, KINDS, seed=5)
    x, u = point(state, iam.nu, 5)
    check_finite_differences(iam, state, x, u, h=1e-6, atol=1e-5)


def test_nodes_that_do_not_qualify():
    iam, state = node("kinova", ("state", "control"))
    data = iam.createData()

    class Euler(crocopy.IntegratedActionModelEuler):
        pass

    assert Euler(iam.differential, 0.01)._compiled_node(Euler(iam.differential, 0.01).createData(), False, {}) is None
    costs = iam.differential.costs
    class Smooth1(crocopy.ActivationModelSmooth1Norm):  # a user's override: its item runs in Python
        def calc(self, data, r):
            super().calc(data, r)

    costs.addCost("grav", crocopy.CostModelResidual(
        state, Smooth1(6), crocopy.ResidualModelCentroidalMomentum(state, np.zeros(6), iam.nu)), 1.0)
    dam = crocopy.DifferentialActionModelFreeFwdDynamics(state, iam.differential.actuation, costs)
    other = crocopy.IntegratedActionModelEuler(dam, 0.01)
    assert other._compiled_node(other.createData(), False, {}) is None
    costs.changeCostStatus("grav", False)
    assert other._compiled_node(other.createData(), False, {}) is not None
    assert iam._compiled_node(data, False, {}) is not None


def test_copies_and_pickles_of_a_data_get_their_own_evaluator():
    iam, state = node("iris", ("state", "placement", "control"))
    data = iam.createData()
    first = iam._compiled_node(data, False, {})
    for other in (copy.deepcopy(data), copy.copy(data), pickle.loads(pickle.dumps(data))):
        evaluator = iam._compiled_node(other, False, {})
        assert evaluator is not first
        x, u = point(state, iam.nu, 1)
        evaluator.calcDiff(x, u, False)
        assert np.isfinite(other.Fx).all()
    assert iam._compiled_node(data, False, {}) is first


def test_parameters_are_read_again_at_each_refresh():
    iam, state = node("kinova", ("state", "translation", "control"))
    data, slow = iam.createData(), iam.createData()
    x, u = point(state, iam.nu, 2)
    iam.differential.costs.costs["translation"].weight = 7.0
    iam.differential.costs.costs["translation"].cost.residual.reference = np.array([0.1, 0.2, 0.3])
    iam.dt = 0.02
    iam._compiled_node(data, False, {}).calcDiff(x, u, False)
    iam.calc(slow, x, u)
    iam.calcDiff(slow, x, u)
    assert data.cost == pytest.approx(slow.cost, rel=1e-10)
    np.testing.assert_allclose(data.Lx, slow.Lx, rtol=1e-8, atol=1e-10)


def test_the_kernel_rebuilds_the_lowered_model_and_workspace_from_the_table():
    """Entry by entry, the arrays the kernel views are the node's own and its model's shared workspace (same
    memory, shapes and values), the workspace fields the node keeps of its own (:data:`node_table.OWN_WORKSPACE`)
    excepted."""
    from crocopy.models.rbd import node_table as table

    iam, state = node("anymal", ("state", "control"))
    data = iam.createData()
    evaluator = iam._compiled_node(data, False, {})
    rb = table.entry_model(evaluator.tbl, evaluator.ints)
    ws = table.entry_workspace(evaluator.tbl, evaluator.ints)
    reference = evaluator._lowered.rb
    assert rb[:4] == reference[:4]
    for name in rb._fields[4:]:
        expected = evaluator.armature if name == "armature" else getattr(reference, name)
        np.testing.assert_array_equal(getattr(rb, name), expected, err_msg=name)
    own = dict(zip(table.OWN_WORKSPACE, evaluator._own[3]))
    for name in ws._fields:
        mine, theirs = getattr(ws, name), getattr(evaluator._lowered.workspace, name)
        expected = own.get(name, theirs)
        assert mine.shape == theirs.shape and mine.ctypes.data == expected.ctypes.data, name
        assert (name in own) == (mine.ctypes.data != theirs.ctypes.data), name


def test_a_changed_pinocchio_model_is_read_again_at_the_next_solve():
    iam, state = node("iris", ("state", "placement", "control"))
    data, slow = iam.createData(), iam.createData()
    x, u = point(state, iam.nu, 4)
    iam._compiled_node(data, False, {}).calcDiff(x, u, False)
    state.pinocchio.gravity = pin.Motion(np.array([0.0, 0.0, -3.7]), np.zeros(3))
    state.pinocchio.inertias[1].mass = 2.5
    evaluator = iam._compiled_node(data, False, {})
    evaluator.calcDiff(x, u, False)
    iam.calc(slow, x, u)
    iam.calcDiff(slow, x, u)
    np.testing.assert_allclose(data.xnext, slow.xnext, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(data.Fu, slow.Fu, rtol=1e-10, atol=1e-12)


def test_nodes_of_one_model_share_their_scratch_and_keep_their_own_arrays():
    """Only the scratch (but what each node keeps of its own, :data:`node_table.OWN`) and the (empty) constraint-row
    arrays of a node without constraints are shared."""
    from crocopy.models.rbd import node_table as table

    iam, state = node("kinova", ("state", "translation", "control"))
    first, second = iam.createData(), iam.createData()
    memo: dict = {}
    a, b = iam._compiled_node(first, False, memo), iam._compiled_node(second, False, memo)
    shared = table.NODE + len(table.NODE_ARRAYS)
    scratch = np.arange(shared, a.tbl.shape[0])
    kept = np.isin(scratch, table.OWN)
    assert kept.any() and np.array_equal(a.tbl[scratch[~kept]], b.tbl[scratch[~kept]])
    assert not np.intersect1d(a.tbl[table.OWN], b.tbl[table.OWN]).size
    own = np.array([e.owner != "constraint rows" for e in table.NODE_ARRAYS])  # no constraints: empty, shared
    assert not np.intersect1d(a.tbl[table.NODE:shared][own], b.tbl[table.NODE:shared][own]).size
    x, u = point(state, iam.nu, 6)
    y, w = point(state, iam.nu, 7)
    a.calcDiff(x, u, False)
    b.calcDiff(y, w, False)
    slow = iam.createData()
    iam.calc(slow, x, u)
    iam.calcDiff(slow, x, u)
    for name in FIELDS:
        np.testing.assert_allclose(getattr(first, name), getattr(slow, name), rtol=1e-10, atol=1e-12, err_msg=name)


def test_the_registry_of_compiled_kinds_is_covered_and_documented():
    """Every residual class that declares a compiled kind beside its maths is built by this file's factory (or by
    the contact-node tests for the cones, the contact force and the contact gravity compensation, the impulse-node
    tests for the centre-of-mass velocity jump) and named in docs/DEVELOPING.md; the kernel knows each kind."""
    from pathlib import Path

    from crocopy.models.rbd import node_table
    from crocopy.models.rbd.node_kinds import compiled_residual_classes

    registry = compiled_residual_classes()
    factory = {"velocity" if kind.startswith("velocity_") else kind for kind in KINDS} | {
        "com", "cone", "force", "contact_control_grav", "impulse_com"}
    assert set(registry.values()) == factory == set(node_table.KIND)
    developing = (Path(__file__).resolve().parents[1] / "docs" / "DEVELOPING.md").read_text()
    for cls in registry:
        assert f"`{cls.__name__}`" in developing, cls.__name__


def test_the_actuations_and_contacts_that_lower_themselves_are_covered_and_documented():
    """The registries built from the models' own lowerings (``compiled_matrix``, ``compiled_reference``) are the
    classes this file's factory (actuations) and the contact-node tests (1D, 2D, 3D and 6D contacts) build, each named
    in the compiled node's docstring, and each lowering agrees with the model's own maths."""
    from crocopy.models.rbd import contact_lowering, euler_node, node_kinds

    states = {robot: crocopy.StateMultibody(load(robot) if robot not in ("iris", "double_pendulum") else _extra(robot))
              for robot in ROBOTS}
    built = {robot: actuation(robot, state) for robot, state in states.items()}
    assert set(node_kinds.ACTUATIONS) == {type(a) for a in built.values()}
    assert set(contact_lowering.CONTACTS) == {crocopy.ContactModel1D, crocopy.ContactModel2D, crocopy.ContactModel3D,
                                              crocopy.ContactModel6D}
    for cls in (*node_kinds.ACTUATIONS, *contact_lowering.CONTACTS):
        assert f"``{cls.__name__}``" in euler_node.__doc__, cls.__name__
    for robot, act in built.items():
        data = act.createData()
        x, u = point(states[robot], act.nu, 3)
        act.calc(data, x, u)
        act.calcDiff(data, x, u)
        np.testing.assert_allclose(act.compiled_matrix(), data.dtau_du, atol=1e-15, err_msg=robot)
        np.testing.assert_allclose(act.compiled_matrix() @ u, data.tau, atol=1e-12, err_msg=robot)
    state = states["anymal"]
    placement = pin.SE3.Random()
    for contact, R, p in ((crocopy.ContactModel6D(state, 5, placement, pin.LOCAL), placement.rotation,
                           placement.translation),
                          (crocopy.ContactModel3D(state, 5, placement.translation, pin.LOCAL), np.zeros((3, 3)),
                           placement.translation)):
        R_out, p_out = np.zeros((3, 3)), np.zeros(3)
        contact.compiled_reference(R_out, p_out)
        np.testing.assert_array_equal(R_out, R)
        np.testing.assert_array_equal(p_out, p)
    axis = pin.rpy.rpyToMatrix(0.3, -0.2, 0.5)
    for contact, rows, p in ((crocopy.ContactModel1D(state, 5, 0.4, pin.LOCAL, axis), axis[2:3], 0.4 * axis[:, 2]),
                             (crocopy.ContactModel2D(state, 5, np.array([0.1, 0.2])), np.eye(3)[[0, 2]],
                              np.array([0.1, 0.2, 0.0]))):
        R_out, p_out = np.ones((3, 3)), np.ones(3)
        contact.compiled_reference(R_out, p_out)
        data = contact.createData(state.pinocchio.createData())
        contact.calc(data, state.rand())
        np.testing.assert_allclose(data.Jc, R_out[: contact.nc] @ data.point.Jc, rtol=0, atol=1e-15)
        np.testing.assert_array_equal(R_out[: contact.nc], rows)
        np.testing.assert_array_equal(R_out[contact.nc:], 0.0)
        np.testing.assert_allclose(p_out, p, rtol=0, atol=1e-15)


def test_activations_with_an_item_form_are_covered_and_others_keep_the_python_path():
    """Every activation class declaring an item form is in the factory; the numerical-differentiation activation and a
    subclass overriding ``calc`` keep the node on the Python path, naming the activation."""
    from crocopy.activations.base import ActivationModelAbstract
    from crocopy.models.rbd.lowering import declaring

    rng = np.random.default_rng(0)
    covered = {type(make(3, rng)) for make in ACTIVATIONS}
    assert set(declaring(ActivationModelAbstract, "item_form")) - {ActivationModelAbstract} <= covered

    class Smooth1(crocopy.ActivationModelSmooth1Norm):
        def calc(self, data, r):
            super().calc(data, r)

    for activation, name in ((crocopy.ActivationModelNumDiff(crocopy.ActivationModelQuad(6)), "ActivationModelNumDiff"),
                             (Smooth1(6), "Smooth1")):
        iam, state = node("kinova", ("state",))
        costs = iam.differential.costs
        residual = crocopy.ResidualModelControl(state, iam.nu)
        costs.addCost("other", crocopy.CostModelResidual(state, activation, residual), 1.0)
        data = iam.createData()
        assert iam._compiled_node(data, False, {}) is None
        problem = crocopy.ShootingProblem(state.zero(), [iam], iam)
        assert name in crocopy.compiled_coverage(problem)[0].reason


@pytest.mark.parametrize("terminal", [False, True])
def test_dense_item_activations_compile_and_match_the_python_node(terminal):
    """The smooth 2-norm, the 2-norm barrier (Gauss-Newton and true Hessian, inside its ball) and the full-Hessian
    quadratic-flat activations on a state-only and a control-dependent residual: the node compiles, and its values
    and derivatives (the dense Hessian ``d I + c r rᵀ`` through ``Jᵀ Arr J``) equal the Python node's; outside the
    ball the barrier adds nothing (a terminal node has no control cost)."""
    model = load("kinova")
    state = crocopy.StateMultibody(model)
    act = actuation("kinova", state)
    x, u = point(state, act.nu, 4)
    ref = state.rand()
    for alpha, inside in ((1e3, True), (1e-3, False)):
        costs, nu = crocopy.CostModelSum(state, act.nu), act.nu
        for n, (activation, residual) in enumerate((
                (crocopy.ActivationModelSmooth2Norm(state.ndx, 0.3), crocopy.ResidualModelState(state, ref, nu)),
                (crocopy.ActivationModelSmooth2Norm(nu), crocopy.ResidualModelControl(state, nu)),
                (crocopy.ActivationModel2NormBarrier(state.ndx, alpha), crocopy.ResidualModelState(state, nu)),
                (crocopy.ActivationModel2NormBarrier(nu, alpha, True), crocopy.ResidualModelControl(state, nu)),
                (crocopy.ActivationModelQuadFlatExp(state.ndx, 30.0, True), crocopy.ResidualModelState(state, ref, nu)),
                (crocopy.ActivationModelQuadFlatLog(nu, 0.5, True), crocopy.ResidualModelControl(state, nu)))):
            costs.addCost(f"c{n}", crocopy.CostModelResidual(state, activation, residual), 1.0 + n)
        dam = crocopy.DifferentialActionModelFreeFwdDynamics(state, act, costs)
        iam = crocopy.IntegratedActionModelEuler(dam, 0.01)
        problem = crocopy.ShootingProblem(state.zero(), [iam], iam)
        assert all(entry.compiled for entry in crocopy.compiled_coverage(problem))
        compare_with_python_node(iam, x, u, terminal, rtol=1e-9, atol=1e-10, cost_rel=1e-12)
        data = iam.createData()
        iam.calc(data, x, None if terminal else u)
        barrier = [data.differential.costs.costs[f"c{n}"].cost for n in ((2,) if terminal else (2, 3))]
        assert (min(barrier) > 0.0) if inside else (max(barrier) == 0.0)


def test_the_stack_adds_a_dense_hessian_as_the_items_own_cost_datas_do():
    """A cost sum holding dense activations: the stack's derivatives equal the sum of each item's own
    ``w Lx``/``w Lxx``/``w Lxu``/``w Luu`` (Crocoddyl's ``Rᵀ Arr R``), kernels on and off."""
    state = crocopy.StateMultibody(load("kinova"))
    nu = state.nv
    rng = np.random.default_rng(3)
    costs = crocopy.CostModelSum(state, nu)
    costs.addCost("s", crocopy.CostModelResidual(state, crocopy.ActivationModelSmooth2Norm(state.ndx, 0.2),
                                                 crocopy.ResidualModelState(state, state.rand(), nu)), 2.0)
    costs.addCost("b", crocopy.CostModelResidual(state, crocopy.ActivationModel2NormBarrier(nu, 1e3, True),
                                                 crocopy.ResidualModelControl(state, rng.standard_normal(nu))), 0.5)
    x, u = point(state, nu, 5)
    try:
        for enabled in (True, False):
            crocopy.set_kernels(enabled)
            data = costs.createData(crocopy.DataCollectorMultibody(pin.Data(state.pinocchio)))
            costs.calc(data, x, u)
            costs.calcDiff(data, x, u)
            assert data.Luu.any() and data.Lxx.any()
            for name in ("Lx", "Lu", "Lxx", "Lxu", "Luu"):
                expected = sum(item.weight * getattr(data.costs[key], name) for key, item in costs.costs.items())
                np.testing.assert_allclose(getattr(data, name), expected, rtol=1e-12, atol=1e-12, err_msg=name)
    finally:
        crocopy.set_kernels(True)


def test_an_item_activation_parameter_set_between_solves_is_read_again():
    """``alpha`` of a quadratic-flat activation assigned between two solves: the compiled solve after it gives the
    iterations and cost of a solve on the Python nodes."""
    iam, state = node("kinova", ("state", "control", "placement", "translation", "rotation"), seed=2)
    flat = iam.differential.costs.costs["rotation"].cost.activation
    assert isinstance(flat, crocopy.ActivationModelQuadFlatExp)
    problem = crocopy.ShootingProblem(state.zero(), [iam] * 5, iam)
    compiled = make_solver("SolverFDDP", problem)
    compiled.solve([], [], 3)
    flat.alpha = 0.5
    results = []
    for solver in (compiled, make_solver("SolverFDDP", problem, False)):
        solver.solve([], [], 6)
        results.append((solver.iter, solver.cost))
    assert results[0][0] == results[1][0]
    assert results[0][1] == pytest.approx(results[1][1], rel=1e-10)
