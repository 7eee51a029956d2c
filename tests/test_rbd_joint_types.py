"""The joint codes of a lowered model cover the robots' configuration and tangent spaces exactly once; every joint
type of Pinocchio's binding either compiles (and equals the Python node) or falls back to the Python node, and a
solve gives the same iterations and cost either way."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from node_checks import compare_with_python_node, make_solver
from robots import JOINT_CHAIN, load, reaching_node

import crocopy
from crocopy.models.rbd.joint_types import HELICAL, NQ, NV, NotLowerable, joint_arrays
from crocopy.models.rbd.lowering import lower_model

example_robot_data = pytest.importorskip("example_robot_data")

CONTINUOUS_URDF = """<robot name="r"><link name="base"/>
 <link name="l1"><inertial><mass value="1"/><origin xyz="0.1 0 0"/>
  <inertia ixx="0.1" iyy="0.2" izz="0.3" ixy="0" ixz="0" iyz="0"/></inertial></link>
 <joint name="j1" type="continuous"><parent link="base"/><child link="l1"/><axis xyz="0 0.6 0.8"/></joint>
</robot>"""


def _continuous_unaligned() -> pin.JointModel:
    """A continuous joint on axis (0, 0.6, 0.8) as a URDF gives it (the binding's constructor takes no axis)."""
    return pin.buildModelFromXML(CONTINUOUS_URDF).joints[1]


def _composite() -> pin.JointModelComposite:
    joint = pin.JointModelComposite(pin.JointModelRX())
    joint.addJoint(pin.JointModelPY(), pin.SE3(np.eye(3), np.array([0.0, 0.1, 0.0])))
    return joint


AXIS = np.array([0.0, 0.6, 0.8])
#: Every joint type of Pinocchio's binding (the mimic joint is added on its own, it needs a primary joint).
JOINTS = {
    "RX": pin.JointModelRX, "RY": pin.JointModelRY, "RZ": pin.JointModelRZ,
    "revolute_unaligned": lambda: pin.JointModelRevoluteUnaligned(*AXIS),
    "RUBX": pin.JointModelRUBX, "RUBY": pin.JointModelRUBY, "RUBZ": pin.JointModelRUBZ,
    "continuous_unaligned": _continuous_unaligned,
    "PX": pin.JointModelPX, "PY": pin.JointModelPY, "PZ": pin.JointModelPZ,
    "prismatic_unaligned": lambda: pin.JointModelPrismaticUnaligned(*AXIS),
    "free_flyer": pin.JointModelFreeFlyer,
    "spherical": pin.JointModelSpherical, "spherical_zyx": pin.JointModelSphericalZYX,
    "planar": pin.JointModelPlanar, "translation": pin.JointModelTranslation,
    "HX": lambda: pin.JointModelHX(0.1), "HY": lambda: pin.JointModelHY(0.1), "HZ": lambda: pin.JointModelHZ(0.1),
    "helical_unaligned": lambda: pin.JointModelHelicalUnaligned(AXIS, 0.1),
    "universal": lambda: pin.JointModelUniversal(np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])),
    "ellipsoid": lambda: pin.JointModelEllipsoid(0.1, 0.2, 0.3),
    "composite": _composite,
}
COMPILED = {"RX", "RY", "RZ", "revolute_unaligned", "RUBX", "RUBY", "RUBZ", "continuous_unaligned", "PX", "PY",
            "PZ", "prismatic_unaligned", "free_flyer", "spherical", "planar", "translation", "HX", "HY", "HZ",
            "helical_unaligned"}


def test_every_binding_joint_type_is_listed():
    """A joint type a newer Pinocchio adds must be added to :data:`JOINTS` (and lowered or refused)."""
    listed = {type(make()).__name__ for make in JOINTS.values()} | {"JointModelMimic"}
    listed |= {"JointModelRevoluteUnboundedUnaligned"}
    offered = {n for n in dir(pin) if n.startswith("JointModel") and n != "JointModel"}
    assert offered <= listed


def chain(kinds: list[str], seed: int = 0, mimic: bool = False) -> pin.Model:
    """A chain of the joints ``kinds`` (each carrying a random body), between an RX and an RY joint, with a frame at
    the tip; ``mimic`` adds a joint mimicking the first one."""
    rng = np.random.default_rng(seed)
    model = pin.Model()

    def placement() -> pin.SE3:
        return pin.SE3(pin.exp3(rng.uniform(-1.0, 1.0, 3)), rng.uniform(-0.2, 0.2, 3))

    def body() -> pin.Inertia:
        return pin.Inertia(rng.uniform(0.5, 2.0), rng.uniform(-0.1, 0.1, 3), np.diag(rng.uniform(0.01, 0.1, 3)))

    parent = 0
    for n, kind in enumerate(["RX", *kinds, "RY"]):
        joint = JOINTS[kind]()
        parent = model.addJoint(parent, joint, placement(), f"{kind}_{n}")
        model.appendBodyToJoint(parent, body(), pin.SE3.Identity())
    if mimic:
        parent = model.addJoint(parent, pin.JointModelMimic(model.joints[1], 2.0, 0.1), placement(), "mimic")
        model.appendBodyToJoint(parent, body(), pin.SE3.Identity())
    model.addFrame(pin.Frame("tip", parent, 0, placement(), pin.FrameType.OP_FRAME))
    return model


def problem(model: pin.Model, T: int = 6) -> tuple:
    """A short free-dynamics problem on ``model``: reach a point with the tip, fully actuated."""
    state = crocopy.StateMultibody(model)
    fid, target = model.getFrameId("tip"), (0.2, 0.1, 0.3)
    running, terminal = (reaching_node(state, fid, target, 10.0, end) for end in (False, True))
    np.random.seed(7)
    x0 = state.rand()
    x0[state.nq:] *= 0.1
    return crocopy.ShootingProblem(x0, [running] * T, terminal), running, state


def check_chain(model: pin.Model, compiles: bool) -> None:
    """The node compiles iff ``compiles`` (and then equals the Python node); solves with and without compiled nodes
    take the same iterations to the same cost, and none raises."""
    shooting, running, state = problem(model)
    evaluator = running._compiled_node(running.createData(), False, {})
    assert (evaluator is not None) == compiles
    if compiles:
        np.random.seed(3)
        x = state.rand()
        u = np.random.default_rng(3).normal(size=running.nu)
        compare_with_python_node(running, x, u, False, rtol=1e-8, atol=1e-9, cost_rel=1e-10)
    results = []
    for compiled in (True, False):
        s = make_solver("SolverFDDP", shooting, compiled)
        solved = s.solve([], [], 8)
        results.append((solved, s.iter, s.cost, s.reason))
    assert results[0][:2] == results[1][:2] and results[0][3] == results[1][3]
    assert results[0][2] == pytest.approx(results[1][2], rel=1e-8)


@pytest.mark.skipif(not crocopy.kernels_enabled(), reason="compiled nodes need numba")
@pytest.mark.parametrize("kind", sorted(JOINTS))
def test_each_joint_type_compiles_or_falls_back(kind):
    check_chain(chain([kind]), kind in COMPILED)


@pytest.mark.skipif(not crocopy.kernels_enabled(), reason="compiled nodes need numba")
def test_a_chain_of_every_compiled_joint_type_compiles():
    check_chain(chain(sorted(COMPILED - {"free_flyer"}), seed=1), True)


@pytest.mark.skipif(not crocopy.kernels_enabled(), reason="compiled nodes need numba")
def test_a_chain_of_every_joint_type_falls_back():
    check_chain(chain(sorted(JOINTS), seed=2), False)


def test_lowering_raises_only_not_lowerable():
    """Every joint type outside the compiled set, and a mimic joint, is refused with :class:`NotLowerable` naming it."""
    for kind in sorted(set(JOINTS) - COMPILED):
        with pytest.raises(NotLowerable, match=f"'{kind}_1' is a JointModel"):
            lower_model(chain([kind]))
    with pytest.raises(NotLowerable, match="'mimic' is a JointModelMimic"):
        lower_model(chain(["RZ"], mimic=True))


def test_continuous_joint_on_an_unaligned_axis():
    """The axis of a URDF continuous joint on (0, 0.6, 0.8) (the binding has no ``axis`` for it) is read from its
    motion subspace."""
    model = pin.buildModelFromXML(CONTINUOUS_URDF)
    jtype, _, _, axis = joint_arrays(model)
    assert model.joints[1].shortname() == "JointModelRevoluteUnboundedUnaligned"
    assert jtype[1] == 2
    np.testing.assert_allclose(axis[1], [*AXIS, 0.0], atol=1e-15)


@pytest.mark.parametrize("robot", ["iris", "double_pendulum", "kinova", "panda", "anymal", "talos"])
def test_joint_arrays_cover_q_and_v(robot):
    model = example_robot_data.load(robot).model
    jtype, idx_q, idx_v, axis = joint_arrays(model)
    assert jtype[0] == -1
    q_seen, v_seen = np.zeros(model.nq, dtype=int), np.zeros(model.nv, dtype=int)
    for i in range(1, model.njoints):
        q_seen[idx_q[i]: idx_q[i] + NQ[jtype[i]]] += 1
        v_seen[idx_v[i]: idx_v[i] + NV[jtype[i]]] += 1
        if jtype[i] != 0:
            assert np.linalg.norm(axis[i, :3]) == pytest.approx(1.0)
    assert (q_seen == 1).all() and (v_seen == 1).all()


def test_unaligned_axis_and_unsupported_joint():
    model = pin.Model()
    model.addJoint(0, pin.JointModelRevoluteUnaligned(0.0, 0.6, 0.8), pin.SE3.Identity(), "hinge")
    assert np.allclose(joint_arrays(model)[3][1], [0.0, 0.6, 0.8, 0.0])
    model.addJoint(1, pin.JointModelSphericalZYX(), pin.SE3.Identity(), "ball")
    with pytest.raises(NotLowerable, match="'ball' is a JointModelSphericalZYX"):
        joint_arrays(model)


def test_helical_axis_and_pitch_are_read_from_the_motion_subspace():
    """A helical joint's axis and pitch (``S = [pitch a; a]``), aligned or not, whatever the sign of the pitch."""
    model = pin.Model()
    model.addJoint(0, pin.JointModelHY(0.3), pin.SE3.Identity(), "screw")
    model.addJoint(1, pin.JointModelHelicalUnaligned(AXIS, -0.15), pin.SE3.Identity(), "tilted")
    jtype, _, _, axis = joint_arrays(model)
    assert list(jtype[1:]) == [HELICAL, HELICAL]
    np.testing.assert_allclose(axis[1:], [[0.0, 1.0, 0.0, 0.3], [*AXIS, -0.15]], atol=1e-15)


@pytest.mark.skipif(not crocopy.kernels_enabled(), reason="compiled nodes need numba")
@pytest.mark.parametrize("impulse", [False, True])
def test_contact_and_impulse_nodes_on_the_new_joints_match_the_python_nodes(impulse):
    """A 3D contact (or impulse) at the tip of :func:`robots.joint_chain` (spherical, planar, translation and helical
    joints on a free flyer): the compiled node equals the Python node."""
    model = load(JOINT_CHAIN)
    state = crocopy.StateMultibody(model)
    fid = model.getFrameId("tip")
    np.random.seed(11)
    x = state.rand()
    x[state.nq:] = np.random.default_rng(11).normal(size=state.nv)
    residual = crocopy.ResidualModelFrameTranslation(state, fid, np.array([0.1, 0.2, 0.3]), 0)
    if impulse:
        impulses = crocopy.ImpulseModelMultiple(state)
        impulses.addImpulse("tip", crocopy.ImpulseModel3D(state, fid, pin.LOCAL_WORLD_ALIGNED))
        costs = crocopy.CostModelSum(state, 0)
        costs.addCost("goal", crocopy.CostModelResidual(state, residual), 1.0)
        node = crocopy.ActionModelImpulseFwdDynamics(state, impulses, costs)
        compare_with_python_node(node, x, np.zeros(0), True, rtol=1e-8, atol=1e-9, cost_rel=1e-10)
        return
    actuation = crocopy.ActuationModelFloatingBase(state)
    contacts = crocopy.ContactModelMultiple(state, actuation.nu)
    contacts.addContact("tip", crocopy.ContactModel3D(state, fid, np.zeros(3), pin.LOCAL_WORLD_ALIGNED, actuation.nu,
                                                      np.array([0.0, 20.0])))
    costs = crocopy.CostModelSum(state, actuation.nu)
    costs.addCost("goal", crocopy.CostModelResidual(state, crocopy.ResidualModelFrameTranslation(
        state, fid, np.array([0.1, 0.2, 0.3]), actuation.nu)), 1.0)
    costs.addCost("u", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, actuation.nu)), 0.1)
    dam = crocopy.DifferentialActionModelContactFwdDynamics(state, actuation, contacts, costs)
    node = crocopy.IntegratedActionModelEuler(dam, 0.01)
    u = np.random.default_rng(12).normal(size=actuation.nu)
    compare_with_python_node(node, x, u, False, rtol=1e-7, atol=1e-7, cost_rel=1e-9)
