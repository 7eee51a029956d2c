"""Squashing wrapper: squashing functions and chain-rule derivatives against finite differences."""

import numpy as np
import pytest

from crocopy import ActionModelLQR, ActionModelUnicycle
from crocopy.actions.control_penalty import ActionModelControlPenalty
from crocopy.shooting import ShootingProblem
from crocopy.solvers import SolverDDP
from crocopy.squashing.action import ActionModelSquashed, smooth_sat, smooth_sat_diff, tanh_squash, tanh_squash_diff

H = 1e-6


def limited_lqr(nx=4, nu=3, seed=0):
    np.random.seed(seed)
    model = ActionModelLQR.Random(nx, nu)
    model.u_lb = -np.linspace(0.5, 1.5, nu)
    model.u_ub = np.linspace(1.0, 2.0, nu)
    return model


def limited_unicycle():
    model = ActionModelUnicycle()
    model.u_lb = np.array([-1.0, -0.5])
    model.u_ub = np.array([2.0, 0.5])
    return model


@pytest.mark.parametrize("kind", ["smooth-sat", "tanh"])
def test_squashing_functions(kind):
    lb, ub = np.array([-1.0, 0.1]), np.array([2.0, 10.3])
    u = np.array([0.3, -4.0])
    if kind == "tanh":
        s, ds = lambda v: tanh_squash(v, lb, ub), lambda v: tanh_squash_diff(v, lb, ub)
    else:
        s, ds = lambda v: smooth_sat(v, lb, ub, 2.0), lambda v: smooth_sat_diff(v, lb, ub, 2.0)
    d1, d2 = ds(u)
    assert np.allclose(d1, (s(u + H) - s(u - H)) / (2 * H), atol=1e-8)
    assert np.allclose(d2, (ds(u + H)[0] - ds(u - H)[0]) / (2 * H), atol=1e-7)
    assert np.allclose(s(np.full(2, 1e8)), ub, atol=1e-6)
    assert np.allclose(s(np.full(2, -1e8)), lb, atol=1e-6)
    w = s(np.linspace(-3, 3, 2))
    assert np.all(w > lb) and np.all(w < ub)
    assert np.allclose(s(0.5 * (lb + ub)) if kind != "tanh" else s(np.zeros(2)), 0.5 * (lb + ub))


def finite_differences(model, data, x, u):
    """Central differences of xnext, cost and Lu (Lu from the analytic calcDiff)."""
    nx, nu = model.state.nx, model.nu
    Fx, Fu, Lx, Lu = np.zeros((nx, nx)), np.zeros((nx, nu)), np.zeros(nx), np.zeros(nu)
    Luu, Lxu = np.zeros((nu, nu)), np.zeros((nx, nu))

    def outputs(xx, uu):
        model.calc(data, xx, uu)
        model.calcDiff(data, xx, uu)
        return data.xnext.copy(), data.cost, data.Lu.copy()

    for i in range(nx):
        e = np.zeros(nx)
        e[i] = H
        xp, cp, Lup = outputs(x + e, u)
        xm, cm, Lum = outputs(x - e, u)
        Fx[:, i], Lx[i], Lxu[i] = (xp - xm) / (2 * H), (cp - cm) / (2 * H), (Lup - Lum) / (2 * H)
    for j in range(nu):
        e = np.zeros(nu)
        e[j] = H
        xp, cp, Lup = outputs(x, u + e)
        xm, cm, Lum = outputs(x, u - e)
        Fu[:, j], Lu[j], Luu[:, j] = (xp - xm) / (2 * H), (cp - cm) / (2 * H), (Lup - Lum) / (2 * H)
    return Fx, Fu, Lx, Lu, Lxu, Luu


@pytest.mark.parametrize("kind", ["smooth-sat", "tanh"])
@pytest.mark.parametrize("make", [limited_lqr, limited_unicycle])
def test_chain_rule_against_finite_differences(kind, make):
    model = ActionModelSquashed(make(), kind, smooth=1.5, rawWeight=0.3)
    data = model.createData()
    rng = np.random.default_rng(1)
    x, u = rng.standard_normal(model.state.nx), 2.0 * rng.standard_normal(model.nu)
    Fx, Fu, Lx, Lu, Lxu, Luu = finite_differences(model, data, x, u)
    model.calc(data, x, u)
    model.calcDiff(data, x, u)
    assert np.allclose(data.Fx, Fx, atol=1e-6)
    assert np.allclose(data.Fu, Fu, atol=1e-6)
    assert np.allclose(data.Lx, Lx, atol=1e-5)
    assert np.allclose(data.Lu, Lu, atol=1e-5)
    assert np.allclose(data.Lxu, Lxu, atol=1e-5)
    assert np.allclose(data.Luu, Luu, atol=1e-5)
    assert np.allclose(data.Luu, data.Luu.T)
    # the inner model really saw s(u), and the raw-control cost is added
    inner = model.model.createData()
    model.model.calc(inner, x, model.squash(u))
    assert np.allclose(data.xnext, inner.xnext)
    assert np.isclose(data.cost, inner.cost + 0.15 * u @ u)


def test_terminal_node_is_the_inner_terminal():
    model = ActionModelSquashed(limited_unicycle(), "tanh")
    data, inner = model.createData(), model.model.createData()
    x = np.array([0.3, -0.2, 0.5])
    model.calc(data, x)
    model.calcDiff(data, x)
    model.model.calc(inner, x)
    model.model.calcDiff(inner, x)
    assert data.cost == inner.cost
    assert np.allclose(data.Lxx, inner.Lxx)


class _HalfTanhSquashing:
    """A Crocoddyl-protocol squashing model written independently for the test."""

    class Data:
        def __init__(self, ns):
            self.u = np.zeros(ns)
            self.du_ds = np.zeros((ns, ns))

    def __init__(self, ns):
        self.ns, self.s_lb, self.s_ub = ns, -0.5 * np.ones(ns), 0.5 * np.ones(ns)

    def createData(self):
        return self.Data(self.ns)

    def calc(self, data, s):
        data.u[:] = 0.5 * np.tanh(s)

    def calcDiff(self, data, s):
        data.du_ds[:] = np.diag(0.5 / np.cosh(s) ** 2)


def test_squashing_model_protocol():
    model = ActionModelSquashed(limited_unicycle(), _HalfTanhSquashing(2), rawWeight=0.0)
    ref = ActionModelSquashed(limited_unicycle(), "tanh", s_lb=-0.5 * np.ones(2), s_ub=0.5 * np.ones(2), rawWeight=0.0)
    d, dr = model.createData(), ref.createData()
    x, u = np.array([0.1, 0.2, 0.3]), np.array([0.7, -0.4])
    for m, dd in ((model, d), (ref, dr)):
        m.calc(dd, x, u)
        m.calcDiff(dd, x, u)
    assert np.allclose(d.xnext, dr.xnext) and np.isclose(d.cost, dr.cost)
    assert np.allclose(d.Fu, dr.Fu) and np.allclose(d.Lu, dr.Lu)


def test_bad_arguments():
    with pytest.raises(ValueError, match="finite"):
        ActionModelSquashed(ActionModelUnicycle())
    with pytest.raises(ValueError, match="s_lb"):
        ActionModelSquashed(ActionModelUnicycle(), s_lb=np.array([1.0, 1.0]), s_ub=np.array([0.0, 2.0]))
    with pytest.raises(ValueError, match="NaN"):
        ActionModelSquashed(ActionModelUnicycle(), s_lb=np.array([np.nan, 1.0]), s_ub=np.array([2.0, 2.0]))
    with pytest.raises(ValueError, match="squashing"):
        ActionModelSquashed(limited_unicycle(), "sigmoid")


def test_control_penalty_derivatives_and_effect():
    inner = limited_unicycle()
    model = ActionModelControlPenalty(inner, weight=50.0)
    data = model.createData()
    x = np.array([0.2, -0.4, 0.9])
    for u in (np.array([2.7, -0.9]), np.array([0.5, 0.1])):  # outside, inside the box
        Fx, Fu, Lx, Lu, Lxu, Luu = finite_differences(model, data, x, u)
        model.calc(data, x, u)
        model.calcDiff(data, x, u)
        assert np.allclose(data.Lu, Lu, atol=1e-5) and np.allclose(data.Luu, Luu, atol=1e-4)
        assert np.allclose(data.Fu, Fu, atol=1e-6) and np.allclose(data.Lx, Lx, atol=1e-5)
        ref = inner.createData()
        inner.calc(ref, x, u)
        r = np.minimum(u - inner.u_lb, 0.0) + np.maximum(u - inner.u_ub, 0.0)
        assert np.isclose(data.cost, ref.cost + 25.0 * r @ r)
    # a heavier penalty pushes a DDP solution closer to the box
    violations = []
    for weight in (1.0, 1e4):
        m = ActionModelControlPenalty(ActionModelUnicycle(), weight, lb=[-0.3, -0.2], ub=[0.3, 0.2])
        problem = ShootingProblem(np.array([1.0, 2.0, 0.5]), [m] * 20, ActionModelUnicycle())
        solver = SolverDDP(problem)
        solver.solve(None, None, 100)
        us = np.array(solver.us)
        violations.append(np.max(np.maximum(us - [0.3, 0.2], 0.0) + np.maximum([-0.3, -0.2] - us, 0.0)))
    assert violations[0] > 0.1 and violations[1] < 1e-2 * violations[0]
    with pytest.raises(ValueError, match="lb"):
        ActionModelControlPenalty(ActionModelUnicycle(), 1.0, lb=[1.0, 1.0], ub=[0.0, 2.0])
