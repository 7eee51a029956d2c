"""Property tests of the core models (issue 14): states, activations, residuals, costs, action models and
integrators answer every drawn argument with a clear error or a finite, shape-correct result, in any
call order, and their derivatives still match numerical differentiation on valid random inputs."""

from __future__ import annotations

import numpy as np
import pytest
from fuzz_inputs import (
    CONTROL_KINDS,
    FUZZ,
    Arg,
    assert_finite,
    assert_matches_numdiff,
    calls_in_drawn_order,
    finite_values,
    outcome,
    vector_arg,
)
from hypothesis import given
from hypothesis import strategies as st

import crocopy


def _cost_sum(nx: int, nu: int) -> crocopy.CostModelSum:
    state = crocopy.StateVector(nx)
    costs = crocopy.CostModelSum(state, nu)
    costs.addCost("x", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, np.ones(nx), nu)), 2.0)
    costs.addCost("u", crocopy.CostModelResidual(
        state, crocopy.ActivationModelSmooth1Norm(nu, 0.1), crocopy.ResidualModelControl(state, nu)), 0.5)
    return costs


def _differential(nq: int = 2, nu: int = 2) -> crocopy.DifferentialActionModelLQR:
    return crocopy.DifferentialActionModelLQR.Random(nq, nu)


ACTIONS = {
    "unicycle": crocopy.ActionModelUnicycle,
    "lqr": lambda: crocopy.ActionModelLQR.Random(3, 2),
    "lqr-constrained": lambda: crocopy.ActionModelLQR.Random(3, 2, 2, 1),
    "euler": lambda: crocopy.IntegratedActionModelEuler(_differential(), 0.05),
    "rk4": lambda: crocopy.IntegratedActionModelRK(_differential(), crocopy.RKType.four, 0.05),
    "rk3-poly-one": lambda: crocopy.IntegratedActionModelRK(
        _differential(), crocopy.ControlParametrizationModelPolyOne(2), crocopy.RKType.three, 0.05),
    "diff-lqr": _differential,
}

ACTIVATIONS = {
    "quad": lambda n: crocopy.ActivationModelQuad(n),
    "weighted": lambda n: crocopy.ActivationModelWeightedQuad(np.linspace(0.5, 2.0, n)),
    "smooth1": lambda n: crocopy.ActivationModelSmooth1Norm(n, 0.1),
    "smooth2": lambda n: crocopy.ActivationModelSmooth2Norm(n, 0.1),
    "flatlog": lambda n: crocopy.ActivationModelQuadFlatLog(n, 0.3),
    "barrier": lambda n: crocopy.ActivationModelQuadraticBarrier(crocopy.ActivationBounds(-np.ones(n), np.ones(n))),
    "norm-barrier": lambda n: crocopy.ActivationModel2NormBarrier(n, 0.5),
}


def _action_shapes(model) -> dict:
    out = {"cost": ()}
    if hasattr(model, "differential") or not isinstance(model, crocopy.DifferentialActionModelAbstract):
        out["xnext"] = (model.state.nx,)
    return out


def _diff_shapes(model) -> dict:
    ndx, nu = model.state.ndx, model.nu
    nf = model.state.nv if isinstance(model, crocopy.DifferentialActionModelAbstract) else ndx
    return {"Fx": (nf, ndx), "Fu": (nf, nu), "Lx": (ndx,), "Lu": (nu,), "Lxx": (ndx, ndx), "Luu": (nu, nu)}


@FUZZ
@given(name=st.sampled_from(sorted(ACTIONS)), data=st.data())
def test_action_models_give_a_clear_error_or_a_finite_result(name, data):
    model = ACTIONS[name]()
    d = model.createData()
    x = data.draw(vector_arg("x", model.state.nx))
    terminal = data.draw(st.booleans())
    u = None if terminal else data.draw(vector_arg("u", model.nu, kinds=CONTROL_KINDS if model.nu else None))
    args = [x] if terminal else [x, u]
    calls_in_drawn_order(data, model, d, args, lambda m: _action_shapes(model) if m == "calc" else _diff_shapes(model))


@FUZZ
@given(name=st.sampled_from(sorted(ACTIONS)), data=st.data())
def test_action_model_derivatives_match_numdiff(name, data):
    model = ACTIONS[name]()
    x = data.draw(finite_values(model.state.nx, 1.0))
    u = data.draw(finite_values(model.nu, 1.0))
    assert_matches_numdiff(model, x, u, 1e-5)


@FUZZ
@given(nx=st.integers(0, 6), data=st.data())
def test_state_vector_operations(nx, data):
    state = crocopy.StateVector(nx)
    a = data.draw(vector_arg("x0", nx))
    b = data.draw(vector_arg("x1", nx))
    out = {}

    def diff():
        out["r"] = state.diff(a.value, b.value)

    def check_diff():
        np.testing.assert_array_equal(out["r"], b.array - a.array)

    outcome(diff, [a, b], check_diff)
    x = data.draw(vector_arg("x", nx))
    dx = data.draw(vector_arg("dx", nx))

    def jintegrate():
        out["J"] = state.Jintegrate(x.value, dx.value, crocopy.Jcomponent.both)

    outcome(jintegrate, [x, dx], lambda: [np.testing.assert_array_equal(J, np.eye(nx)) for J in out["J"]])


@FUZZ
@given(name=st.sampled_from(sorted(ACTIVATIONS)), nr=st.integers(1, 5), data=st.data())
def test_activations(name, nr, data):
    act = ACTIVATIONS[name](nr)
    ad = act.createData()
    r = data.draw(vector_arg("r", nr))
    outcome(lambda: act.calc(ad, r.value), [r], lambda: assert_finite(ad, {"a_value": ()}))
    outcome(lambda: act.calcDiff(ad, r.value), [r], lambda: assert_finite(ad, {"Ar": (nr,), "Arr": (nr, nr)}))


@FUZZ
@given(data=st.data())
def test_residuals_costs_and_cost_sums(data):
    nx, nu = 4, 2
    state = crocopy.StateVector(nx)
    collector = crocopy.DataCollectorAbstract()
    models = [
        crocopy.ResidualModelState(state, np.ones(nx), nu),
        crocopy.ResidualModelControl(state, np.ones(nu)),
        crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, np.zeros(nx), nu)),
        _cost_sum(nx, nu),
    ]
    model = data.draw(st.sampled_from(models))
    md = model.createData(collector)
    x = data.draw(vector_arg("x", nx))
    u = data.draw(vector_arg("u", nu, kinds=CONTROL_KINDS))
    if hasattr(model, "activation") or isinstance(model, crocopy.CostModelSum):
        shapes = {"cost": (), "Lx": (nx,), "Lu": (nu,), "Lxx": (nx, nx), "Luu": (nu, nu)}
    else:
        shapes = {"r": (model.nr,), "Rx": (model.nr, nx), "Ru": (model.nr, nu)}
    outcome(lambda: (model.calc(md, x.value, u.value), model.calcDiff(md, x.value, u.value)), [x, u],
            lambda: assert_finite(md, shapes))


@FUZZ
@given(data=st.data())
def test_references_and_setters(data):
    state = crocopy.StateVector(3)
    residual = crocopy.ResidualModelState(state, np.zeros(3), 2)
    ref = data.draw(vector_arg("xref", 3))

    def set_reference():
        residual.reference = ref.value

    outcome(set_reference, [ref], lambda: np.testing.assert_array_equal(residual.reference, ref.array))
    model = crocopy.ActionModelUnicycle()
    dt = data.draw(st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=2), st.none()))
    valid = isinstance(dt, float) and np.isfinite(dt) and dt >= 0.0

    def set_dt():
        model.dt = dt

    outcome(set_dt, [Arg("dt", "dt", dt, np.array(dt) if valid else None)], lambda: None)
    costs = _cost_sum(3, 2)
    weight = data.draw(st.one_of(st.floats(), st.booleans(), st.none()))
    valid = isinstance(weight, float) and np.isfinite(weight)

    def set_weight():
        costs.costs["x"].weight = weight

    outcome(set_weight, [Arg("weight", "w", weight, np.array(weight) if valid else None)], lambda: None)


@FUZZ
@given(data=st.data())
def test_control_bounds_in_any_order_then_a_box_solve(data):
    model = crocopy.ActionModelUnicycle()
    problem = crocopy.ShootingProblem(np.array([-1.0, -1.0, 1.0]), [model] * 5, model)
    for name in data.draw(st.permutations(["u_lb", "u_ub"])):
        arg = data.draw(vector_arg(name, 2, kinds=("ok", "list", "column", "nan", "short", "string")))
        if arg.kind in ("nan", "short", "string"):
            with pytest.raises((ValueError, TypeError), match=name):
                setattr(model, name, arg.value)
        else:
            setattr(model, name, arg.value)
            np.testing.assert_array_equal(getattr(model, name), arg.array)
    lb = model.u_lb
    ub = model.u_ub
    if np.any(lb > ub):
        with pytest.raises(ValueError, match="u_lb"):
            crocopy.SolverBoxFDDP(problem).solve(maxiter=5)
        return
    solver = crocopy.SolverBoxFDDP(problem)
    converged = solver.solve(maxiter=30)
    assert all(np.all(np.isfinite(x)) for x in solver.xs) and np.isfinite(solver.cost)
    if converged:  # the warm start (zero controls) may lie outside the box until a step is accepted
        assert all(np.all(u >= lb - 1e-9) and np.all(u <= ub + 1e-9) for u in solver.us)


BOUND_ENTRY = st.one_of(st.floats(-3.0, 3.0), st.sampled_from([-np.inf, np.inf]))


@FUZZ
@given(lb=st.lists(BOUND_ENTRY, min_size=3, max_size=3), ub=st.lists(BOUND_ENTRY, min_size=3, max_size=3))
def test_bounds_refuse_impossible_values(lb, ub):
    lb, ub = np.array(lb), np.array(ub)
    impossible = np.any(lb == np.inf) or np.any(ub == -np.inf)
    if impossible or np.any(lb > ub):
        with pytest.raises(ValueError, match=r"\b(lb|ub)\b"):
            crocopy.ActivationBounds(lb, ub)
    else:
        bounds = crocopy.ActivationBounds(lb, ub)
        np.testing.assert_array_equal(bounds.lb, lb)
    model = crocopy.ActionModelLQR.Random(2, 3)
    for name, value, bad in (("u_lb", lb, np.any(lb == np.inf)), ("u_ub", ub, np.any(ub == -np.inf))):
        if bad:
            with pytest.raises(ValueError, match=rf"{name}\[\d\] = .*admits no value"):
                setattr(model, name, value)
        else:
            setattr(model, name, value)
            np.testing.assert_array_equal(getattr(model, name), value)


KEYS = st.one_of(st.sampled_from(["x", "u", "nope"]), st.integers(-2, 2), st.floats(allow_nan=False), st.booleans(),
                 st.none(), st.binary(max_size=2), st.tuples(st.text(max_size=1)))


@FUZZ
@given(key=KEYS, active=st.one_of(st.booleans(), st.sampled_from([0, 1, 2, 0.5, "yes", None])))
def test_cost_names_must_be_strings_and_flags_bools(key, active):
    costs = _cost_sum(3, 2)
    valid_flag = isinstance(active, bool) or (isinstance(active, int) and active in (0, 1))
    if not isinstance(key, str):
        with pytest.raises(TypeError, match=r"\bname must be a str"):
            costs.changeCostStatus(key, True)
    elif key not in costs.costs:
        with pytest.raises(KeyError, match=repr(key)):
            costs.changeCostStatus(key, True)
    elif not valid_flag:
        with pytest.raises(TypeError, match=r"\bactive must be a bool"):
            costs.changeCostStatus(key, active)
    else:
        costs.changeCostStatus(key, active)
        assert (key in costs.active_set) == bool(active)
