"""Activations, residuals and cost sums against finite differences; cost-sum bookkeeping."""

import numpy as np
import pytest

import crocopy

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
