"""Constraint models: residual constraints, the manager, derivatives and wiring into action models."""

from __future__ import annotations

import numpy as np
import pytest

import crocopy
from crocopy.constraints.base import ConstraintModelResidual, ConstraintType
from crocopy.constraints.manager import ConstraintModelManager
from crocopy.residuals.base import ResidualDataAbstract, ResidualModelAbstract


class ResidualSinus(ResidualModelAbstract):
    """Nonlinear test residual ``r = [sin(x0) + x1 u0, x2² - cos(u1)]``."""

    def __init__(self, state, nu=2):
        super().__init__(state, 2, nu, True, True, True)

    def calc(self, data, x, u=None):
        u = np.zeros(self.nu) if u is None else u
        data.r[:] = [np.sin(x[0]) + x[1] * u[0], x[2] ** 2 - np.cos(u[1])]

    def calcDiff(self, data, x, u=None):
        u = np.zeros(self.nu) if u is None else u
        data.Rx[:] = 0.0
        data.Rx[0, 0] = np.cos(x[0])
        data.Rx[0, 1] = u[0]
        data.Rx[1, 2] = 2 * x[2]
        data.Ru[:] = [[x[1], 0.0], [0.0, np.sin(u[1])]]

    def createData(self, data=None):
        return ResidualDataAbstract(self, data)


@pytest.fixture
def state():
    return crocopy.StateVector(4)


def fd_jacobians(model, data, x, u, field):
    eps = 1e-7
    model.calc(data, x, u)
    f0 = getattr(data, field).copy()
    Jx = np.zeros((f0.size, x.size))
    Ju = np.zeros((f0.size, u.size))
    for i in range(x.size):
        xp = x.copy()
        xp[i] += eps
        model.calc(data, xp, u)
        Jx[:, i] = (getattr(data, field) - f0) / eps
    for i in range(u.size):
        up = u.copy()
        up[i] += eps
        model.calc(data, x, up)
        Ju[:, i] = (getattr(data, field) - f0) / eps
    return Jx, Ju


def test_residual_constraint_equality_and_inequality(state):
    res = crocopy.ResidualModelState(state, np.ones(4), 2)
    eq = ConstraintModelResidual(state, res)
    assert (eq.ng, eq.nh, eq.type, eq.T_constraint) == (0, 4, ConstraintType.Equality, True)
    ineq = ConstraintModelResidual(state, res, -np.ones(4), 2 * np.ones(4))
    assert (ineq.ng, ineq.nh, ineq.type) == (4, 0, ConstraintType.Inequality)
    np.testing.assert_array_equal(ineq.lb, -np.ones(4))
    x, u = np.arange(4.0), np.array([0.5, -2.0])
    for c in (eq, ineq):
        d = c.createData(crocopy.DataCollectorAbstract())
        c.calc(d, x, u)
        c.calcDiff(d, x, u)
        np.testing.assert_allclose(d.h if c.nh else d.g, x - 1.0)
        np.testing.assert_allclose(d.Hx if c.nh else d.Gx, np.eye(4))
    ineq.removeBounds()
    assert np.all(np.isinf(ineq.lb)) and np.all(np.isinf(ineq.ub))
    # a control-only residual is never a terminal constraint
    assert not ConstraintModelResidual(state, crocopy.ResidualModelControl(state, 2)).T_constraint
    assert not ConstraintModelResidual(state, res, False).T_constraint


def test_bad_bounds_and_shapes(state):
    res = crocopy.ResidualModelControl(state, 2)
    with pytest.raises(ValueError, match="lower"):
        ConstraintModelResidual(state, res, np.ones(2), -np.ones(2))
    with pytest.raises(ValueError, match="lower"):
        ConstraintModelResidual(state, res, np.ones(3), np.ones(3))
    m = ConstraintModelManager(state, 3)
    with pytest.raises(ValueError, match="nu"):
        m.addConstraint("c", ConstraintModelResidual(state, res))
    with pytest.raises(KeyError):
        m.removeConstraint("nothing")
    with pytest.raises(KeyError):
        m.changeConstraintStatus("nothing", False)


def test_manager_stacks_by_name_and_terminal_rows(state):
    m = ConstraintModelManager(state, 2)
    m.addConstraint("b", ConstraintModelResidual(state, crocopy.ResidualModelState(state, np.ones(4), 2),
                                                  -np.ones(4), 2 * np.ones(4)))
    m.addConstraint("a", ConstraintModelResidual(state, crocopy.ResidualModelControl(state, np.ones(2)),
                                                  -3 * np.ones(2), 4 * np.ones(2)))
    m.addConstraint("c", ConstraintModelResidual(state, crocopy.ResidualModelState(state, 2 * np.ones(4), 2), False))
    m.addConstraint("d", ConstraintModelResidual(state, crocopy.ResidualModelState(state, 3 * np.ones(4), 2)))
    assert list(m.constraints) == ["a", "b", "c", "d"]
    assert (m.ng, m.nh, m.ng_T, m.nh_T) == (6, 8, 4, 4)
    np.testing.assert_array_equal(m.g_lb, [-3, -3, -1, -1, -1, -1])
    np.testing.assert_array_equal(m.g_ub, [4, 4, 2, 2, 2, 2])
    d = m.createData(crocopy.DataCollectorAbstract())
    x, u = np.arange(4.0) * 0.3, np.array([0.5, -2.0])
    m.calc(d, x, u)
    np.testing.assert_allclose(d.g, [-0.5, -3.0, -1.0, -0.7, -0.4, -0.1])
    np.testing.assert_allclose(d.h, np.r_[x - 2, x - 3])
    m.calc(d, x)
    np.testing.assert_allclose(d.g, [-1.0, -0.7, -0.4, -0.1, 0.0, 0.0])
    np.testing.assert_allclose(d.h, np.r_[x - 3, np.zeros(4)])
    m.calcDiff(d, x)
    np.testing.assert_allclose(d.Gx[:4], np.eye(4))
    np.testing.assert_allclose(d.Gu, 0.0)
    m.changeConstraintStatus("c", False)
    assert m.inactive_set == {"c"} and m.active_set == {"a", "b", "d"}
    assert not m.getConstraintStatus("c")
    assert (m.nh, m.nh_T) == (4, 4)
    with pytest.raises(ValueError, match="create the data again"):
        m.calc(d, x, u)
    m.removeConstraint("a")
    assert (m.ng, m.ng_T) == (4, 4)


def test_constraint_derivatives_match_finite_differences(state):
    rng = np.random.default_rng(0)
    m = ConstraintModelManager(state, 2)
    m.addConstraint("eq", ConstraintModelResidual(state, ResidualSinus(state)))
    m.addConstraint("in", ConstraintModelResidual(state, ResidualSinus(state), -np.ones(2), np.ones(2)))
    m.addConstraint("x", ConstraintModelResidual(state, crocopy.ResidualModelState(state, rng.standard_normal(4), 2)))
    d = m.createData()
    for _ in range(3):
        x, u = rng.standard_normal(4), rng.standard_normal(2)
        m.calcDiff(d, x, u)
        Gx, Gu, Hx, Hu = d.Gx.copy(), d.Gu.copy(), d.Hx.copy(), d.Hu.copy()
        for field, (Ax, Au) in (("g", (Gx, Gu)), ("h", (Hx, Hu))):
            Jx, Ju = fd_jacobians(m, d, x, u, field)
            np.testing.assert_allclose(Ax, Jx, atol=1e-5)
            np.testing.assert_allclose(Au, Ju, atol=1e-5)


def test_share_memory_with_action_data_and_integrators(state):
    """A differential model wired to a manager exposes its rows; the integrators copy them."""

    class DAMWithConstraints(crocopy.DifferentialActionModelAbstract):
        def __init__(self, constraints):
            super().__init__(state, 2, 1, constraints.ng, constraints.nh, constraints.ng_T, constraints.nh_T)
            self.constraints = constraints
            self.g_lb, self.g_ub = constraints.g_lb, constraints.g_ub

        def createData(self):
            data = crocopy.DifferentialActionDataAbstract(self)
            data.constraints = self.constraints.createData()
            data.constraints.shareMemory(data)
            return data

        def calc(self, data, x, u=None):
            data.xout[:] = 0.0 if u is None else u - x[:2]
            data.cost = 0.0
            self.constraints.calc(data.constraints, x, u)

        def calcDiff(self, data, x, u=None):
            if u is not None:
                data.Fx[:] = np.hstack([-np.eye(2), np.zeros((2, 2))])
                data.Fu[:] = np.eye(2)
            self.constraints.calcDiff(data.constraints, x, u)

    m = ConstraintModelManager(state, 2)
    m.addConstraint("s", ConstraintModelResidual(state, ResidualSinus(state)))
    ures = crocopy.ResidualModelControl(state, 2)
    m.addConstraint("u", ConstraintModelResidual(state, ures, -np.ones(2), np.ones(2)))
    dam = DAMWithConstraints(m)
    x, u = np.array([0.1, 0.2, 0.3, 0.4]), np.array([0.7, -0.2])
    for iam in (crocopy.IntegratedActionModelEuler(dam, 1e-2),
                crocopy.IntegratedActionModelRK(dam, crocopy.RKType.four, 1e-2)):
        assert (iam.ng, iam.nh, iam.ng_T, iam.nh_T) == (2, 2, 0, 2)
        np.testing.assert_array_equal(iam.g_lb, -np.ones(2))
        d = iam.createData()
        iam.calc(d, x, u)
        iam.calcDiff(d, x, u)
        np.testing.assert_allclose(d.h, [np.sin(0.1) + 0.2 * 0.7, 0.09 - np.cos(-0.2)])
        np.testing.assert_allclose(d.g, u)
        np.testing.assert_allclose(d.Gu, np.eye(2))
        np.testing.assert_allclose(d.Hu, [[0.2, 0.0], [0.0, np.sin(-0.2)]])
    data = crocopy.DifferentialActionDataAbstract(crocopy.DifferentialActionModelLQR(2, 2))
    with pytest.raises(ValueError, match="data.g has shape"):
        m.createData().shareMemory(data)


def test_models_follow_their_manager():
    """As in Crocoddyl, a model's ng, nh, ng_T, nh_T and bounds follow its manager after a status change
    (running-only items leave the terminal counts); a data created afterwards has the new rows."""
    from robots import load

    model = load("talos_arm")
    ms = crocopy.StateMultibody(model)
    act = crocopy.ActuationModelFull(ms)
    m = ConstraintModelManager(ms, act.nu)
    m.addConstraint("a_run", ConstraintModelResidual(ms, crocopy.ResidualModelControl(ms, act.nu),
                                                     -np.ones(act.nu), np.ones(act.nu), False))
    m.addConstraint("b_both", ConstraintModelResidual(ms, crocopy.ResidualModelCoMPosition(ms, np.zeros(3), act.nu),
                                                      -2 * np.ones(3), 2 * np.ones(3)))
    m.addConstraint("c_eq", ConstraintModelResidual(ms, crocopy.ResidualModelCoMPosition(ms, np.ones(3), act.nu)))
    dam = crocopy.DifferentialActionModelFreeFwdDynamics(ms, act, crocopy.CostModelSum(ms, act.nu), m)
    models = (dam, crocopy.IntegratedActionModelEuler(dam, 1e-2), crocopy.IntegratedActionModelRK(dam, crocopy.four,
                                                                                                    1e-2))
    nu = act.nu
    for mod in models:
        assert (mod.ng, mod.nh, mod.ng_T, mod.nh_T) == (nu + 3, 3, 3, 3)
        np.testing.assert_array_equal(mod.g_lb, np.r_[-np.ones(nu), -2 * np.ones(3)])
    m.changeConstraintStatus("a_run", False)
    for mod in models:
        assert (mod.ng, mod.nh, mod.ng_T, mod.nh_T) == (3, 3, 3, 3)
        np.testing.assert_array_equal(mod.g_ub, 2 * np.ones(3))
        d = mod.createData()
        x = ms.zero()
        mod.calc(d, x, np.zeros(nu))
        assert d.g.shape == (3,) and d.h.shape == (3,)
    m.changeConstraintStatus("b_both", False)
    assert (dam.ng, dam.ng_T, dam.g_lb.shape) == (0, 0, (0,))
    m.changeConstraintStatus("b_both", True)
    dam.g_lb = -3 * np.ones(3)  # an assigned bound stays
    np.testing.assert_array_equal(dam.g_lb, -3 * np.ones(3))
    np.testing.assert_array_equal(m.g_lb, -2 * np.ones(3))
