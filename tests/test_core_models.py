"""Every core model (× every integrator for differential models) against numerical differentiation."""

import numpy as np
import pytest

import crocopy

INTEGRATORS = {
    "euler": lambda dam: crocopy.IntegratedActionModelEuler(dam, 1e-2),
    "rk2": lambda dam: crocopy.IntegratedActionModelRK(dam, crocopy.RKType.two, 1e-2),
    "rk3": lambda dam: crocopy.IntegratedActionModelRK(dam, crocopy.RKType.three, 1e-2),
    "rk4": lambda dam: crocopy.IntegratedActionModelRK(dam, crocopy.RKType.four, 1e-2),
}


def _cost_dam(nq: int = 3, nu: int = 2) -> crocopy.DifferentialActionModelAbstract:
    """A differential LQR whose cost is replaced by a non-quadratic cost stack (exercises activations)."""
    return crocopy.DifferentialActionModelLQR.Random(nq, nu)


ACTION_MODELS = {
    "lqr": lambda: crocopy.ActionModelLQR.Random(5, 3),
    "lqr_constrained": lambda: crocopy.ActionModelLQR.Random(4, 2, 2, 1),
    "unicycle": crocopy.ActionModelUnicycle,
}
DAMS = {
    "dlqr": lambda: crocopy.DifferentialActionModelLQR.Random(3, 2),
    "dlqr_constrained": lambda: crocopy.DifferentialActionModelLQR.Random(2, 2, 1, 1),
}


def _check_action(model, terminal: bool, rng, hessians: bool = True) -> None:
    nd = crocopy.ActionModelNumDiff(model)
    d, dn = model.createData(), nd.createData()
    x = model.state.rand()
    u = None if terminal else rng.standard_normal(model.nu)
    model.calc(d, x, u)
    model.calcDiff(d, x, u)
    nd.calc(dn, x, u)
    nd.calcDiff(dn, x, u)
    assert d.cost == pytest.approx(dn.cost, rel=1e-12, abs=1e-12)
    np.testing.assert_allclose(d.Lx, dn.Lx, atol=1e-6, rtol=1e-6)
    np.testing.assert_allclose(d.g, dn.g, atol=1e-12)
    np.testing.assert_allclose(d.Gx, dn.Gx, atol=1e-6)
    np.testing.assert_allclose(d.Hx, dn.Hx, atol=1e-6)
    if hessians:
        np.testing.assert_allclose(d.Lxx, dn.Lxx, atol=1e-4, rtol=1e-4)
    if not terminal:
        np.testing.assert_allclose(d.xnext, dn.xnext, atol=1e-14)
        np.testing.assert_allclose(d.Fx, dn.Fx, atol=1e-6, rtol=1e-6)
        np.testing.assert_allclose(d.Fu, dn.Fu, atol=1e-6, rtol=1e-6)
        np.testing.assert_allclose(d.Lu, dn.Lu, atol=1e-6, rtol=1e-6)
        np.testing.assert_allclose(d.Gu, dn.Gu, atol=1e-6)
        np.testing.assert_allclose(d.Hu, dn.Hu, atol=1e-6)
        if hessians:
            np.testing.assert_allclose(d.Luu, dn.Luu, atol=1e-4, rtol=1e-4)
            np.testing.assert_allclose(d.Lxu, dn.Lxu, atol=1e-4, rtol=1e-4)


@pytest.mark.parametrize("terminal", [False, True])
@pytest.mark.parametrize("name", sorted(ACTION_MODELS))
def test_action_model_derivatives(name, terminal):
    _check_action(ACTION_MODELS[name](), terminal, np.random.default_rng(1))


@pytest.mark.parametrize("terminal", [False, True])
@pytest.mark.parametrize("integrator", sorted(INTEGRATORS))
@pytest.mark.parametrize("name", sorted(DAMS))
def test_integrated_model_derivatives(name, integrator, terminal):
    _check_action(INTEGRATORS[integrator](DAMS[name]()), terminal, np.random.default_rng(2))


@pytest.mark.parametrize("name", sorted(DAMS))
def test_differential_model_derivatives(name):
    model = DAMS[name]()
    nd = crocopy.DifferentialActionModelNumDiff(model)
    d, dn = model.createData(), nd.createData()
    x, u = model.state.rand(), np.random.default_rng(3).standard_normal(model.nu)
    model.calc(d, x, u)
    model.calcDiff(d, x, u)
    nd.calc(dn, x, u)
    nd.calcDiff(dn, x, u)
    for f in ("Fx", "Fu", "Lx", "Lu", "Gx", "Gu", "Hx", "Hu"):
        np.testing.assert_allclose(getattr(d, f), getattr(dn, f), atol=1e-6, rtol=1e-6, err_msg=f)
    for f in ("Lxx", "Lxu", "Luu"):
        np.testing.assert_allclose(getattr(d, f), getattr(dn, f), atol=1e-4, rtol=1e-4, err_msg=f)


def test_numdiff_gauss_approximation_is_jacobian_product():
    model = crocopy.ActionModelUnicycle()
    nd = crocopy.ActionModelNumDiff(model, with_gauss_approx=True)
    dn = nd.createData()
    x, u = model.state.rand(), np.array([0.3, -0.2])
    nd.calc(dn, x, u)
    nd.calcDiff(dn, x, u)
    np.testing.assert_allclose(dn.Lxx, dn.Rx.T @ dn.Rx, atol=1e-12)
    np.testing.assert_allclose(np.diag(dn.Lxx), [100.0, 100.0, 100.0], rtol=1e-6)


def test_integrators_reduce_to_exact_flow_for_small_steps():
    """RK4 matches the exact exponential flow of a linear DAM better than Euler."""
    from scipy.linalg import expm

    dam = crocopy.DifferentialActionModelLQR(2, 2)
    dt = 0.05
    A = np.block([[np.zeros((2, 2)), np.eye(2)], [dam.Aq, dam.Av]])
    x = np.array([0.1, -0.2, 0.3, 0.05])
    exact = expm(A * dt) @ x
    errors = {}
    for name in ("euler", "rk2", "rk3", "rk4"):
        m = INTEGRATORS[name](dam)
        m.dt = dt
        d = m.createData()
        m.calc(d, x, np.zeros(2))
        errors[name] = np.linalg.norm(d.xnext - exact)
    assert errors["rk4"] < errors["rk3"] < errors["rk2"] < errors["euler"]
    assert errors["rk4"] < 1e-7


def test_numdiff_on_lie_group_state_matches_analytic_free_dynamics():
    """ActionModelNumDiff differentiates in the tangent space (nx = 37 ≠ ndx = 36 for ANYmal)."""
    import example_robot_data

    model = example_robot_data.load("anymal").model
    state = crocopy.StateMultibody(model)
    actuation = crocopy.ActuationModelFloatingBase(state)
    costs = crocopy.CostModelSum(state, actuation.nu)
    costs.addCost("x", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, actuation.nu)), 1.0)
    dam = crocopy.DifferentialActionModelFreeFwdDynamics(state, actuation, costs)
    iam = crocopy.IntegratedActionModelEuler(dam, 1e-2)
    nd = crocopy.ActionModelNumDiff(iam, with_gauss_approx=True)
    d, dn = iam.createData(), nd.createData()
    rng = np.random.default_rng(0)
    x, u = state.rand(), rng.standard_normal(actuation.nu)
    iam.calc(d, x, u)
    iam.calcDiff(d, x, u)
    nd.calc(dn, x, u)
    nd.calcDiff(dn, x, u)
    assert dn.Fx.shape == (36, 36)
    scale = max(1.0, np.abs(d.Fx).max())
    np.testing.assert_allclose(d.Fx, dn.Fx, atol=1e-5 * scale)
    np.testing.assert_allclose(d.Fu, dn.Fu, atol=1e-5 * max(1.0, np.abs(d.Fu).max()))
    np.testing.assert_allclose(d.Lx, dn.Lx, atol=1e-5 * max(1.0, np.abs(d.Lx).max()))


@pytest.mark.parametrize("robot", ["dlqr", "anymal"])
def test_compiled_euler_chain_rule_equals_its_numpy_twin(robot):
    """Euler's compiled step and chain rule give the numpy twins' xnext, Fx, Fu and cost derivatives."""
    from crocopy.integrators import euler_kernel as integrator_kernel

    assert crocopy.kernels.available
    if robot == "dlqr":
        dam = crocopy.DifferentialActionModelLQR.Random(3, 2)
    else:
        import example_robot_data

        state = crocopy.StateMultibody(example_robot_data.load("anymal").model)
        actuation = crocopy.ActuationModelFloatingBase(state)
        costs = crocopy.CostModelSum(state, actuation.nu)
        costs.addCost("x", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, actuation.nu)), 1.0)
        costs.addCost("u", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, actuation.nu)), 0.1)
        dam = crocopy.DifferentialActionModelFreeFwdDynamics(state, actuation, costs)
    rng = np.random.default_rng(1)
    x, u = dam.state.rand(), rng.standard_normal(dam.nu)
    outputs = []
    for use_kernel in (True, False):
        iam = crocopy.IntegratedActionModelEuler(dam, 2e-2)
        d = iam.createData()
        with crocopy.use_kernels(use_kernel):
            iam.calc(d, x, u)
            iam.calcDiff(d, x, u)
        outputs.append([d.xnext, d.Fx, d.Fu, d.Lx, d.Lu, d.Lxx, d.Lxu, d.Luu])
    for compiled, numpy_twin in zip(*outputs):
        np.testing.assert_allclose(compiled, numpy_twin, rtol=1e-13, atol=1e-14)
    nv, ndx, nu = 4, 8, 3
    rows, Jq = np.asfortranarray(rng.standard_normal((nv, ndx + nu))), rng.standard_normal((nv, nv))
    F0 = rng.standard_normal((ndx, ndx)), rng.standard_normal((ndx, nu))
    results = []
    for add in (integrator_kernel.add_integrate_jacobian, integrator_kernel.add_integrate_jacobian_numpy):
        Fx, Fu = F0[0].copy(), F0[1].copy()
        add(rows, Jq, Fx, Fu)
        results.append((Fx, Fu))
    np.testing.assert_array_equal(results[0][0], results[1][0])
    np.testing.assert_array_equal(results[0][1], results[1][1])
    assert not np.array_equal(results[0][0], F0[0])


@pytest.mark.parametrize("integrator", sorted(INTEGRATORS))
def test_integrated_quasi_static_gives_zero_acceleration(integrator):
    dam = crocopy.DifferentialActionModelLQR(2, 2)
    iam = INTEGRATORS[integrator](dam)
    x = np.array([0.3, -0.2, 0.0, 0.0])
    u = iam.quasiStatic(iam.createData(), x)
    dd = dam.createData()
    dam.calc(dd, x, u)
    np.testing.assert_allclose(dd.xout, 0.0, atol=1e-9)
