"""Actuation models (full, floating base, thrusters, squashed) and the smooth-saturation squashing."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from robots import FLOATING, load

import crocopy

H = 1e-6


def test_full_actuation():
    model = load("talos_arm")
    state = crocopy.StateMultibody(model)
    act = crocopy.ActuationModelFull(state)
    data = act.createData()
    x, u = state.rand(), np.arange(1.0, state.nv + 1)
    act.calc(data, x, u)
    act.calcDiff(data, x, u)
    assert act.nu == state.nv and np.allclose(data.tau, u)
    assert np.allclose(data.dtau_du, np.eye(state.nv)) and not data.dtau_dx.any()
    act.commands(data, x, 2 * u)
    act.torqueTransform(data, x, u)
    assert np.allclose(data.u, 2 * u) and np.allclose(data.Mtau, np.eye(state.nv)) and data.tau_set.all()
    assert np.allclose(act.u_ub, model.effortLimit) and np.allclose(act.u_lb, -model.effortLimit)


@pytest.mark.parametrize("robot", FLOATING)
def test_floating_base_actuation(robot):
    model = load(robot)
    state = crocopy.StateMultibody(model)
    act = crocopy.ActuationModelFloatingBase(state)
    data = act.createData()
    x, u = state.rand(), np.random.rand(state.nv - 6)
    act.calc(data, x, u)
    act.calcDiff(data, x, u)
    assert act.nu == state.nv - 6
    assert not data.tau[:6].any() and np.allclose(data.tau[6:], u)
    assert np.allclose(data.dtau_du[6:], np.eye(act.nu)) and not data.dtau_du[:6].any()
    tau = np.random.rand(state.nv)
    act.commands(data, x, tau)
    act.torqueTransform(data, x, u)
    assert np.allclose(data.u, tau[6:]) and np.allclose(data.Mtau @ data.dtau_du, np.eye(act.nu))
    assert not data.tau_set[:6].any() and data.tau_set[6:].all()
    lim = np.array(model.effortLimit[6:])
    assert np.allclose(act.u_ub, lim) and np.allclose(act.u_lb, -lim)


def _quad_state():
    return crocopy.StateMultibody(load("iris"))


def test_thruster_construction():
    t = crocopy.Thruster(0.3)
    assert t.pose == pin.SE3.Identity() and t.ctorque == 0.3 and t.type == crocopy.ThrusterType.CW
    assert t.min_thrust == 0.0 and t.max_thrust == np.inf
    M = pin.SE3(np.eye(3), np.array([0.1, 0.0, 0.0]))
    t = crocopy.Thruster(M, 0.2, crocopy.ThrusterType.CCW, 1.0, 5.0)
    assert t.pose == M and t.type == crocopy.ThrusterType.CCW and (t.min_thrust, t.max_thrust) == (1.0, 5.0)
    t = crocopy.Thruster(M, ctorque=0.2, max_thrust=4.0)
    assert t.max_thrust == 4.0 and t.min_thrust == 0.0
    with pytest.raises(ValueError, match="min_thrust"):
        crocopy.Thruster(M, 0.1, crocopy.ThrusterType.CW, 2.0, 1.0)
    with pytest.raises(ValueError, match="ctorque"):
        crocopy.Thruster(M)


def test_thruster_wrenches():
    """A thruster at p with axis z pushes f = z and produces p × z ± ctorque z (CW +, CCW -)."""
    state = _quad_state()
    p = np.array([0.2, -0.1, 0.05])
    R = pin.exp3(np.array([0.1, 0.2, -0.3]))
    thrusters = [
        crocopy.Thruster(pin.SE3(R, p), 0.1, crocopy.ThrusterType.CW, 0.5, 6.0),
        crocopy.Thruster(pin.SE3.Identity(), 0.2, crocopy.ThrusterType.CCW),
    ]
    act = crocopy.ActuationModelFloatingBaseThrusters(state, thrusters)
    z = R[:, 2]
    expected = np.zeros((6, 2))
    expected[:, 0] = np.concatenate([z, np.cross(p, z) + 0.1 * z])
    expected[:, 1] = [0, 0, 1, 0, 0, -0.2]
    assert act.nthrusters == 2 and act.nu == 2
    assert np.allclose(act.Wthrust, expected)
    assert np.allclose(act.u_lb, [0.5, 0.0]) and np.allclose(act.u_ub, [6.0, np.inf])
    assert np.allclose(act.S, act.Wthrust @ np.linalg.pinv(act.Wthrust))
    data = act.createData()
    x, u = state.rand(), np.array([1.0, 2.0])
    act.calc(data, x, u)
    act.calcDiff(data, x, u)
    assert np.allclose(data.tau, expected @ u) and np.allclose(data.dtau_du, expected)
    act.commands(data, x, data.tau.copy())
    assert np.allclose(data.u, u)
    act.thrusters = [thrusters[1], thrusters[0]]
    assert np.allclose(act.Wthrust, expected[:, ::-1])
    act.calcDiff(data, x, u)  # a data created before the change follows it
    assert np.allclose(data.dtau_du, expected[:, ::-1])
    with pytest.raises(ValueError, match="thrusters"):
        act.thrusters = thrusters[:1]
    with pytest.raises(ValueError, match=r"thrusters\[0\]"):
        crocopy.ActuationModelFloatingBaseThrusters(state, [0.1])


def test_linear_actuation():
    """tau = S u with a constant S: values, the constant Jacobians, S⁺ as commands and Mtau, tau_set."""
    state = crocopy.StateMultibody(load("kinova"))
    S = np.zeros((state.nv, 2))
    S[1, 0], S[3, 1], S[4, 1] = 1.0, 2.0, -0.5
    act = crocopy.ActuationModelLinear(state, S)
    data = act.createData()
    x, u = state.rand(), np.array([0.7, -1.3])
    act.calc(data, x, u)
    act.calcDiff(data, x, u)
    assert act.nu == 2 and np.allclose(data.tau, S @ u)
    assert np.array_equal(data.dtau_du, S) and not data.dtau_dx.any()
    act.commands(data, x, data.tau.copy())
    act.torqueTransform(data, x, u)
    assert np.allclose(data.u, u) and np.allclose(data.Mtau @ S, np.eye(2))
    assert data.tau_set.tolist() == [i in (1, 3, 4) for i in range(state.nv)]
    assert np.all(act.u_lb == -np.inf) and np.all(act.u_ub == np.inf)
    S[1, 0] = 5.0
    assert act.S[1, 0] == 1.0
    with pytest.raises(ValueError, match="read-only"):
        act.S[1, 0] = 5.0
    pendulum = crocopy.StateMultibody(load("double_pendulum"))
    assert crocopy.ActuationModelLinear(pendulum, [0.0, 1.0]).S.shape == (2, 1)


@pytest.mark.parametrize(
    ("S", "match"),
    [(np.ones((3, 1)), r"\(nv, nu\) = \(2, nu\).*got \(3, 1\)"), (np.ones((2, 0)), r"got \(2, 0\)"),
     (np.ones((2, 1, 1)), r"got \(2, 1, 1\)"), (np.array([[np.nan], [1.0]]), "finite")],
)
def test_linear_actuation_rejects_bad_S(S, match):
    with pytest.raises(ValueError, match=match):
        crocopy.ActuationModelLinear(crocopy.StateMultibody(load("double_pendulum")), S)


def test_smooth_sat_values_and_derivative():
    lb, ub = np.array([-1.0, 0.5]), np.array([2.0, 3.0])
    sq = crocopy.SquashingModelSmoothSat(lb, ub, 2)
    assert sq.smooth == 0.1 and np.allclose(sq.s_lb, lb) and np.allclose(sq.s_ub, ub)
    data = sq.createData()
    s = np.array([0.3, -1.7])
    sq.calc(data, s)
    beta = 0.1 * (ub - lb)
    expected = 0.5 * (lb + np.sqrt(beta**2 + (s - lb) ** 2)) + 0.5 * (ub - np.sqrt(beta**2 + (s - ub) ** 2))
    assert np.allclose(data.u, expected)
    sq.calcDiff(data, s)
    num = np.zeros(2)
    for i in range(2):
        e = np.zeros(2)
        e[i] = H
        sq.calc(data, s + e)
        up = data.u.copy()
        sq.calc(data, s - e)
        num[i] = (up[i] - data.u[i]) / (2 * H)
    sq.calc(data, s)
    sq.calcDiff(data, s)
    assert np.allclose(np.diag(data.du_ds), num, atol=1e-8) and np.allclose(data.du_ds, np.diag(num), atol=1e-8)
    for big in (1e6, -1e6):
        sq.calc(data, np.full(2, big))
        assert np.all(data.u >= lb) and np.all(data.u <= ub)
        assert np.allclose(data.u, ub if big > 0 else lb, atol=1e-5)
    sq.smooth = 0.5
    sq.calc(data, s)
    beta = 0.5 * (ub - lb)
    expected = 0.5 * (lb + np.sqrt(beta**2 + (s - lb) ** 2)) + 0.5 * (ub - np.sqrt(beta**2 + (s - ub) ** 2))
    assert np.allclose(data.u, expected)
    with pytest.raises(ValueError, match="u_ub"):
        crocopy.SquashingModelSmoothSat(lb, ub[:1], 2)
    with pytest.raises(ValueError, match="lower bound above upper bound"):
        crocopy.SquashingModelSmoothSat(ub, lb, 2)
    with pytest.raises(ValueError, match="smooth"):
        sq.smooth = 0.0


def test_actuation_squashing_model():
    state = crocopy.StateMultibody(load("solo12"))
    base = crocopy.ActuationModelFloatingBase(state)
    sq = crocopy.SquashingModelSmoothSat(-np.full(base.nu, 2.0), np.full(base.nu, 2.5), base.nu)
    act = crocopy.ActuationSquashingModel(base, sq, base.nu)
    data = act.createData()
    np.random.seed(2)
    x, u = state.rand(), 3 * np.random.rand(act.nu) - 1.5
    act.calc(data, x, u)
    act.calcDiff(data, x, u)
    assert np.allclose(data.tau[6:], data.squashing.u) and not data.tau[:6].any()
    num = np.zeros((state.nv, act.nu))
    for i in range(act.nu):
        e = np.zeros(act.nu)
        e[i] = H
        act.calc(data, x, u + e)
        tp = data.tau.copy()
        act.calc(data, x, u - e)
        num[:, i] = (tp - data.tau) / (2 * H)
    act.calc(data, x, u)
    act.calcDiff(data, x, u)
    assert np.allclose(data.dtau_du, num, atol=1e-8)
    assert np.all(np.isinf(act.u_lb)) and np.all(np.isinf(act.u_ub))
    tau = np.concatenate([np.zeros(6), np.linspace(-1.5, 2.0, base.nu)])
    act.commands(data, x, tau)
    act.calc(data, x, data.u.copy())
    assert np.allclose(data.tau, tau, atol=1e-9)
    with pytest.raises(ValueError, match="squashing.ns"):
        crocopy.ActuationSquashingModel(base, crocopy.SquashingModelSmoothSat(-np.ones(3), np.ones(3), 3), 3)


def test_actuation_bad_inputs():
    with pytest.raises(ValueError, match="StateMultibody"):
        crocopy.ActuationModelFull(crocopy.StateVector(4))
    with pytest.raises(ValueError, match="free-flyer"):
        crocopy.ActuationModelFloatingBase(crocopy.StateMultibody(load("kinova")))
    act = crocopy.ActuationModelFull(crocopy.StateMultibody(load("kinova")))
    with pytest.raises(ValueError, match=r"u_lb has shape \(2,\), expected \(6,\)"):
        act.u_lb = np.zeros(2)
