"""Activations, residuals and cost sums against finite differences; cost-sum bookkeeping."""

import warnings

import numpy as np
import pytest

import crocopy
from crocopy.validation import NonFiniteWarning

ACTIVATIONS = {
    "quad": lambda: crocopy.ActivationModelQuad(4),
    "wquad": lambda: crocopy.ActivationModelWeightedQuad(np.array([1.0, 2.0, 3.0, 4.0])),
    "barrier": lambda: crocopy.ActivationModelQuadraticBarrier(
        crocopy.ActivationBounds(-0.5 * np.ones(4), 0.5 * np.ones(4))
    ),
    "wbarrier": lambda: crocopy.ActivationModelWeightedQuadraticBarrier(
        crocopy.ActivationBounds(-0.5 * np.ones(4), 0.5 * np.ones(4), 0.8), np.array([1.0, 2.0, 3.0, 4.0])
    ),
    "smooth1": lambda: crocopy.ActivationModelSmooth1Norm(4, 0.1),
    "smooth2": lambda: crocopy.ActivationModelSmooth2Norm(4, 0.1),
    "2normbarrier": lambda: crocopy.ActivationModel2NormBarrier(4, 2.0, True),
}


def _fd_grad(f, r, h=1e-6):
    g = np.zeros_like(r)
    for i in range(r.size):
        e = np.zeros_like(r)
        e[i] = h
        g[i] = (f(r + e) - f(r - e)) / (2 * h)
    return g


@pytest.mark.parametrize("name", sorted(ACTIVATIONS))
def test_activation_derivatives(name):
    model = ACTIVATIONS[name]()
    data = model.createData()
    r = np.array([0.9, -0.7, 0.2, 0.3])

    def value(z):
        model.calc(data, z)
        return data.a_value

    def grad(z):
        model.calcDiff(data, z)
        return data.Ar.copy()

    model.calc(data, r)
    model.calcDiff(data, r)
    np.testing.assert_allclose(data.Ar, _fd_grad(value, r), atol=1e-7)
    hess = np.column_stack([_fd_grad(lambda z, i=i: grad(z)[i], r) for i in range(r.size)])
    model.calcDiff(data, r)
    np.testing.assert_allclose(data.Arr, hess.T, atol=1e-6)


def test_activation_bounds_reject_inverted_and_shrink_with_beta():
    with pytest.raises(ValueError, match="lb"):
        crocopy.ActivationBounds(np.array([1.0]), np.array([0.0]))
    b = crocopy.ActivationBounds(np.array([-1.0, -np.inf]), np.array([3.0, np.inf]), 0.5)
    np.testing.assert_allclose(b.lb[0], 0.0)
    np.testing.assert_allclose(b.ub[0], 2.0)
    assert np.isinf(b.lb[1]) and np.isinf(b.ub[1])


def _cost_sum(state, nu):
    costs = crocopy.CostModelSum(state, nu)
    xref = state.rand()
    costs.addCost("x", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, xref, nu)), 2.0)
    costs.addCost(
        "u",
        crocopy.CostModelResidual(
            state, crocopy.ActivationModelSmooth1Norm(nu, 0.5), crocopy.ResidualModelControl(state, np.ones(nu))
        ),
        0.5,
    )
    costs.addCost(
        "xb",
        crocopy.CostModelResidual(
            state,
            crocopy.ActivationModelQuadraticBarrier(
                crocopy.ActivationBounds(-0.1 * np.ones(state.ndx), 0.1 * np.ones(state.ndx))
            ),
            crocopy.ResidualModelState(state, nu),
        ),
        3.0,
    )
    return costs


def test_cost_sum_derivatives_and_bookkeeping():
    state, nu = crocopy.StateVector(4), 2
    costs = _cost_sum(state, nu)
    assert costs.nr == 4 + 2 + 4 and costs.active_set == {"x", "u", "xb"}
    data = costs.createData(crocopy.DataCollectorAbstract())
    x, u = np.array([0.3, -0.5, 0.2, 0.05]), np.array([0.4, -1.2])

    def cost(z):
        costs.calc(data, z[:4], z[4:])
        return data.cost

    costs.calc(data, x, u)
    costs.calcDiff(data, x, u)
    g = _fd_grad(cost, np.concatenate([x, u]))
    np.testing.assert_allclose(data.Lx, g[:4], atol=1e-7)
    np.testing.assert_allclose(data.Lu, g[4:], atol=1e-7)
    costs.changeCostStatus("u", False)
    assert costs.inactive_set == {"u"} and costs.nr == 8
    costs.calc(data, x, u)
    expected = 2.0 * data.costs["x"].cost + 3.0 * data.costs["xb"].cost
    assert data.cost == pytest.approx(expected)
    costs.removeCost("xb")
    assert set(costs.costs) == {"x", "u"}
    with pytest.raises(ValueError, match="already exists"):
        costs.addCost("x", costs.costs["x"].cost, 1.0)
    with pytest.raises(KeyError):
        costs.removeCost("nope")
    with pytest.raises(ValueError, match="nu"):
        costs.addCost("bad", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, 3)), 1.0)


def test_control_residual_is_zero_on_terminal_nodes():
    state = crocopy.StateVector(4)
    cost = crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, np.ones(2)))
    data = cost.createData(crocopy.DataCollectorAbstract())
    cost.calc(data, state.rand())
    assert data.cost == 0.0


def test_state_residual_reference_checks_shape():
    state = crocopy.StateVector(4)
    with pytest.raises(ValueError, match=r"xref has shape \(3,\), expected \(4,\)"):
        crocopy.ResidualModelState(state, np.zeros(3), 2)


def _every_activation_sum(state, nu, kinds=None):
    """One item per activation kind (4 rows each) on state and control residuals in turn, plus a control cost."""
    costs = crocopy.CostModelSum(state, nu)
    for k, name in enumerate(kinds or sorted(ACTIVATIONS)):
        if k % 2:
            residual = crocopy.ResidualModelControl(state, 0.2 * np.ones(nu))
        else:
            residual = crocopy.ResidualModelState(state, 0.1 * np.arange(4.0), nu)
        costs.addCost(name, crocopy.CostModelResidual(state, ACTIVATIONS[name](), residual), 0.5 + k)
    costs.addCost("u", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, nu)), 0.3)
    return costs


def _item_by_item(costs, data, x, u):
    """Weighted sums of every active item's own cost and derivatives (the definition)."""
    total, Lx, Lu = 0.0, np.zeros(costs.state.ndx), np.zeros(costs.nu)
    Lxx, Luu = np.zeros((costs.state.ndx,) * 2), np.zeros((costs.nu, costs.nu))
    for name, item in costs.costs.items():
        if not item.active:
            continue
        cd = data.costs[name]
        total += item.weight * cd.cost
        Lx += item.weight * cd.Lx
        Lxx += item.weight * cd.Lxx
        if u is not None:
            Lu += item.weight * cd.Lu
            Luu += item.weight * cd.Luu
    return total, Lx, Lu, Lxx, Luu


@pytest.mark.parametrize("terminal", [False, True])
def test_stacked_cost_sum_equals_its_items_and_follows_parameter_changes(terminal):
    state, nu = crocopy.StateVector(4), 4
    costs = _every_activation_sum(state, nu)
    data = costs.createData(crocopy.DataCollectorAbstract())
    x, u = np.array([0.9, -0.7, 0.2, 0.3]), (None if terminal else np.array([0.4, -1.2, 0.0, 0.7]))

    def check():
        costs.calc(data, x, u)
        costs.calcDiff(data, x, u)
        fresh = costs.createData(crocopy.DataCollectorAbstract())
        costs.calc(fresh, x, u)
        costs.calcDiff(fresh, x, u)
        total, Lx, Lu, Lxx, Luu = _item_by_item(costs, data, x, u)
        assert data.cost == pytest.approx(total, rel=1e-12) and data.cost == pytest.approx(fresh.cost, rel=1e-12)
        np.testing.assert_allclose(data.Lx, Lx, atol=1e-12)
        np.testing.assert_allclose(data.Lxx, Lxx, atol=1e-12)
        np.testing.assert_allclose(data.Lxx, fresh.Lxx, atol=1e-12)
        if u is not None:
            np.testing.assert_allclose(data.Lu, Lu, atol=1e-12)
            np.testing.assert_allclose(data.Luu, Luu, atol=1e-12)
        return data.cost

    first = check()
    costs.costs["wquad"].cost.activation.weights = np.array([5.0, 1.0, 1.0, 1.0])
    costs.costs["barrier"].cost.activation.bounds = crocopy.ActivationBounds(-0.1 * np.ones(4), 0.1 * np.ones(4))
    costs.costs["wbarrier"].cost.activation.bounds.ub = 0.2 * np.ones(4)
    costs.costs["quad"].weight = 7.0
    costs.changeCostStatus("smooth1", False)
    assert check() != pytest.approx(first)
    with pytest.raises(ValueError):
        costs.costs["wquad"].cost.activation.weights[0] = 3.0


@pytest.mark.parametrize("terminal", [False, True])
def test_compiled_stack_steps_equal_the_numpy_steps(terminal):
    """The numba kernels of the stack give the numpy steps' cost, derivatives and activation rows."""
    assert crocopy.kernels.available
    state, nu = crocopy.StateVector(4), 4
    costs = _every_activation_sum(state, nu)
    costs.changeCostStatus("wquad", False)
    rng = np.random.default_rng(3)
    results = []
    for use_kernel in (True, False):
        data = costs.createData(crocopy.DataCollectorAbstract())
        out = []
        for _ in range(4):
            x = rng.uniform(-1.0, 1.0, 4)
            u = None if terminal else rng.uniform(-1.0, 1.0, nu)
            with crocopy.use_kernels(use_kernel):
                costs.calc(data, x, u)
                costs.calcDiff(data, x, u)
            out.append([data.cost, data.Lx, data.Lu, data.Lxx, data.Lxu, data.Luu, data.stack.Ar, data.stack.Arr])
            out[-1] = [np.array(a, copy=True) for a in out[-1]]
        rng = np.random.default_rng(3)
        results.append(out)
    assert any(np.any(step[7] == 0.0) for step in results[0]), "some barrier row must lie inside its bounds"
    for compiled, numpy_steps in zip(*results):
        for a, b in zip(compiled, numpy_steps):
            np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-13)


def test_stacked_cost_sum_reports_an_infinite_residual_without_warnings():
    state = crocopy.StateVector(4)
    costs = _every_activation_sum(state, 4, ("barrier", "quad", "wbarrier", "wquad"))
    data = costs.createData(crocopy.DataCollectorAbstract())

    with warnings.catch_warnings(record=True) as caught:  # no NumPy overflow warning, only crocopy's own
        warnings.simplefilter("always")
        costs.calc(data, np.array([1e300, 0.0, 0.0, 0.0]), np.zeros(4))
    assert [w.category for w in caught] == [NonFiniteWarning] and "CostModelSum: data.cost" in str(caught[0].message)
    assert data.cost == np.inf
    assert data.costs["barrier"].cost == np.inf
    assert all(np.isfinite(data.costs[name].cost) for name in ("quad", "u"))


@pytest.mark.parametrize("name", ["barrier", "wbarrier"])
def test_barrier_curvature_counts_rows_on_their_bound_alone_and_in_a_sum(name):
    """``Arr = w² [r ≤ lb or r ≥ ub]`` (Crocoddyl's convention on the bound): a row sitting on its bound is curved."""
    model = ACTIVATIONS[name]()
    lb, ub = model.bounds.lb, model.bounds.ub
    r = np.array([lb[0], ub[1], 0.5 * (lb[2] + ub[2]), ub[3] + 1.0])
    data = model.createData()
    model.calc(data, r)
    model.calcDiff(data, r)
    w = getattr(model, "weights", np.ones(4)) ** 2
    np.testing.assert_array_equal(data.Arr_diag, w * np.array([1.0, 1.0, 0.0, 1.0]))
    state = crocopy.StateVector(4)
    costs = crocopy.CostModelSum(state, 0)
    costs.addCost("b", crocopy.CostModelResidual(state, model, crocopy.ResidualModelState(state, np.zeros(4), 0)), 2.0)
    sdata = costs.createData(crocopy.DataCollectorAbstract())
    costs.calc(sdata, r, np.zeros(0))
    costs.calcDiff(sdata, r, np.zeros(0))
    np.testing.assert_allclose(np.diag(sdata.Lxx), 2.0 * w * np.array([1.0, 1.0, 0.0, 1.0]))


def test_cost_sum_of_unstacked_costs_only_restarts_its_sums_at_each_calcdiff():
    """A sum whose items all have dense activations (no stack) must not accumulate across calls."""
    state = crocopy.StateVector(4)
    costs = crocopy.CostModelSum(state, 2)
    act = crocopy.ActivationModelSmooth2Norm(4, 0.1)
    costs.addCost("n", crocopy.CostModelResidual(state, act, crocopy.ResidualModelState(state, np.zeros(4), 2)), 3.0)
    data = costs.createData(crocopy.DataCollectorAbstract())
    x, u = np.array([0.3, -0.5, 0.2, 0.05]), np.array([0.4, -1.2])
    for _ in range(2):
        costs.calc(data, x, u)
        costs.calcDiff(data, x, u)
    np.testing.assert_allclose(data.Lx, 3.0 * data.costs["n"].Lx, atol=1e-14)
    np.testing.assert_allclose(data.Lxx, 3.0 * data.costs["n"].Lxx, atol=1e-14)
