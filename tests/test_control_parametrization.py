"""Control parametrizations on their own and inside the integrators (× differential model), against
numerical differentiation; constructor overloads and bad arguments."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_free_fwd_dynamics import make_dam

import crocopy
from crocopy.state import StateAbstract

RK = crocopy.RKType


class LinearMapControl(crocopy.ControlParametrizationModelAbstract):
    """A user-defined parametrization ``w = (M₀ + t M₁) u``: uses the base class's Jacobian products."""

    def __init__(self, nw: int, nu: int, seed: int = 0) -> None:
        super().__init__(nw, nu)
        rng = np.random.default_rng(seed)
        self.M0, self.M1 = rng.standard_normal((nw, nu)), rng.standard_normal((nw, nu))

    def calc(self, data, t, u):
        data.w[:] = (self.M0 + t * self.M1) @ u

    def calcDiff(self, data, t, u):
        data.dw_du[:] = self.M0 + t * self.M1

    def params(self, data, t, w):
        data.u[:] = np.linalg.lstsq(self.M0 + t * self.M1, w, rcond=None)[0]

    def convertBounds(self, w_lb, w_ub, u_lb=None, u_ub=None):
        return [np.full(self.nu, -np.inf), np.full(self.nu, np.inf)]


class ScaledControl(crocopy.ControlParametrizationModelAbstract):
    """``w = (1 + t) u``, overriding the Jacobian products with Crocoddyl's abstract signature ``(data, A)``."""

    def __init__(self, nw: int) -> None:
        super().__init__(nw, nw)

    def calc(self, data, t, u):
        data.scale = 1.0 + t
        data.w[:] = data.scale * u

    def calcDiff(self, data, t, u):
        data.dw_du[:] = (1.0 + t) * np.eye(self.nw)

    def params(self, data, t, w):
        data.u[:] = w / (1.0 + t)

    def convertBounds(self, w_lb, w_ub, u_lb=None, u_ub=None):
        return [w_lb / 2.0, w_ub / 2.0]

    def multiplyByJacobian(self, data, A):
        return data.scale * A

    def multiplyJacobianTransposeBy(self, data, A):
        return data.scale * A


class SlowPolyZero(crocopy.ControlParametrizationModelPolyZero):
    """PolyZero that the integrators do not recognise: it goes through the general Jacobian path."""


CONTROLS = {
    "poly0": crocopy.ControlParametrizationModelPolyZero,
    "poly1": crocopy.ControlParametrizationModelPolyOne,
    "poly2rk3": lambda nw: crocopy.ControlParametrizationModelPolyTwoRK(nw, RK.three),
    "poly2rk4": lambda nw: crocopy.ControlParametrizationModelPolyTwoRK(nw, RK.four),
    "linear_map": lambda nw: LinearMapControl(nw, nw + 1),
    "scaled": ScaledControl,
}
POLYNOMIALS = ("poly0", "poly1", "poly2rk3", "poly2rk4")
NODES = {"poly0": (0.0,), "poly1": (0.0, 0.5), "poly2rk3": (0.0, 1 / 3, 2 / 3), "poly2rk4": (0.0, 0.5, 1.0)}
INTEGRATORS = {
    "euler": lambda dam, control, dt: crocopy.IntegratedActionModelEuler(dam, control, dt),
    "rk2": lambda dam, control, dt: crocopy.IntegratedActionModelRK(dam, control, RK.two, dt),
    "rk3": lambda dam, control, dt: crocopy.IntegratedActionModelRK(dam, control, RK.three, dt),
    "rk4": lambda dam, control, dt: crocopy.IntegratedActionModelRK(dam, control, RK.four, dt),
}
DAMS = {
    "dlqr": lambda: crocopy.DifferentialActionModelLQR.Random(3, 2),
    "dlqr_constrained": lambda: crocopy.DifferentialActionModelLQR.Random(2, 2, 1, 1),
}


def _evaluate(model, x, u):
    data = model.createData()
    model.calc(data, x, u)
    model.calcDiff(data, x, u)
    return data


def _numdiff(model, x, u, hessians: bool = True):
    """Central differences; without ``hessians`` the cheap Gauss-Newton ones (O(n) instead of O(n²) calls)."""
    return _evaluate(crocopy.ActionModelNumDiff(model, with_gauss_approx=not hessians), x, u)


# ---------------------------------------------------------------- the parametrizations alone


@pytest.mark.parametrize("name", POLYNOMIALS)
def test_polynomial_passes_through_its_nodes_and_reproduces_its_degree(name):
    """``uₖ`` is ``w`` at node ``tₖ``; any polynomial of the model's degree is reproduced exactly."""
    nw, nodes = 3, NODES[name]
    control = CONTROLS[name](nw)
    data = control.createData()
    rng = np.random.default_rng(0)
    assert (control.nw, control.nu) == (nw, nw * len(nodes))
    coefficients = rng.standard_normal((len(nodes), nw))

    def exact(t):
        return sum(a * t**k for k, a in enumerate(coefficients))

    u = np.concatenate([exact(t) for t in nodes])
    for k, t in enumerate(nodes):
        control.calc(data, t, u)
        np.testing.assert_allclose(data.w, u[k * nw : (k + 1) * nw], atol=1e-14)
    for t in rng.uniform(-0.5, 1.5, 5):
        control.calc(data, t, u)
        np.testing.assert_allclose(data.w, exact(t), atol=1e-12)


@settings(max_examples=40, deadline=None)
@given(
    name=st.sampled_from(sorted(set(CONTROLS) - {"scaled"})),
    nw=st.integers(1, 4),
    t=st.floats(0.0, 1.0),
    seed=st.integers(0, 2**16),
)
def test_jacobian_products_and_params_agree_with_calc(name, nw, t, seed):
    """``dw_du`` is the derivative of ``calc`` (which is linear in ``u``); the products equal
    ``A dw_du`` and ``dw_duᵀ A``; ``calc`` of ``params(t, w)`` gives back ``w``."""
    control = CONTROLS[name](nw)
    data = control.createData()
    rng = np.random.default_rng(seed)
    u = rng.standard_normal(control.nu)
    control.calc(data, t, u)
    control.calcDiff(data, t, u)
    w = data.w.copy()
    np.testing.assert_allclose(data.dw_du @ u, w, atol=1e-12)
    for j in range(control.nu):
        control.calc(data, t, u + np.eye(control.nu)[j])
        np.testing.assert_allclose(data.w - w, data.dw_du[:, j], atol=1e-12)
    control.calc(data, t, u)
    A = rng.standard_normal((5, nw))
    np.testing.assert_allclose(control.multiplyByJacobian(data, A), A @ data.dw_du, atol=1e-12)
    np.testing.assert_allclose(control.multiplyJacobianTransposeBy(data, A.T), data.dw_du.T @ A.T, atol=1e-12)
    out = np.ones((5, control.nu))
    control.multiplyByJacobian(data, A, crocopy.AssignmentOp.addto, out)
    np.testing.assert_allclose(out, 1.0 + A @ data.dw_du, atol=1e-12)
    control.multiplyJacobianTransposeBy(data, A.T, crocopy.AssignmentOp.rmfrom, out.T)
    np.testing.assert_allclose(out, 1.0, atol=1e-12)
    target = rng.standard_normal(nw)
    control.params(data, t, target)
    control.calc(data, t, data.u.copy())
    np.testing.assert_allclose(data.w, target, atol=1e-9)


@pytest.mark.parametrize("name", POLYNOMIALS)
def test_params_is_the_constant_polynomial(name):
    control = CONTROLS[name](2)
    data = control.createData()
    control.params(data, 0.3, np.array([1.5, -2.0]))
    for t in (0.0, 0.25, 0.9, 1.0):
        control.calc(data, t, data.u.copy())
        np.testing.assert_allclose(data.w, [1.5, -2.0], atol=1e-14)


@pytest.mark.parametrize("name", POLYNOMIALS)
def test_convert_bounds_repeats_the_bounds_per_node(name):
    control = CONTROLS[name](2)
    blocks = len(NODES[name])
    lb, ub = np.array([-1.0, -np.inf]), np.array([2.0, 3.0])
    u_lb, u_ub = control.convertBounds(lb, ub)
    np.testing.assert_array_equal(u_lb, np.tile(lb, blocks))
    np.testing.assert_array_equal(u_ub, np.tile(ub, blocks))
    out_lb, out_ub = np.zeros(control.nu), np.zeros(control.nu)
    control.convertBounds(lb, ub, out_lb, out_ub)
    np.testing.assert_array_equal(out_lb, u_lb)
    np.testing.assert_array_equal(out_ub, u_ub)
    with pytest.raises(ValueError, match=r"w_lb has shape \(3,\), expected \(2,\)"):
        control.convertBounds(np.zeros(3), ub)


def test_data_types_and_fields_follow_crocoddyl():
    zero, one = crocopy.ControlParametrizationModelPolyZero(2), crocopy.ControlParametrizationModelPolyOne(2)
    two = crocopy.ControlParametrizationModelPolyTwoRK(2, RK.four)
    assert type(zero.createData()) is crocopy.ControlParametrizationDataAbstract
    np.testing.assert_array_equal(zero.createData().dw_du, np.eye(2))
    d1, d = one.createData(), two.createData()
    assert isinstance(d1, crocopy.ControlParametrizationDataPolyOne) and d1.c.shape == (2,)
    assert isinstance(d, crocopy.ControlParametrizationDataPolyTwoRK) and d.c.shape == (3,)
    assert (d.w.shape, d.u.shape, d.dw_du.shape) == ((2,), (6,), (2, 6))
    assert repr(two) == "ControlParametrizationModelPolyTwoRK {nw=2, rktype=four}"
    assert repr(one) == "ControlParametrizationModelPolyOne {nw=2}"


def test_bad_parametrization_arguments_raise_clear_errors():
    for bad in (-1, 2.5, True, "2"):
        with pytest.raises(ValueError, match="nw must be a non-negative integer"):
            crocopy.ControlParametrizationModelPolyOne(bad)
    for rktype in (RK.two, 7, "four"):
        with pytest.raises(ValueError, match="rktype must be RKType.three or RKType.four"):
            crocopy.ControlParametrizationModelPolyTwoRK(2, rktype)
    control = crocopy.ControlParametrizationModelPolyOne(2)
    data = control.createData()
    control.calc(data, 0.2, np.ones(4))
    with pytest.raises(ValueError, match=r"A has shape \(3, 3\), expected \(na, nw\) with nw = 2"):
        control.multiplyByJacobian(data, np.ones((3, 3)))
    with pytest.raises(ValueError, match=r"expected \(nw, na\)"):
        control.multiplyJacobianTransposeBy(data, np.ones((3, 3)))
    with pytest.raises(ValueError, match="op=addto needs an output matrix out"):
        control.multiplyByJacobian(data, np.ones((3, 2)), crocopy.AssignmentOp.addto)
    with pytest.raises(ValueError, match=r"w has shape \(3,\), expected \(2,\)"):
        control.params(data, 0.0, np.ones(3))
    abstract = crocopy.ControlParametrizationModelAbstract(2, 4)
    assert (abstract.nw, abstract.nu) == (2, 4)
    for call, size in ((abstract.calc, 4), (abstract.calcDiff, 4), (abstract.params, 2)):
        with pytest.raises(NotImplementedError):
            call(abstract.createData(), 0.0, np.zeros(size))


# ---------------------------------------------------------------- inside the integrators


def _check_against_numdiff(model, x, u, hessians: bool) -> None:
    d, dn = _evaluate(model, x, u), _numdiff(model, x, u, hessians)
    np.testing.assert_allclose(d.xnext, dn.xnext, atol=1e-14)
    assert d.cost == pytest.approx(dn.cost, rel=1e-12, abs=1e-12)
    fields = ["Fx", "Fu", "Lx", "Lu", "Gx", "Gu", "Hx", "Hu"] + (["Lxx", "Lxu", "Luu"] if hessians else [])
    for name in fields:
        numeric = getattr(dn, name)
        tol = (1e-4 if name.startswith("L") and len(name) == 3 else 1e-6) * max(1.0, np.abs(numeric).max(initial=0.0))
        np.testing.assert_allclose(getattr(d, name), numeric, atol=tol, rtol=0, err_msg=name)


@pytest.mark.parametrize("integrator", sorted(INTEGRATORS))
@pytest.mark.parametrize("control", sorted(CONTROLS))
@pytest.mark.parametrize("dam", sorted(DAMS))
def test_lqr_nodes_against_numdiff(dam, control, integrator):
    """Values and every derivative (the Hessians are exact for linear dynamics and a quadratic cost)."""
    diff = DAMS[dam]()
    model = INTEGRATORS[integrator](diff, CONTROLS[control](diff.nu), 5e-2)
    assert model.nu == model.control.nu
    rng = np.random.default_rng(4)
    _check_against_numdiff(model, model.state.rand(), rng.standard_normal(model.nu), hessians=True)


@pytest.mark.parametrize("integrator", sorted(INTEGRATORS))
@pytest.mark.parametrize("control", sorted(CONTROLS))
@pytest.mark.parametrize("robot", ["talos_arm", "solo12"])
def test_free_dynamics_nodes_against_numdiff(robot, control, integrator):
    diff = make_dam(robot)
    model = INTEGRATORS[integrator](diff, CONTROLS[control](diff.nu), 1e-2)
    rng = np.random.default_rng(5)
    _check_against_numdiff(model, model.state.rand(), 0.5 * rng.standard_normal(model.nu), hessians=False)


class _DenseJacobianState(crocopy.StateMultibody):
    """A multibody state without the row transport: Euler falls back to dense ``Jintegrate`` products."""

    JintegrateTransport = StateAbstract.JintegrateTransport


@pytest.mark.parametrize("control", ["poly0", "poly1", "linear_map"])
def test_euler_dense_fallback_against_numdiff(control):
    diff = make_dam("solo12")
    diff.state.__class__ = _DenseJacobianState
    model = crocopy.IntegratedActionModelEuler(diff, CONTROLS[control](diff.nu), 1e-2)
    assert not model._transport and not model._euclidean
    rng = np.random.default_rng(6)
    _check_against_numdiff(model, model.state.rand(), 0.5 * rng.standard_normal(model.nu), hessians=False)


@pytest.mark.parametrize("integrator", sorted(INTEGRATORS))
def test_general_path_equals_the_polyzero_shortcut(integrator):
    """A PolyZero the integrators do not recognise (products through ``dw_du``) gives the shortcut's numbers."""
    diff = make_dam("talos_arm")
    fast = INTEGRATORS[integrator](diff, crocopy.ControlParametrizationModelPolyZero(diff.nu), 1e-2)
    slow = INTEGRATORS[integrator](diff, SlowPolyZero(diff.nu), 1e-2)
    assert fast._identity_control and not slow._identity_control
    rng = np.random.default_rng(7)
    x, u = diff.state.rand(), rng.standard_normal(diff.nu)
    d_fast, d_slow = _evaluate(fast, x, u), _evaluate(slow, x, u)
    for name in ("xnext", "Fx", "Fu", "Lx", "Lu", "Lxx", "Lxu", "Luu"):
        np.testing.assert_allclose(getattr(d_slow, name), getattr(d_fast, name), rtol=1e-13, atol=1e-13, err_msg=name)
    assert d_slow.cost == d_fast.cost


@pytest.mark.parametrize("integrator", sorted(INTEGRATORS))
@pytest.mark.parametrize("control", POLYNOMIALS)
def test_constant_parameters_give_the_constant_control_node(control, integrator):
    """``u = params(w)`` (a constant polynomial) moves the system as ``w`` under PolyZero; the column
    blocks of ``Fu`` sum to PolyZero's ``Fu`` (the Lagrange coefficients sum to one)."""
    diff = DAMS["dlqr"]()
    model = INTEGRATORS[integrator](diff, CONTROLS[control](diff.nu), 5e-2)
    reference = INTEGRATORS[integrator](diff, None, 5e-2)
    rng = np.random.default_rng(8)
    x, w = diff.state.rand(), rng.standard_normal(diff.nu)
    cdata = model.control.createData()
    model.control.params(cdata, 0.0, w)
    d, d0 = _evaluate(model, x, cdata.u), _evaluate(reference, x, w)
    np.testing.assert_allclose(d.xnext, d0.xnext, atol=1e-13)
    assert d.cost == pytest.approx(d0.cost, rel=1e-13)
    np.testing.assert_allclose(d.Fu.reshape(-1, len(NODES[control]), diff.nu).sum(axis=1), d0.Fu, atol=1e-13)


@pytest.mark.parametrize("integrator", sorted(INTEGRATORS))
def test_integrated_model_takes_the_parametrization_dimensions_and_bounds(integrator):
    diff = crocopy.DifferentialActionModelLQR(2, 2)
    diff.u_lb, diff.u_ub = np.array([-1.0, -2.0]), np.array([1.0, 2.0])
    control = crocopy.ControlParametrizationModelPolyTwoRK(2, RK.four)
    model = INTEGRATORS[integrator](diff, control, 1e-2)
    assert model.control is control and model.nu == 6 and model.has_control_limits
    np.testing.assert_array_equal(model.u_lb, [-1.0, -2.0] * 3)
    np.testing.assert_array_equal(model.u_ub, [1.0, 2.0] * 3)
    data = model.createData()
    assert data.Fu.shape == (4, 6) and data.Luu.shape == (6, 6)
    with pytest.raises(AttributeError):
        model.control = crocopy.ControlParametrizationModelPolyZero(2)
    default = INTEGRATORS[integrator](diff, None, 1e-2)
    assert type(default.control) is crocopy.ControlParametrizationModelPolyZero and default.nu == 2


@pytest.mark.parametrize("integrator", sorted(INTEGRATORS))
def test_quasi_static_returns_parameters(integrator):
    diff = crocopy.DifferentialActionModelLQR(2, 2)
    model = INTEGRATORS[integrator](diff, crocopy.ControlParametrizationModelPolyOne(2), 1e-2)
    x = np.array([0.3, -0.2, 0.0, 0.0])
    u = model.quasiStatic(model.createData(), x)
    assert u.shape == (4,)
    data = model.createData()
    model.calc(data, x, u)
    np.testing.assert_allclose(data.xnext, x, atol=1e-9)


def test_terminal_node_has_no_control_jacobian():
    diff = DAMS["dlqr_constrained"]()
    model = crocopy.IntegratedActionModelRK(diff, crocopy.ControlParametrizationModelPolyOne(diff.nu), RK.four, 1e-2)
    data = model.createData()
    data.Gu[:] = 1.0
    x = diff.state.rand()
    model.calc(data, x)
    model.calcDiff(data, x)
    np.testing.assert_array_equal(data.Gu, 0.0)
    dn = _numdiff(model, x, None)
    np.testing.assert_allclose(data.Lx, dn.Lx, atol=1e-6)


def test_parametrized_lqr_problem_solves_in_one_step():
    """An LQ problem stays LQ under a linear parametrization: FDDP converges in one iteration and its
    solution satisfies the dynamics."""
    diff = crocopy.DifferentialActionModelLQR(2, 2, False)
    model = crocopy.IntegratedActionModelRK(
        diff, crocopy.ControlParametrizationModelPolyTwoRK(2, RK.four), RK.four, 5e-2
    )
    problem = crocopy.ShootingProblem(np.ones(4), [model] * 10, model)
    solver = crocopy.SolverFDDP(problem)
    assert solver.solve([], [], 10)
    assert solver.iter <= 2 and solver.us[0].shape == (6,)
    data = model.createData()
    for x, u, xn in zip(solver.xs[:-1], solver.us, solver.xs[1:]):
        model.calc(data, x, u)
        np.testing.assert_allclose(data.xnext, xn, atol=1e-9)


# ---------------------------------------------------------------- constructor overloads


def test_constructor_overloads_and_keywords():
    diff = crocopy.DifferentialActionModelLQR(2, 2)
    one = crocopy.ControlParametrizationModelPolyOne(2)
    Euler, RKModel = crocopy.IntegratedActionModelEuler, crocopy.IntegratedActionModelRK
    for model, (control_type, dt, residual) in [
        (Euler(diff), (crocopy.ControlParametrizationModelPolyZero, 1e-3, True)),
        (Euler(diff, 0.1, False), (crocopy.ControlParametrizationModelPolyZero, 0.1, False)),
        (Euler(diff, one, 0.1), (crocopy.ControlParametrizationModelPolyOne, 0.1, True)),
        (Euler(diff, control=one, timeStep=0.2, withCostResidual=False), (type(one), 0.2, False)),
        (Euler(diff, one, stepTime=0.3), (type(one), 0.3, True)),
        (Euler(diff, timeStep=0.4), (crocopy.ControlParametrizationModelPolyZero, 0.4, True)),
        (RKModel(diff, RK.four, 0.1, False), (crocopy.ControlParametrizationModelPolyZero, 0.1, False)),
        (RKModel(diff, one, RK.three, 0.2), (type(one), 0.2, True)),
        (RKModel(diff, rktype=RK.two, timeStep=0.3), (crocopy.ControlParametrizationModelPolyZero, 0.3, True)),
        (RKModel(diff, control=one, rktype=RK.four, stepTime=0.4), (type(one), 0.4, True)),
    ]:
        assert type(model.control) is control_type
        assert model.dt == dt and model.withCostResidual is residual
        assert model.nu == model.control.nu
    assert RKModel(diff, one, RK.three, 0.2).ni == 3


def test_bad_integrator_arguments_raise_clear_errors():
    diff = crocopy.DifferentialActionModelLQR(2, 2)
    Euler, RKModel = crocopy.IntegratedActionModelEuler, crocopy.IntegratedActionModelRK
    with pytest.raises(ValueError, match=r"control.nw \(3\) must equal diffModel.nu \(2\)"):
        Euler(diff, crocopy.ControlParametrizationModelPolyOne(3))
    with pytest.raises(TypeError, match="control must be a ControlParametrizationModelAbstract, got str"):
        Euler(diff, control="poly1")
    with pytest.raises(TypeError, match="timeStep must be a real number, got str"):
        Euler(diff, "0.1")
    with pytest.raises(TypeError, match="takes at most 4 positional arguments"):
        Euler(diff, crocopy.ControlParametrizationModelPolyZero(2), 0.1, True, 1)
    with pytest.raises(TypeError, match="unexpected keyword argument 'dt'"):
        Euler(diff, dt=0.1)
    with pytest.raises(TypeError, match="multiple values for argument 'timeStep'"):
        Euler(diff, 0.1, timeStep=0.2)
    with pytest.raises(TypeError, match="missing required argument 'rktype'"):
        RKModel(diff, crocopy.ControlParametrizationModelPolyZero(2))
    with pytest.raises(ValueError, match="rktype must be RKType.two, three or four"):
        RKModel(diff, crocopy.ControlParametrizationModelPolyZero(2), 5)
    with pytest.raises(ValueError, match="timeStep must be >= 0.0, got -1.0"):
        RKModel(diff, RK.four, -1.0)
