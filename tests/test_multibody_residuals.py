"""Multibody residuals on several robots against finite differences, plus their bad-input errors.

Each residual sits in the cost stack of a free-dynamics DAM, which fills the shared Pinocchio
data; ``Rx``/``Ru`` are compared with central differences (step ``H = 1e-6`` on the tangent
space) of ``r`` recomputed by ``DAM.calc``.  Agreement: ``RTOL = 1e-5`` relative to the largest
entry (truncation and round-off errors are ~1e-9).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from robots import FLOATING, ROBOTS, frame, load

import crocopy

H = 1e-6
RTOL = 1e-5
RESIDUALS = (
    "placement",
    "translation",
    "rotation",
    "velocity_local",
    "velocity_world",
    "velocity_lwa",
    "com",
    "centroidal",
    "control_grav",
    "joint_effort",
    "joint_acceleration",
    "state",
)


def make_residual(kind: str, state, actuation, fid: int):
    nu = actuation.nu
    rng = np.random.RandomState(7)
    if kind == "placement":
        return crocopy.ResidualModelFramePlacement(state, fid, pin.SE3(pin.exp3(rng.rand(3)), rng.rand(3)), nu)
    if kind == "translation":
        return crocopy.ResidualModelFrameTranslation(state, fid, rng.rand(3), nu)
    if kind == "rotation":
        return crocopy.ResidualModelFrameRotation(state, fid, pin.exp3(rng.rand(3)), nu)
    if kind.startswith("velocity"):
        rf = {"velocity_local": pin.LOCAL, "velocity_world": pin.WORLD, "velocity_lwa": pin.LOCAL_WORLD_ALIGNED}[kind]
        return crocopy.ResidualModelFrameVelocity(state, fid, pin.Motion(rng.rand(6)), rf, nu)
    if kind == "com":
        return crocopy.ResidualModelCoMPosition(state, rng.rand(3), nu)
    if kind == "centroidal":
        return crocopy.ResidualModelCentroidalMomentum(state, rng.rand(6), nu)
    if kind == "control_grav":
        return crocopy.ResidualModelControlGrav(state, nu)
    if kind == "joint_effort":
        return crocopy.ResidualModelJointEffort(state, actuation, rng.rand(nu), nu, True)
    if kind == "joint_acceleration":
        return crocopy.ResidualModelJointAcceleration(state, rng.rand(state.nv), nu)
    return crocopy.ResidualModelState(state, state.rand(), nu)


def setup(robot: str, kind: str):
    model = load(robot)
    state = crocopy.StateMultibody(model)
    act = crocopy.ActuationModelFloatingBase(state) if robot in FLOATING else crocopy.ActuationModelFull(state)
    residual = make_residual(kind, state, act, model.getFrameId(frame(robot)))
    costs = crocopy.CostModelSum(state, act.nu)
    costs.addCost("r", crocopy.CostModelResidual(state, residual), 1.0)
    return crocopy.DifferentialActionModelFreeFwdDynamics(state, act, costs), residual


def numeric_jacobians(dam, x, u):
    state, data = dam.state, dam.createData()
    terminal = u is None

    def r(xx, uu):
        dam.calc(data, xx, uu)
        return data.costs.costs["r"].residual.r.copy()

    nr = dam.costs.costs["r"].cost.residual.nr
    Rx = np.zeros((nr, state.ndx))
    for i in range(state.ndx):
        e = np.zeros(state.ndx)
        e[i] = H
        Rx[:, i] = (r(state.integrate(x, e), u) - r(state.integrate(x, -e), u)) / (2 * H)
    Ru = np.zeros((nr, dam.nu))
    if not terminal:
        for i in range(dam.nu):
            e = np.zeros(dam.nu)
            e[i] = H
            Ru[:, i] = (r(x, u + e) - r(x, u - e)) / (2 * H)
    return Rx, Ru


def assert_close(analytic, numeric, name):
    scale = max(1.0, float(np.abs(numeric).max()))
    err = float(np.abs(analytic - numeric).max())
    assert err <= RTOL * scale, f"{name}: max error {err:.3e} (scale {scale:.3e})"


@pytest.mark.parametrize("terminal", [False, True], ids=["running", "terminal"])
@pytest.mark.parametrize("kind", RESIDUALS)
@pytest.mark.parametrize("robot", ROBOTS)
def test_residual_jacobians(robot, kind, terminal):
    dam, residual = setup(robot, kind)
    np.random.seed(11)
    x, u = dam.state.rand(), np.random.rand(dam.nu) - 0.5
    u = None if terminal else u
    data = dam.createData()
    dam.calc(data, x, u)
    dam.calcDiff(data, x, u)
    rdata = data.costs.costs["r"].residual
    Rx, Ru = numeric_jacobians(dam, x, u)
    assert_close(rdata.Rx, Rx, f"{kind} Rx")
    if not terminal:
        assert_close(rdata.Ru, Ru, f"{kind} Ru")


@pytest.mark.parametrize("robot", ["anymal", "kinova"])
def test_residual_values(robot):
    """Residuals vanish at their own reference and match direct Pinocchio computations."""
    model = load(robot)
    state = crocopy.StateMultibody(model)
    dam, _ = setup(robot, "state")
    np.random.seed(3)
    x = state.rand()
    q, v = x[: state.nq], x[state.nq :]
    pd = model.createData()
    pin.forwardKinematics(model, pd, q, v)
    fid = model.getFrameId(frame(robot))
    oMf = pin.updateFramePlacement(model, pd, fid)
    com = pin.centerOfMass(model, pd, q)
    h = pin.computeCentroidalMomentum(model, pd, q, v).vector
    nu = dam.nu
    cases = [
        crocopy.ResidualModelFramePlacement(state, fid, oMf, nu),
        crocopy.ResidualModelFrameTranslation(state, frame(robot), oMf.translation, nu),
        crocopy.ResidualModelFrameRotation(state, fid, oMf.rotation, nu),
        crocopy.ResidualModelFrameVelocity(state, fid, pin.getFrameVelocity(model, pd, fid, pin.WORLD), pin.WORLD, nu),
        crocopy.ResidualModelCoMPosition(state, com, nu),
        crocopy.ResidualModelCentroidalMomentum(state, h, nu),
    ]
    for residual in cases:
        costs = crocopy.CostModelSum(state, nu)
        costs.addCost("r", crocopy.CostModelResidual(state, residual), 1.0)
        d = crocopy.DifferentialActionModelFreeFwdDynamics(state, dam.actuation, costs)
        data = d.createData()
        d.calc(data, x, np.zeros(nu))
        assert np.abs(data.costs.costs["r"].residual.r).max() < 1e-10, type(residual).__name__


def test_control_grav_value():
    dam, _ = setup("anymal", "control_grav")
    np.random.seed(5)
    x, u = dam.state.rand(), np.random.rand(dam.nu)
    data = dam.createData()
    dam.calc(data, x, u)
    g = pin.computeGeneralizedGravity(dam.pinocchio, dam.pinocchio.createData(), x[: dam.state.nq])
    assert np.allclose(data.costs.costs["r"].residual.r, np.concatenate([np.zeros(6), u]) - g)
    dam.calc(data, x)
    assert np.allclose(data.costs.costs["r"].residual.r, -g)


def test_dependencies_and_dimensions():
    dam, _ = setup("solo12", "state")
    state, act = dam.state, dam.actuation
    r = crocopy.ResidualModelFrameVelocity(state, 3, pin.Motion.Zero(), pin.LOCAL)
    assert (r.nr, r.nu, r.q_dependent, r.v_dependent, r.u_dependent) == (6, state.nv, True, True, False)
    r = crocopy.ResidualModelJointEffort(state, act, np.zeros(act.nu), act.nu, True)
    assert (r.nr, r.q_dependent, r.v_dependent, r.u_dependent) == (act.nu, False, False, True)
    r = crocopy.ResidualModelJointEffort(state, act, act.nu)
    assert np.allclose(r.reference, 0.0) and r.nu == act.nu and r.q_dependent
    r = crocopy.ResidualModelJointAcceleration(state, act.nu)
    assert r.nr == state.nv and np.allclose(r.reference, 0.0) and r.nu == act.nu
    r = crocopy.ResidualModelControlGrav(state, act.nu)
    assert (r.nr, r.q_dependent, r.v_dependent, r.u_dependent) == (state.nv, True, False, True)
    r = crocopy.ResidualModelFramePlacement(state, "FL_FOOT", pin.SE3.Identity())
    assert r.id == load("solo12").getFrameId("FL_FOOT") and r.nu == state.nv


def test_bad_frames_and_references():
    state = crocopy.StateMultibody(load("talos_arm"))
    with pytest.raises(KeyError, match="no_such_frame"):
        crocopy.ResidualModelFramePlacement(state, "no_such_frame", pin.SE3.Identity())
    with pytest.raises(KeyError, match="10000"):
        crocopy.ResidualModelFrameTranslation(state, 10000, np.zeros(3))
    with pytest.raises(KeyError, match="-1"):
        crocopy.ResidualModelFrameRotation(state, -1, np.eye(3))
    with pytest.raises(ValueError, match=r"xref has shape \(2,\), expected \(3,\)"):
        crocopy.ResidualModelFrameTranslation(state, 2, np.zeros(2))
    with pytest.raises(ValueError, match="Rref"):
        crocopy.ResidualModelFrameRotation(state, 2, np.eye(2))
    with pytest.raises(ValueError, match="rotation matrix"):
        crocopy.ResidualModelFrameRotation(state, 2, 2 * np.eye(3))
    with pytest.raises(ValueError, match="SE3"):
        crocopy.ResidualModelFramePlacement(state, 2, np.eye(4))
    with pytest.raises(ValueError, match="Motion"):
        crocopy.ResidualModelFrameVelocity(state, 2, np.zeros(6), pin.LOCAL)
    with pytest.raises(ValueError, match="ReferenceFrame"):
        crocopy.ResidualModelFrameVelocity(state, 2, pin.Motion.Zero(), "LOCAL")
    with pytest.raises(ValueError, match="cref"):
        crocopy.ResidualModelCoMPosition(state, np.zeros(4))
    with pytest.raises(ValueError, match="href"):
        crocopy.ResidualModelCentroidalMomentum(state, np.zeros(3))
    with pytest.raises(ValueError, match="aref"):
        crocopy.ResidualModelJointAcceleration(state, np.zeros(3))
    with pytest.raises(ValueError, match="StateMultibody"):
        crocopy.ResidualModelCoMPosition(crocopy.StateVector(4), np.zeros(3))


def test_different_robot_errors():
    arm = crocopy.StateMultibody(load("talos_arm"))
    quad = crocopy.StateMultibody(load("anymal"))
    act = crocopy.ActuationModelFloatingBase(quad)
    with pytest.raises(ValueError, match="different robot"):
        crocopy.ResidualModelJointEffort(arm, act, np.zeros(act.nu), act.nu)
    place = crocopy.ResidualModelFramePlacement(arm, 2, pin.SE3.Identity(), act.nu)
    collector = crocopy.DataCollectorMultibody(load("anymal").createData())
    with pytest.raises(ValueError, match="different robot"):
        place.createData(collector)
    with pytest.raises(ValueError, match="data collector"):
        place.createData(crocopy.DataCollectorAbstract())
    grav = crocopy.ResidualModelControlGrav(arm)
    with pytest.raises(ValueError, match="actuation"):
        grav.createData(crocopy.DataCollectorMultibody(load("talos_arm").createData()))


def test_frame_residuals_on_a_one_dof_robot():
    """Pinocchio's binding returns a one-dof robot's frame Jacobian as a vector: the frame residuals and contacts
    still evaluate, and a solve gives the same answer with and without compiled nodes."""
    model = pin.Model()
    joint = model.addJoint(0, pin.JointModelRZ(), pin.SE3.Identity(), "j")
    model.appendBodyToJoint(joint, pin.Inertia.FromSphere(1.0, 0.1), pin.SE3.Identity())
    tip = model.addFrame(pin.Frame("tip", joint, 0, pin.SE3(np.eye(3), np.array([1.0, 0.0, 0.0])),
                                   pin.FrameType.OP_FRAME))
    state = crocopy.StateMultibody(model)
    costs = crocopy.CostModelSum(state, 1)
    residuals = (crocopy.ResidualModelFrameTranslation(state, tip, np.array([0.0, 1.0, 0.0]), 1),
                 crocopy.ResidualModelFramePlacement(state, tip, pin.SE3.Identity(), 1),
                 crocopy.ResidualModelFrameRotation(state, tip, np.eye(3), 1),
                 crocopy.ResidualModelFrameVelocity(state, tip, pin.Motion.Zero(), pin.LOCAL, 1))
    for n, residual in enumerate(residuals):
        costs.addCost(str(n), crocopy.CostModelResidual(state, residual), 1.0)
    dam = crocopy.DifferentialActionModelFreeFwdDynamics(state, crocopy.ActuationModelFull(state), costs)
    iam = crocopy.IntegratedActionModelEuler(dam, 0.05)
    results = []
    for kernels in (True, False):
        with crocopy.use_kernels(kernels):
            problem = crocopy.ShootingProblem(np.zeros(2), [iam] * 10, iam)
            solver = crocopy.SolverFDDP(problem)
            solver.solve([], [], 20)
            results.append((solver.iter, solver.cost))
    assert results[0][0] == results[1][0]
    assert results[0][1] == pytest.approx(results[1][1], rel=1e-9)
