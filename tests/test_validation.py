"""Validation at the public boundary (issue 14): the reproducers, the setters and the trusted path of a solve."""

from __future__ import annotations

import functools
import inspect
import pickle
import re
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import crocopy
from crocopy import guards
from crocopy.validation import ArgumentTypeError, NonFiniteWarning


def unicycle_problem(T: int = 5) -> crocopy.ShootingProblem:
    m = crocopy.ActionModelUnicycle()
    return crocopy.ShootingProblem(np.array([-1.0, -1.0, 1.0]), [m] * T, m)


# ---------------------------------------------------------------- reproducer 3: ShootingProblem arguments
@pytest.mark.parametrize("method", ["calc", "calcDiff"])
def test_problem_rejects_wrong_trajectory_lengths_and_none(method):
    p = unicycle_problem()
    call = getattr(p, method)
    with pytest.raises(ValueError, match=r"us has 0 items, expected T = 5"):
        call([np.ones(3)] * 6, [])
    with pytest.raises(ValueError, match=r"xs has 5 items, expected T \+ 1 = 6"):
        call([np.ones(3)] * 5, [np.zeros(2)] * 5)
    with pytest.raises(TypeError, match=r"us\[0\] must be a vector of shape \(2,\), got None"):
        call([np.ones(3)] * 6, [None] * 5)
    with pytest.raises(TypeError, match="us must be a list of vectors, got NoneType"):
        call([np.ones(3)] * 6, None)


def test_problem_rollout_and_quasi_static_check_their_arguments():
    p = unicycle_problem()
    with pytest.raises(ValueError, match=r"us has 4 items, expected T = 5"):
        p.rollout([np.zeros(2)] * 4)
    with pytest.raises(ValueError, match=r"us\[1\] has shape \(3,\), expected \(2,\)"):
        p.rollout([np.zeros(2), np.zeros(3), *[np.zeros(2)] * 3])
    with pytest.raises(ValueError, match=r"xs\[2\] contains NaN"):
        p.quasiStatic([np.zeros(3), np.zeros(3), np.full(3, np.nan), np.zeros(3), np.zeros(3)])
    xs = p.rollout([[1.0, 0.5]] * 5)  # plain lists are converted
    assert len(xs) == 6 and all(x.shape == (3,) for x in xs)


def test_problem_calc_accepts_lists_and_columns_with_the_same_result():
    p = unicycle_problem()
    xs = [np.array([0.1 * t, -0.2, 0.3]) for t in range(6)]
    us = [np.array([0.5, -0.1 * t]) for t in range(5)]
    expected = p.calc(xs, us)
    assert p.calc([x.tolist() for x in xs], [u.reshape(2, 1) for u in us]) == expected
    assert p.calcDiff(xs, us) == expected


# ---------------------------------------------------------------- reproducer 4: cost added after createData
def test_cost_added_after_create_data_raises():
    state = crocopy.StateVector(4)
    costs = crocopy.CostModelSum(state, 2)
    costs.addCost("u", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, 2)), 1.0)
    data = costs.createData(crocopy.DataCollectorAbstract())
    costs.addCost("x", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, np.ones(4), 2)), 1.0)
    with pytest.raises(ValueError, match="a cost was added or removed after createData"):
        costs.calc(data, np.zeros(4), np.zeros(2))
    with guards.unchecked():  # the check is in calc itself, so a solve meets it too
        with pytest.raises(ValueError, match="a cost was added or removed after createData"):
            costs.calc(data, np.zeros(4), np.zeros(2))
    fresh = costs.createData(crocopy.DataCollectorAbstract())
    costs.calc(fresh, np.zeros(4), np.zeros(2))
    assert fresh.cost == pytest.approx(0.5 * 4.0)


def test_cost_swapped_after_create_data_raises_and_copies_keep_their_pairing():
    """Removing one cost and adding another keeps the count but not the names: still refused. A model
    copied or pickled with its data stays a valid pair; a copy's change is seen by the copy's data."""
    state = crocopy.StateVector(4)
    costs = crocopy.CostModelSum(state, 2)
    costs.addCost("u", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, 2)), 1.0)
    data = costs.createData(crocopy.DataCollectorAbstract())
    costs.calc(data, np.zeros(4), np.ones(2))
    pair = pickle.loads(pickle.dumps((costs, data)))
    costs.removeCost("u")
    costs.addCost("x", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, np.ones(4), 2)), 1.0)
    with guards.unchecked(), pytest.raises(ValueError, match=r"data holds cost datas \['u'\] but the model has"):
        costs.calc(data, np.zeros(4), np.zeros(2))
    copied, copied_data = pair
    copied.calc(copied_data, np.zeros(4), np.ones(2))
    assert copied_data.cost == pytest.approx(1.0)
    copied.addCost("x", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, np.ones(4), 2)), 1.0)
    with pytest.raises(ValueError, match="a cost was added or removed after createData"):
        copied.calc(copied_data, np.zeros(4), np.ones(2))


# ---------------------------------------------------------------- reproducers 5 and 6: shapes, columns, lists
def test_state_operations_take_columns_and_refuse_other_shapes():
    s = crocopy.StateVector(3)
    np.testing.assert_array_equal(s.integrate(np.zeros(3), np.ones((3, 1))), np.ones(3))
    np.testing.assert_array_equal(s.diff([0.0, 0.0, 0.0], np.ones((1, 3))), np.ones(3))
    with pytest.raises(ValueError, match=r"dx has shape \(3, 3\), expected \(3,\)"):
        s.integrate(np.zeros(3), np.ones((3, 3)))
    with pytest.raises(ValueError, match=r"x1 has shape \(2,\), expected \(3,\)"):
        s.Jdiff(np.zeros(3), np.zeros(2))
    with pytest.raises(ValueError, match="firstsecond must be Jcomponent"):
        s.Jintegrate(np.zeros(3), np.zeros(3), 7)
    with pytest.raises(TypeError, match="Jin must be a float64 numpy array"):
        s.JintegrateTransport(np.zeros(3), np.zeros(3), [[1.0]] * 3, crocopy.Jcomponent.first)


def test_action_calc_takes_lists_and_columns_and_refuses_scalars():
    m = crocopy.ActionModelUnicycle()
    d, d_ref = m.createData(), m.createData()
    x, u = np.array([0.3, -0.2, 0.5]), np.array([1.0, -0.4])
    m.calc(d_ref, x, u)
    m.calc(d, x.tolist(), u.reshape(2, 1))
    assert d.cost == d_ref.cost
    np.testing.assert_array_equal(d.xnext, d_ref.xnext)
    with pytest.raises(ValueError, match=r"x has shape \(\), expected \(3,\)"):
        m.calc(d, 1.0)
    with pytest.raises(ValueError, match=r"u has shape \(3,\), expected \(2,\)"):
        m.calcDiff(d, x, np.zeros(3))


def test_action_calc_refuses_the_data_of_another_model():
    m = crocopy.ActionModelUnicycle()
    other = crocopy.ActionModelLQR(3, 1).createData()
    with pytest.raises(ValueError, match=r"data was not created by this ActionModelUnicycle: data.Lu has shape"):
        m.calc(other, np.zeros(3), np.zeros(2))


# ---------------------------------------------------------------- reproducer 7: setters
def test_setters_validate():
    m = crocopy.ActionModelUnicycle()
    with pytest.raises(ValueError, match=r"dt must be >= 0.0, got -0.1"):
        m.dt = -0.1
    with pytest.raises(ValueError, match="costWeights contains NaN"):
        m.costWeights = [np.nan, 1.0]
    integrated = crocopy.IntegratedActionModelEuler(crocopy.DifferentialActionModelLQR(2, 1), 0.1)
    with pytest.raises(ValueError, match="timeStep"):
        integrated.dt = np.inf
    state = crocopy.StateVector(2)
    costs = crocopy.CostModelSum(state, 1)
    costs.addCost("u", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, 1)), 1.0)
    with pytest.raises(ValueError, match="weight of cost 'u' must be a finite number, got nan"):
        costs.costs["u"].weight = np.nan
    with pytest.raises(TypeError, match="active must be a bool"):
        costs.costs["u"].active = "yes"
    solver = crocopy.SolverFDDP(unicycle_problem())
    with pytest.raises(ValueError, match=r"reg_min must be >= 0.0, got -1.0"):
        solver.reg_min = -1
    with pytest.raises(ValueError, match="th_stop must be a finite number"):
        solver.th_stop = np.nan
    solver.reg_min = 10.0
    solver.reg_max = 1.0
    with pytest.raises(ValueError, match=r"reg_min = 10.0 is above reg_max = 1.0"):
        solver.solve()


def test_control_bounds_may_be_set_in_either_order():
    m = crocopy.ActionModelUnicycle()
    m.u_ub = np.array([-2.0, -2.0])  # below the current (default) u_lb? no: the default is -inf
    m.u_lb = np.array([-1.0, -1.0])  # now u_lb > u_ub: allowed until the pair is used
    m.u_ub = np.array([1.0, 1.0])
    assert m.has_control_limits
    np.testing.assert_array_equal(m.u_lb, -1.0)
    problem = crocopy.ShootingProblem(np.zeros(3), [m] * 3, m)
    assert crocopy.SolverBoxFDDP(problem).solve(maxiter=5) in (True, False)
    m.u_ub = np.array([-2.0, 1.0])
    for Solver in (crocopy.SolverFDDP, crocopy.SolverBoxFDDP):
        with pytest.raises(ValueError, match=r"u_lb\[0\] = -1.0 is above runningModels\[0\].u_ub\[0\] = -2.0"):
            Solver(problem).solve()


# ---------------------------------------------------------------- reproducer 8: indefinite LQR
def test_lqr_with_an_indefinite_cost_hessian_is_rejected():
    with pytest.raises(ValueError, match=r"positive semi-definite, got smallest eigenvalue -1"):
        crocopy.ActionModelLQR(np.eye(3), np.eye(3, 1), -np.eye(3), np.eye(1), np.zeros((3, 1)))
    with pytest.raises(ValueError, match="positive semi-definite"):
        crocopy.DifferentialActionModelLQR(
            np.eye(1), np.eye(1), np.ones((1, 1)), np.eye(2), np.eye(1), 3.0 * np.ones((2, 1))
        )
    with pytest.raises(ValueError, match="Q must be symmetric"):
        crocopy.ActionModelLQR(np.eye(2), np.eye(2, 1), np.array([[1.0, 1.0], [0.0, 1.0]]), np.eye(1),
                               np.zeros((2, 1)))
    crocopy.ActionModelLQR(np.eye(2), np.eye(2, 1), np.zeros((2, 2)), np.eye(1), np.zeros((2, 1)))  # PSD is fine


# ---------------------------------------------------------------- reproducer 10: silently accepted
def test_solve_arguments_and_x0_types_are_checked():
    p = unicycle_problem()
    solver = crocopy.SolverFDDP(p)
    with pytest.raises(ValueError, match="maxiter must be non-negative, got -5"):
        solver.solve(None, None, -5)
    with pytest.raises(TypeError, match="maxiter must be an integer, got float"):
        solver.solve(None, None, 2.5)
    with pytest.raises(TypeError, match="is_feasible must be a bool, got str 'yes'"):
        solver.solve(None, None, 10, "yes")
    with pytest.raises(ValueError, match=r"init_reg must be >= 0.0, got -1.0"):
        solver.solve(None, None, 10, False, -1.0)
    assert solver.solve(None, None, 10, False, float("nan")) in (True, False)  # NaN: the default, as Crocoddyl
    with pytest.raises(TypeError, match="x0 must be a vector of shape \\(3,\\) of real numbers, got dtype complex"):
        p.x0 = np.array([1.0 + 1j, 0.0, 0.0])
    with pytest.raises(TypeError, match="dtype <U1"):
        p.x0 = ["1", "2", "3"]
    with pytest.raises(TypeError, match="dtype bool"):
        p.x0 = [True, False, True]


# ---------------------------------------------------------------- reproducer 11: NaN/inf and overflow
def test_nonfinite_inputs_raise_and_overflow_warns():
    m = crocopy.ActionModelUnicycle()
    d = m.createData()
    with pytest.raises(ValueError, match=r"x contains NaN or inf \(x\[1\] = nan\)"):
        m.calc(d, np.array([0.0, np.nan, 0.0]), np.zeros(2))
    with pytest.raises(ValueError, match=r"u contains NaN or inf \(u\[0\] = inf\)"):
        m.calcDiff(d, np.zeros(3), np.array([np.inf, 0.0]))
    with pytest.warns(NonFiniteWarning, match="ActionModelUnicycle: data.cost is not finite"):
        with np.errstate(over="ignore"):
            m.calc(d, np.full(3, 1e300), np.zeros(2))
    act = crocopy.ActivationModelQuad(3)
    with pytest.raises(ValueError, match=r"r contains NaN"):
        act.calc(act.createData(), np.array([0.0, np.nan, 1.0]))
    state = crocopy.StateVector(3)
    residual = crocopy.ResidualModelState(state, np.zeros(3), 2)
    with pytest.raises(ValueError, match="xref contains NaN"):
        residual.reference = np.array([np.nan, 0.0, 0.0])
    with pytest.raises(ValueError, match="x contains NaN"):
        residual.calc(residual.createData(crocopy.DataCollectorAbstract()), np.full(3, np.nan), np.zeros(2))
    for eps in (-0.0, 0.0, 1e-300, np.nan):
        with pytest.raises(ValueError, match="eps must be"):
            crocopy.ActivationModelSmooth1Norm(3, eps)
        with pytest.raises(ValueError, match="eps must be"):
            crocopy.ActivationModelSmooth2Norm(3, eps)
    smooth = crocopy.ActivationModelSmooth2Norm(3, crocopy.activations.norms.EPS_MIN)
    sd = smooth.createData()
    smooth.calcDiff(sd, np.zeros(3))
    assert np.all(np.isfinite(sd.Arr))


# ---------------------------------------------------------------- the trusted path
class CountingUnicycle(crocopy.ActionModelUnicycle):
    """A user's subclass overriding calc, as Crocoddyl users write them."""

    def __init__(self):
        super().__init__()
        self.calls = 0
        self.checked_calls = 0

    def calc(self, data, x, u=None):
        self.calls += 1
        self.checked_calls += guards.checking()
        super().calc(data, x, u)


def guarded_methods() -> dict:
    """Every guarded method as its class holds it: ``(class, name) -> function``."""
    found, todo = {}, [guards.Guarded]
    while todo:
        cls = todo.pop()
        todo.extend(cls.__subclasses__())
        found.update({(cls, n): cls.__dict__[n] for n in cls._guards if n in cls.__dict__})
    return found


def test_solve_runs_user_overrides_unchecked_and_leaves_the_classes_alone():
    m = CountingUnicycle()
    problem = crocopy.ShootingProblem(np.array([-1.0, -1.0, 1.0]), [m] * 10, m)
    solver = crocopy.SolverFDDP(problem)
    before = guarded_methods()
    assert before[CountingUnicycle, "calc"]._crocopy_raw is not None
    inside = []

    def callback(s):
        inside.append((guards.checking(), guarded_methods() == before))

    solver.setCallbacks([callback])
    assert solver.solve([], [], 20)
    assert m.calls > 0 and m.checked_calls == 0
    assert inside and all(c == (False, True) for c in inside)  # unchecked, and no class changed
    assert guards.checking()
    assert guarded_methods() == before
    with pytest.raises(ValueError, match="x has shape"):
        m.calc(m.createData(), np.zeros(2))


def test_checks_come_back_after_a_solve_that_raises():
    m = crocopy.ActionModelUnicycle()
    problem = crocopy.ShootingProblem(np.zeros(3), [m] * 3, m)
    solver = crocopy.SolverFDDP(problem)

    def boom(s):
        raise RuntimeError("callback failed")

    solver.setCallbacks([boom])
    with pytest.raises(RuntimeError, match="callback failed"):
        solver.solve()
    assert guards.checking()
    with pytest.raises(ValueError, match="x contains NaN"):
        m.calc(m.createData(), np.full(3, np.nan))


def test_a_direct_call_checks_only_the_outermost_level():
    differential = crocopy.DifferentialActionModelLQR(2, 1)
    seen = []
    inner = type(differential)

    class Spy(inner):
        def calc(self, data, x, u=None):
            seen.append(guards.checking())
            super().calc(data, x, u)

    spy = Spy(2, 1)
    integrated = crocopy.IntegratedActionModelEuler(spy, 0.1)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        integrated.calc(integrated.createData(), [0.1, 0.2, 0.3, 0.4], [[0.5]])
    assert seen == [False]
    with pytest.raises(ArgumentTypeError):
        integrated.calc(integrated.createData(), None)


def test_problem_node_updates_and_named_items_check_their_arguments():
    p = unicycle_problem()
    with pytest.raises(TypeError, match="i must be an integer, got str"):
        p.updateModel("2", crocopy.ActionModelUnicycle())
    with pytest.raises(TypeError, match="model must be an ActionModelAbstract, got NoneType"):
        p.updateModel(2, None)
    with pytest.raises(TypeError, match="model must be an ActionModelAbstract, got str"):
        p.circularAppend("unicycle")
    state = crocopy.StateVector(2)
    costs = crocopy.CostModelSum(state, 1)
    with pytest.raises(TypeError, match="name of the cost must be a str, got int"):
        costs.addCost(3, crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, 1)), 1.0)
    costs.addCost("u", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, 1)), 1.0)
    with pytest.raises(TypeError, match="active must be a bool"):
        costs.changeCostStatus("u", "no")
    with pytest.raises(KeyError, match="no cost named 'v'"):
        costs.changeCostStatus("v", False)


def test_calc_diff_before_calc_evaluates_the_node_first():
    differential = crocopy.DifferentialActionModelLQR.Random(2, 1)
    x, u = np.array([0.1, -0.2, 0.3, 0.4]), np.array([0.5])
    fresh, ref = differential.createData(), differential.createData()
    differential.calcDiff(fresh, x, u)  # no calc before
    differential.calc(ref, x, u)
    differential.calcDiff(ref, x, u)
    assert fresh.cost == ref.cost
    for f in ("xout", "Fx", "Fu", "Lx", "Lu"):
        np.testing.assert_array_equal(getattr(fresh, f), getattr(ref, f), err_msg=f)


class Signatures(crocopy.ActionModelUnicycle):
    """A user's ``calc`` with positional-only, keyword-only and variadic parameters, and mutable defaults."""

    def calc(self, data, x, /, u=None, *extra, scale=1.0, **options):
        data.seen = (extra, scale, options)
        super().calc(data, x, u)

    def calcDiff(self, data, x, u=None, *, scale=1.0):
        data.seen = scale
        super().calcDiff(data, x, u)


def test_a_wrapper_has_its_methods_signature_and_forwards_every_argument():
    m = Signatures()
    d = m.createData()
    m.calc(d, [1.0, 2.0, 3.0], [[0.5], [0.1]], "a", scale=2.0, flag=True)
    assert d.seen == (("a",), 2.0, {"flag": True}) and np.isfinite(d.cost)
    assert str(inspect.signature(Signatures.calc)) == "(self, data, x, /, u=None, *extra, scale=1.0, **options)"
    assert Signatures.calc.__qualname__ == "Signatures.calc"
    with pytest.raises(TypeError, match=r"calc\(\) missing 1 required positional argument: 'x'"):
        m.calc(d, x=np.zeros(3))  # x is positional-only: here it is one of the options
    with pytest.raises(ValueError, match="u has shape"):
        m.calc(d, np.zeros(3), u=np.zeros(3))
    with guards.trusted_path():
        m.calc(d, np.zeros(3), np.zeros(2), scale=3.0)
    assert d.seen == ((), 3.0, {})
    assert str(inspect.signature(Signatures.calcDiff)) == "(self, data, x, u=None, *, scale=1.0)"
    m.calcDiff(d, x=[0.0, 1.0, 2.0], u=[[1.0], [2.0]], scale=4.0)
    assert d.seen == 4.0
    with pytest.raises(TypeError, match=r"calcDiff\(\) takes from 3 to 4 positional arguments but 5 were given"):
        m.calcDiff(d, np.zeros(3), np.zeros(2), 4.0)


class HalfControl(crocopy.ResidualModelControl):
    """A residual whose ``calc`` is not a plain function: it is not wrapped, and composites still call it."""

    def _scaled(self, data, x, u=None, scale=1.0):
        data.r[:] = scale * u

    calc = functools.partialmethod(_scaled, scale=0.5)


def test_composites_call_a_definition_that_is_not_a_function():
    state = crocopy.StateVector(3)
    residual = HalfControl(state, 2)
    cost = crocopy.CostModelResidual(state, residual)
    data = cost.createData(crocopy.DataCollectorAbstract())
    x, u = np.zeros(3), np.array([2.0, -4.0])
    cost.calc(data, x, u)
    np.testing.assert_array_equal(data.residual.r, [1.0, -2.0])
    assert data.cost == pytest.approx(0.5 * (1.0 + 4.0))
    assert HalfControl.__dict__["_raw_calc"] is HalfControl.__dict__["calc"]


class _HalvingMixin:
    """A mixin that is not guarded, placed before the guarded base (as ``ActionModelNumDiff`` does)."""

    def calc(self, data, x, u=None):
        data.r[:] = 0.5 * u


class MixedControl(_HalvingMixin, crocopy.ResidualModelControl):
    pass


def test_composites_call_a_method_a_mixin_defines():
    state = crocopy.StateVector(3)
    cost = crocopy.CostModelResidual(state, MixedControl(state, 2))
    data = cost.createData(crocopy.DataCollectorAbstract())
    cost.calc(data, np.zeros(3), np.array([2.0, -4.0]))
    np.testing.assert_array_equal(data.residual.r, [1.0, -2.0])
    assert MixedControl._raw_calc is _HalvingMixin.calc


# ---------------------------------------------------------------- issue 27: the last unclear errors and nonsense
def test_scalar_and_misshaped_references_name_the_argument():
    state = crocopy.StateVector(4)
    assert crocopy.ResidualModelState(state, 3).nu == 3  # Crocoddyl's (state, nu)
    with pytest.raises(ValueError, match=r"xref has shape \(\), expected \(4,\)"):
        crocopy.ResidualModelState(state, 1.0, 2)
    with pytest.raises(TypeError, match=r"xref must be a vector of shape \(4,\), got str 'abc'"):
        crocopy.ResidualModelState(state, "abc", 2)
    with pytest.raises(TypeError, match="nu must be an integer, got float"):
        crocopy.ResidualModelState(state, np.zeros(4), 2.0)
    assert crocopy.ResidualModelControl(state, 2).nu == 2
    with pytest.raises(TypeError, match=r"uref must be a vector of shape \(n,\) of real numbers, got dtype complex"):
        crocopy.ResidualModelControl(state, np.zeros(2) + 1j)
    with pytest.raises(ValueError, match=r"weights has shape \(2, 2\), expected \(n,\)"):
        crocopy.ActivationModelWeightedQuad(np.ones((2, 2)))


def test_impossible_bounds_are_refused():
    model = crocopy.ActionModelUnicycle()
    with pytest.raises(ValueError, match=r"u_lb\[1\] = inf: a lower bound of inf admits no value"):
        model.u_lb = np.array([0.0, np.inf])
    with pytest.raises(ValueError, match=r"u_ub\[0\] = -inf: an upper bound of -inf admits no value"):
        model.u_ub = np.array([-np.inf, 1.0])
    model.u_lb, model.u_ub = np.array([-np.inf, -1.0]), np.array([np.inf, 1.0])  # unbounded sides are fine
    with pytest.raises(ValueError, match=r"lb\[0\] = inf"):
        crocopy.ActivationBounds(np.full(2, np.inf), np.full(2, np.inf))
    with pytest.raises(ValueError, match="lb and ub must have the same shape"):
        crocopy.ActivationBounds(np.zeros(2), np.ones(3))
    with pytest.raises(ValueError, match=r"ub\[1\] = -inf"):
        crocopy.StateVector(2).ub = np.array([1.0, -np.inf])


def test_complex_and_boolean_numbers_are_refused():
    with pytest.raises(TypeError, match="alpha must be a real number, got complex"):
        crocopy.ActivationModelQuadFlatLog(2, 1j)
    with pytest.raises(TypeError, match="beta must be a real number, got bool"):
        crocopy.ActivationBounds(np.zeros(2), np.ones(2), True)
    integrated = crocopy.IntegratedActionModelEuler(crocopy.DifferentialActionModelLQR(2, 1), 0.1)
    with pytest.raises(TypeError, match=r"dt \(timeStep\) must be a real number, got str"):
        integrated.dt = "0.1"
    solver = crocopy.SolverFDDP(crocopy.ShootingProblem(np.zeros(3), [crocopy.ActionModelUnicycle()] * 2,
                                                        crocopy.ActionModelUnicycle()))
    with pytest.raises(ValueError, match="reg_min must be a finite number, got inf"):
        solver.reg_min = np.inf
    solver.reg_max = np.inf  # no maximum


def test_names_and_flags_of_named_items_have_their_types():
    state = crocopy.StateVector(2)
    costs = crocopy.CostModelSum(state, 1)
    costs.addCost("u", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, 1)), 1.0)
    for key in (True, 1, 1.0, None, b"u"):
        with pytest.raises(TypeError, match=rf"name must be a str, got {type(key).__name__}"):
            costs.changeCostStatus(key, False)
    manager = crocopy.ConstraintModelManager(state, 1)
    residual = crocopy.ResidualModelControl(state, 1)
    with pytest.raises(TypeError, match="active must be a bool, got str"):
        manager.addConstraint("c", crocopy.ConstraintModelResidual(state, residual, -np.ones(1), np.ones(1)), "yes")


def test_direct_calls_that_overflow_warn_at_every_level():
    state = crocopy.StateVector(2)
    huge = np.full(2, 1e200)
    activation = crocopy.ActivationModelQuad(2)
    residual = crocopy.ResidualModelState(state, np.zeros(2), 1)
    cost = crocopy.CostModelResidual(state, residual)
    costs = crocopy.CostModelSum(state, 1)
    costs.addCost("x", cost, 1.0)
    collector = crocopy.DataCollectorAbstract()
    for model, data, args, what in ((activation, activation.createData(), (huge,), "a_value"),
                                    (cost, cost.createData(collector), (huge, np.zeros(1)), "cost"),
                                    (costs, costs.createData(collector), (huge, np.zeros(1)), "cost")):
        with pytest.warns(NonFiniteWarning, match=rf"{type(model).__name__}: data.{what} is not finite"):
            model.calc(data, *args)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        residual.calc(residual.createData(collector), huge, np.zeros(1))  # r = x - xref: finite, no warning
    with pytest.warns(NonFiniteWarning, match=r"StateVector.diff: the result is not finite"):
        state.diff(np.full(2, -1.7e308), np.full(2, 1.7e308))


def test_index_and_rotation_checkers():
    from crocopy.validation import as_index, as_rotation

    assert as_index(np.int64(2), "i", 3) == 2
    for value, error, message in ((True, TypeError, "i must be an int index, got bool"),
                                  (1.0, TypeError, "i must be an int index, got float"),
                                  (3, ValueError, r"i = 3 is out of range \(0 <= i < 3\)"),
                                  (-1, ValueError, "i = -1 is out of range")):
        with pytest.raises(error, match=message):
            as_index(value, "i", 3)
    R = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    np.testing.assert_array_equal(as_rotation(R, "R"), R)
    with pytest.raises(ValueError, match="R must be a rotation matrix .* got a reflection of determinant -1"):
        as_rotation(R @ np.diag([1.0, 1.0, -1.0]), "R")
    with pytest.raises(ValueError, match=r"R must be a rotation matrix .* \|RᵀR - I\| = 0.002 of determinant 1.003"):
        as_rotation(1.001 * R, "R")


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 10), st.integers(0, 2),
                          st.sampled_from([np.nan, np.inf, -np.inf, 1e308, -1e308, 0.5])), max_size=4))
def test_trajectory_check_refuses_exactly_the_non_finite_entries(writes):
    """The one-sum check of a problem's plain trajectories (float64 arrays of the nodes' shapes) agrees with the
    entry-by-entry check: a NaN or inf anywhere is refused naming its vector; finite entries whose sum overflows are
    accepted; the arrays come back unchanged."""
    p = unicycle_problem()
    xs, us = [np.ones(3) for _ in range(6)], [np.zeros(2) for _ in range(5)]
    for t, i, value in writes:
        if t <= 5:
            xs[t][i] = value
        else:
            us[t - 6][min(i, 1)] = value
    bad = [f"xs[{t}]" for t, x in enumerate(xs) if not np.isfinite(x).all()]
    bad += [f"us[{t}]" for t, u in enumerate(us) if not np.isfinite(u).all()]
    if bad:
        with pytest.raises(ValueError, match=re.escape(bad[0]) + " contains NaN or inf"):
            p.check_trajectories(xs, us)
    else:
        checked_xs, checked_us = p.check_trajectories(xs, us)
        assert all(a is b for a, b in zip(checked_xs + checked_us, xs + us))
