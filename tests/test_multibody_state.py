"""StateMultibody: Lie-group operations and Jacobians against finite differences; limits; collectors."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from robots import FLOATING, ROBOTS, load

import crocopy
from crocopy import Jcomponent

EPS = 1e-7  # finite-difference step on the tangent space
TOL = 1e-5  # agreement of analytic and forward-difference Jacobians (O(EPS) truncation)


def _fd(fun, x, state, nout):
    """Forward differences of ``fun`` (returning a tangent vector) along the tangent space at ``x``."""
    J = np.zeros((nout, state.ndx))
    f0 = fun(x)
    for i in range(state.ndx):
        dx = np.zeros(state.ndx)
        dx[i] = EPS
        J[:, i] = (fun(state.integrate(x, dx)) - f0) / EPS
    return J


@pytest.fixture(params=ROBOTS)
def state(request):
    np.random.seed(0)
    return crocopy.StateMultibody(load(request.param))


def test_dimensions_and_zero(state):
    model = state.pinocchio
    assert (state.nq, state.nv, state.nx, state.ndx) == (model.nq, model.nv, model.nq + model.nv, 2 * model.nv)
    x0 = state.zero()
    assert np.allclose(x0[: state.nq], pin.neutral(model)) and not x0[state.nq :].any()


def test_diff_integrate_roundtrip(state):
    x0, x1 = state.rand(), state.rand()
    dx = state.diff(x0, x1)
    assert np.allclose(state.diff(x0, state.integrate(x0, dx)), dx, atol=1e-10)
    assert np.allclose(state.diff(x0, x0), 0.0)
    assert pin.isNormalized(state.pinocchio, x0[: state.nq])


def test_Jdiff(state):
    x0, x1 = state.rand(), state.rand()
    J0, J1 = state.Jdiff(x0, x1)
    assert np.allclose(J0, _fd(lambda x: state.diff(x, x1), x0, state, state.ndx), atol=TOL)
    assert np.allclose(J1, _fd(lambda x: state.diff(x0, x), x1, state, state.ndx), atol=TOL)
    assert np.allclose(state.Jdiff(x0, x1, Jcomponent.first)[0], J0)
    assert np.allclose(state.Jdiff(x0, x1, Jcomponent.second)[0], J1)


def test_Jintegrate(state):
    x, dx = state.rand(), np.random.rand(state.ndx) - 0.5
    J0, J1 = state.Jintegrate(x, dx)
    x1 = state.integrate(x, dx)
    assert np.allclose(J0, _fd(lambda y: state.diff(x1, state.integrate(y, dx)), x, state, state.ndx), atol=TOL)
    num = np.zeros((state.ndx, state.ndx))
    for i in range(state.ndx):
        e = np.zeros(state.ndx)
        e[i] = EPS
        num[:, i] = state.diff(x1, state.integrate(x, dx + e)) / EPS
    assert np.allclose(J1, num, atol=TOL)
    assert np.allclose(state.Jintegrate(x, dx, Jcomponent.second)[0], J1)


@pytest.mark.parametrize("ncols", [3, 1, 0])
def test_JintegrateTransport(state, ncols):
    x, dx = state.rand(), np.random.rand(state.ndx) - 0.5
    Jin = np.random.rand(state.ndx, ncols)
    for comp in (Jcomponent.first, Jcomponent.second):
        J = Jin.copy()
        state.JintegrateTransport(x, dx, J, comp)
        Jq = state.Jintegrate(x, dx, comp)[0][: state.nv, : state.nv]
        expected = Jin.copy()
        expected[: state.nv] = Jq @ Jin[: state.nv]
        assert np.allclose(J, expected, atol=1e-10)


@pytest.mark.parametrize("name", FLOATING)
def test_limits_floating_base(name):
    model = load(name)
    state = crocopy.StateMultibody(model)
    assert np.all(np.isinf(state.lb[:7])) and np.all(np.isinf(state.ub[:7]))
    assert np.allclose(state.lb[7 : state.nq], model.lowerPositionLimit[7:])
    assert np.allclose(state.ub[state.nq + 6 :], model.velocityLimit[6:])
    assert np.all(np.isinf(state.ub[state.nq : state.nq + 6])) and state.has_limits


def test_bad_model():
    with pytest.raises(ValueError, match="pinocchio.Model"):
        crocopy.StateMultibody(np.zeros(3))


def test_collectors():
    model = load("anymal")
    data = model.createData()
    act = crocopy.ActuationModelFloatingBase(crocopy.StateMultibody(model))
    adata = act.createData()
    c = crocopy.DataCollectorActMultibody(data, adata)
    assert c.pinocchio is data and c.actuation is adata
    assert isinstance(c, crocopy.DataCollectorMultibody) and isinstance(c, crocopy.DataCollectorAbstract)
    c = crocopy.DataCollectorActMultibodyInContact(data, adata, [])
    assert c.contacts == [] and isinstance(c, crocopy.DataCollectorContact)
    c = crocopy.DataCollectorMultibodyInImpulse(data, [])
    assert c.impulses == [] and isinstance(c, crocopy.DataCollectorMultibody)


def test_in_place_forms_equal_the_public_operations(state):
    """``_integrate_into``, ``_diff_into``, ``_Jdiff_second_into`` and ``_integrate_chain_rule`` (used by
    residuals and Euler) give ``integrate``, ``diff``, ``Jdiff`` and ``Jintegrate``'s chain rule."""
    x0, x1 = state.rand(), state.rand()
    dx = 0.3 * np.random.rand(state.ndx)
    xout = np.full(state.nx, np.nan)
    state._integrate_into(x0, dx, xout)
    np.testing.assert_allclose(xout, state.integrate(x0, dx), atol=1e-14)
    out = np.full(state.ndx, np.nan)
    state._diff_into(x0, x1, out)
    np.testing.assert_allclose(out, state.diff(x0, x1), atol=1e-14)
    J = np.full((state.ndx, state.ndx), np.nan)
    state._Jdiff_second_into(x0, x1, J)
    np.testing.assert_allclose(J, state.Jdiff(x0, x1, Jcomponent.second)[0], atol=1e-14)
    Fx, Fu = np.random.rand(state.ndx, state.ndx), np.random.rand(state.ndx, 3)
    Jx, Jdx = state.Jintegrate(x0, dx, Jcomponent.both)
    expected_x, expected_u = Jx + Jdx @ Fx, Jdx @ Fu
    state._integrate_chain_rule(x0, dx, Fx, Fu)
    np.testing.assert_allclose(Fx, expected_x, atol=1e-12)
    np.testing.assert_allclose(Fu, expected_u, atol=1e-12)


def test_subclass_overriding_diff_is_honoured_by_the_in_place_forms():
    class ShiftedState(crocopy.StateMultibody):
        def diff(self, x0, x1):
            return super().diff(x0, x1) + 1.0

    state = ShiftedState(load("talos_arm"))
    residual = crocopy.ResidualModelState(state, state.zero(), state.nv)
    data = residual.createData(crocopy.DataCollectorAbstract())
    x = state.rand()
    residual.calc(data, x, np.zeros(state.nv))
    np.testing.assert_allclose(data.r, crocopy.StateMultibody.diff(state, state.zero(), x) + 1.0, atol=1e-14)

    class ShiftedIntegrate(crocopy.StateMultibody):
        def integrate(self, x, dx):
            return super().integrate(x, dx) + 1.0

    state = ShiftedIntegrate(load("talos_arm"))
    out = np.zeros(state.nx)
    state._integrate_into(x, np.zeros(state.ndx), out)
    np.testing.assert_allclose(out, x + 1.0, atol=1e-14)
