"""DifferentialActionModelFreeFwdDynamics × actuation × integrator × robot, against finite differences.

Tolerance: central differences on the tangent space with step ``H = 1e-6``; the truncation and
round-off errors are ~1e-10 relative, so Jacobians must agree to ``RTOL = 1e-5`` relative to their
largest entry (Fx entries reach 1e3 on light distal links).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from robots import FLOATING, ROBOTS, frame, load

import crocopy

H = 1e-6
RTOL = 1e-5
INTEGRATORS = ("none", "euler", "rk2", "rk3", "rk4")


def _actuation(state, kind):
    if kind == "thrusters":
        thrusters = [
            crocopy.Thruster(pin.SE3(np.eye(3), np.array(p)), 0.1, t)
            for p, t in (
                ([0.2, 0.0, 0.0], crocopy.ThrusterType.CW),
                ([0.0, 0.2, 0.0], crocopy.ThrusterType.CCW),
                ([-0.2, 0.0, 0.0], crocopy.ThrusterType.CW),
                ([0.0, -0.2, 0.0], crocopy.ThrusterType.CCW),
            )
        ]
        return crocopy.ActuationModelFloatingBaseThrusters(state, thrusters)
    if kind == "linear":
        return crocopy.ActuationModelLinear(state, np.random.default_rng(7).standard_normal((state.nv, 3)))
    floating = state.pinocchio.joints[1].shortname() == "JointModelFreeFlyer"
    act = crocopy.ActuationModelFloatingBase(state) if floating else crocopy.ActuationModelFull(state)
    if kind == "squashed":
        sq = crocopy.SquashingModelSmoothSat(-np.full(act.nu, 2.0), np.full(act.nu, 3.0), act.nu)
        act = crocopy.ActuationSquashingModel(act, sq, act.nu)
    return act


def make_dam(robot: str, kind: str = "plain", armature: bool = False):
    """A free-dynamics DAM of ``robot`` with a small cost stack covering q, v and u."""
    model = load(robot)
    state = crocopy.StateMultibody(model)
    act = _actuation(state, kind)
    nu = act.nu
    costs = crocopy.CostModelSum(state, nu)
    costs.addCost("x", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, state.zero(), nu)), 0.1)
    costs.addCost("u", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, nu)), 0.01)
    fid = model.getFrameId(frame(robot)) if robot in ROBOTS else model.nframes - 1
    place = crocopy.ResidualModelFramePlacement(state, fid, pin.SE3(np.eye(3), np.array([0.1, 0.2, 0.3])), nu)
    costs.addCost("place", crocopy.CostModelResidual(state, place), 1.0)
    vel = crocopy.ResidualModelFrameVelocity(state, fid, pin.Motion.Zero(), pin.LOCAL_WORLD_ALIGNED, nu)
    costs.addCost("vel", crocopy.CostModelResidual(state, vel), 0.5)
    dam = crocopy.DifferentialActionModelFreeFwdDynamics(state, act, costs)
    if armature:
        dam.armature = np.linspace(0.05, 0.2, state.nv)
    return dam


def integrate(dam, integrator: str):
    if integrator == "none":
        return dam
    if integrator == "euler":
        return crocopy.IntegratedActionModelEuler(dam, 1e-2)
    rk = {"rk2": crocopy.RKType.two, "rk3": crocopy.RKType.three, "rk4": crocopy.RKType.four}[integrator]
    return crocopy.IntegratedActionModelRK(dam, rk, 1e-2)


def finite_differences(model, x, u):
    """Central differences of (dynamics, cost) w.r.t. (x on the tangent space, u)."""
    state = model.state
    data = model.createData()
    is_dam = not hasattr(data, "xnext")

    def outputs(xx, uu):
        model.calc(data, xx, uu)
        return (data.xout.copy() if is_dam else data.xnext.copy()), data.cost

    # pinocchio.difference of unbounded revolute joints returns 0 below ~1e-8, so next states are
    # differenced from x (far away) and mapped to the tangent space at xnext by Jdiff.
    if not is_dam:
        model.calc(data, x, u)
        Jd = state.Jdiff(x, data.xnext.copy())[1]

    def dyn_diff(a, b):
        return (b - a) if is_dam else np.linalg.solve(Jd, state.diff(x, b) - state.diff(x, a))

    n = state.ndx + model.nu
    nout = state.nv if is_dam else state.ndx
    Jf, grad = np.zeros((nout, n)), np.zeros(n)
    for i in range(n):
        if i < state.ndx:
            e = np.zeros(state.ndx)
            e[i] = H
            (fp, cp), (fm, cm) = outputs(state.integrate(x, e), u), outputs(state.integrate(x, -e), u)
        else:
            e = np.zeros(model.nu)
            e[i - state.ndx] = H
            (fp, cp), (fm, cm) = outputs(x, u + e), outputs(x, u - e)
        Jf[:, i] = dyn_diff(fm, fp) / (2 * H)
        grad[i] = (cp - cm) / (2 * H)
    return Jf[:, : state.ndx], Jf[:, state.ndx :], grad[: state.ndx], grad[state.ndx :]


def assert_close(analytic, numeric, name):
    scale = max(1.0, float(np.abs(numeric).max()))
    err = float(np.abs(analytic - numeric).max())
    assert err <= RTOL * scale, f"{name}: max error {err:.3e} (scale {scale:.3e})"


def random_point(model, seed=0):
    np.random.seed(seed)
    return model.state.rand(), np.random.rand(model.nu) - 0.5


CASES = [(r, k, a) for r in ROBOTS for k in ("plain", "squashed") for a in (False, True)] + [
    ("iris", "thrusters", False), ("kinova", "linear", False), ("anymal", "linear", True)
]


@pytest.mark.parametrize("integrator", INTEGRATORS)
@pytest.mark.parametrize(("robot", "kind", "armature"), CASES)
def test_derivatives_vs_finite_differences(robot, kind, armature, integrator):
    model = integrate(make_dam(robot, kind, armature), integrator)
    x, u = random_point(model)
    data = model.createData()
    model.calc(data, x, u)
    model.calcDiff(data, x, u)
    Fx, Fu, Lx, Lu = finite_differences(model, x, u)
    assert_close(data.Fx, Fx, "Fx")
    assert_close(data.Fu, Fu, "Fu")
    assert_close(data.Lx, Lx, "Lx")
    assert_close(data.Lu, Lu, "Lu")


@pytest.mark.parametrize("robot", ROBOTS)
def test_gauss_newton_hessians(robot):
    """Lxx, Lxu, Luu are the weighted Gauss-Newton sums of the residual Jacobians (quadratic activations)."""
    dam = make_dam(robot)
    x, u = random_point(dam, 1)
    data = dam.createData()
    dam.calc(data, x, u)
    dam.calcDiff(data, x, u)
    Lxx, Lxu, Luu = 0.0, 0.0, 0.0
    for name, item in dam.costs.costs.items():
        rd = data.costs.costs[name].residual
        Lxx = Lxx + item.weight * rd.Rx.T @ rd.Rx
        Lxu = Lxu + item.weight * rd.Rx.T @ rd.Ru
        Luu = Luu + item.weight * rd.Ru.T @ rd.Ru
    assert np.allclose(data.Lxx, Lxx) and np.allclose(data.Lxu, Lxu) and np.allclose(data.Luu, Luu)


@pytest.mark.parametrize("robot", ROBOTS)
def test_terminal_node(robot):
    dam = make_dam(robot)
    x, _ = random_point(dam, 2)
    data = dam.createData()
    dam.calc(data, x)
    dam.calcDiff(data, x)
    _, _, Lx, _ = finite_differences_terminal(dam, x)
    assert_close(data.Lx, Lx, "terminal Lx")


def finite_differences_terminal(dam, x):
    state, data = dam.state, dam.createData()
    grad = np.zeros(state.ndx)
    for i in range(state.ndx):
        e = np.zeros(state.ndx)
        e[i] = H
        dam.calc(data, state.integrate(x, e))
        cp = data.cost
        dam.calc(data, state.integrate(x, -e))
        grad[i] = (cp - data.cost) / (2 * H)
    return None, None, grad, None


@pytest.mark.parametrize("robot", ROBOTS)
def test_dynamics_match_pinocchio(robot):
    """xout is M⁻¹(τ - b) (with armature on the diagonal of M) and Minv is the inverse mass matrix."""
    for armature in (False, True):
        dam = make_dam(robot, armature=armature)
        x, u = random_point(dam, 3)
        data = dam.createData()
        dam.calc(data, x, u)
        dam.calcDiff(data, x, u)
        model, pd = dam.pinocchio, dam.pinocchio.createData()
        q, v = x[: dam.state.nq], x[dam.state.nq :]
        M = pin.crba(model, pd, q) + np.diag(dam.armature)
        tau = data.multibody.actuation.tau
        a = np.linalg.solve(M, tau - pin.nonLinearEffects(model, pd, q, v))
        assert np.allclose(data.xout, a, atol=1e-8 * max(1.0, np.abs(a).max()))
        assert np.allclose(data.Minv @ M, np.eye(dam.state.nv), atol=1e-8)
        assert np.allclose(data.multibody.joint.a, data.xout) and np.allclose(data.multibody.joint.tau, u)


@pytest.mark.parametrize("robot", ["talos_arm", "kinova"])
def test_quasi_static_gives_zero_acceleration(robot):
    for armature in (False, True):
        dam = make_dam(robot, armature=armature)
        data = dam.createData()
        x = dam.state.rand()
        x[dam.state.nq :] = 0.0
        u = dam.quasiStatic(data, x)
        dam.calc(data, x, u)
        assert np.abs(data.xout).max() < 1e-8


@pytest.mark.parametrize("robot", FLOATING)
def test_quasi_static_floating_base_cancels_joint_gravity(robot):
    dam = make_dam(robot)
    data = dam.createData()
    x = dam.state.zero()
    u = dam.quasiStatic(data, x)
    g = pin.computeGeneralizedGravity(dam.pinocchio, dam.pinocchio.createData(), x[: dam.state.nq])
    assert np.allclose(u, g[6:])


def test_control_limits_from_effort_limits():
    model = load("anymal")
    dam = make_dam("anymal")
    assert np.allclose(dam.u_ub, model.effortLimit[6:]) and np.allclose(dam.u_lb, -model.effortLimit[6:])
    assert not dam.has_control_limits
    dam = make_dam("talos_arm")
    assert np.allclose(dam.u_ub, load("talos_arm").effortLimit)
    dam.u_lb = -np.ones(dam.nu)
    assert dam.has_control_limits


def test_data_fields():
    dam = make_dam("solo12")
    data = dam.createData()
    nv = dam.state.nv
    assert isinstance(data.pinocchio, pin.Data) and data.multibody.pinocchio is data.pinocchio
    assert data.Minv.shape == (nv, nv) and data.u_drift.shape == (nv,)
    assert data.xout.shape == (nv,) and data.Fx.shape == (nv, 2 * nv) and data.Fu.shape == (nv, dam.nu)
    assert set(data.costs.costs) == set(dam.costs.costs)


def test_bad_inputs():
    dam = make_dam("anymal")
    state, act = dam.state, dam.actuation
    with pytest.raises(ValueError, match="StateMultibody"):
        crocopy.DifferentialActionModelFreeFwdDynamics(crocopy.StateVector(4), act, dam.costs)
    with pytest.raises(ValueError, match="nu"):
        crocopy.DifferentialActionModelFreeFwdDynamics(state, act, crocopy.CostModelSum(state, 3))
    other = crocopy.StateMultibody(load("talos_arm"))
    with pytest.raises(ValueError, match="actuation"):
        crocopy.DifferentialActionModelFreeFwdDynamics(other, act, crocopy.CostModelSum(other, act.nu))
    with pytest.raises(ValueError, match="armature"):
        dam.armature = np.ones(3)
    with pytest.raises(ValueError, match="free-flyer"):
        crocopy.ActuationModelFloatingBase(other)


def test_constraints_are_stacked():
    dam0 = make_dam("talos_arm")
    state, nu = dam0.state, dam0.nu
    constraints = crocopy.ConstraintModelManager(state, nu)
    fid = load("talos_arm").getFrameId(frame("talos_arm"))
    trans = crocopy.ResidualModelFrameTranslation(state, fid, np.zeros(3), nu)
    constraints.addConstraint("ee", crocopy.ConstraintModelResidual(state, trans, -np.ones(3), np.ones(3)))
    constraints.addConstraint("u", crocopy.ConstraintModelResidual(state, crocopy.ResidualModelControl(state, nu)))
    dam = crocopy.DifferentialActionModelFreeFwdDynamics(state, dam0.actuation, dam0.costs, constraints)
    assert (dam.ng, dam.nh) == (3, nu) and np.allclose(dam.g_lb, -1.0)
    x, u = random_point(dam, 4)
    data = dam.createData()
    dam.calc(data, x, u)
    dam.calcDiff(data, x, u)
    pd = dam.pinocchio.createData()
    pin.framesForwardKinematics(dam.pinocchio, pd, x[: state.nq])
    assert np.allclose(data.g, pd.oMf[fid].translation) and np.allclose(data.h, u)
    assert np.allclose(data.Hu, np.eye(nu)) and np.abs(data.Gx).max() > 0.0
