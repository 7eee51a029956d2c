"""The one cache-invalidation scheme (crocopy.versioning): parameter changes after ``createData`` reach ``calc``.

Cost sums cache their items' weights, activity and activation parameters; contact sets cache the
Pinocchio constraint models built from their contacts' references and gains.  Each test changes a
parameter after the data exist and compares with a data created afterwards (which cannot be stale).
"""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from robots import load

import crocopy
from crocopy.costs.stack import CostStack
from crocopy.versioning import ParametersSeen, ParametersVersion, touch

NR = 4


class _Owner:
    """Something with parameters."""


def test_parameters_seen_follows_the_stamps_of_its_sources():
    mine, other = _Owner(), _Owner()
    calls = []

    def sources():
        calls.append(1)
        return [mine]

    seen = ParametersSeen()
    assert seen.stale(sources)
    seen.filled()
    assert not seen.stale(sources) and not calls
    touch(other)
    assert not seen.stale(sources) and len(calls) == 1
    assert seen.value == ParametersVersion.value
    assert not seen.stale(sources) and len(calls) == 1
    touch(mine)
    assert seen.stale(sources) and seen.stale(sources)
    seen.filled()
    assert not seen.stale(sources)


def _cost_sum(state: crocopy.StateVector, nu: int) -> crocopy.CostModelSum:
    """Residual costs whose parameters live in items, activations and activation bounds."""
    costs = crocopy.CostModelSum(state, nu)
    bounds = crocopy.ActivationBounds(-0.2 * np.ones(NR), 0.3 * np.ones(NR))
    activations = {
        "wquad": crocopy.ActivationModelWeightedQuad(np.array([1.0, 2.0, 3.0, 0.5])),
        "barrier": crocopy.ActivationModelQuadraticBarrier(bounds),
        "wbarrier": crocopy.ActivationModelWeightedQuadraticBarrier(
            crocopy.ActivationBounds(-0.1 * np.ones(NR), 0.1 * np.ones(NR)), np.array([2.0, 1.0, 0.5, 3.0])
        ),
    }
    for k, (name, activation) in enumerate(activations.items()):
        residual = crocopy.ResidualModelControl(state, np.full(nu, 0.1 * k)) if k % 2 else crocopy.ResidualModelState(
            state, np.linspace(-0.5, 0.5, state.nx), nu
        )
        costs.addCost(name, crocopy.CostModelResidual(state, activation, residual), 1.0 + k)
    return costs


CHANGES = st.one_of(
    st.tuples(st.just("weights"), st.sampled_from(["wquad", "wbarrier"]),
              st.lists(st.floats(0.0, 5.0), min_size=NR, max_size=NR)),
    st.tuples(st.just("lb"), st.sampled_from(["barrier", "wbarrier"]),
              st.lists(st.floats(-1.0, -0.01), min_size=NR, max_size=NR)),
    st.tuples(st.just("ub"), st.sampled_from(["barrier", "wbarrier"]),
              st.lists(st.floats(0.01, 1.0), min_size=NR, max_size=NR)),
    st.tuples(st.just("bounds"), st.sampled_from(["barrier", "wbarrier"]), st.floats(0.01, 1.0)),
    st.tuples(st.just("weight"), st.sampled_from(["wquad", "barrier", "wbarrier"]), st.floats(0.0, 10.0)),
    st.tuples(st.just("status"), st.sampled_from(["wquad", "barrier", "wbarrier"]), st.booleans()),
)


def _apply(costs: crocopy.CostModelSum, change: tuple) -> None:
    kind, name, value = change
    activation = costs.costs[name].cost.activation
    if kind == "weights":
        activation.weights = np.array(value)
    elif kind in ("lb", "ub"):
        setattr(activation.bounds, kind, np.array(value))
    elif kind == "bounds":
        activation.bounds = crocopy.ActivationBounds(-value * np.ones(NR), value * np.ones(NR))
    elif kind == "weight":
        costs.costs[name].weight = value
    else:
        costs.changeCostStatus(name, value)


@settings(max_examples=40, deadline=None)
@given(changes=st.lists(CHANGES, min_size=1, max_size=6), terminal=st.booleans())
def test_cost_sum_data_see_every_parameter_change(changes, terminal):
    """After any sequence of changes, a data created before gives what a fresh data gives; the data of
    another cost sum whose parameters did not change keep their cached rows (no refresh)."""
    state, nu = crocopy.StateVector(4), 4
    costs, bystander = _cost_sum(state, nu), _cost_sum(state, nu)
    x = np.array([0.9, -0.7, 0.2, 0.3])
    u = None if terminal else np.array([0.4, -1.2, 0.0, 0.7])
    old = costs.createData(crocopy.DataCollectorAbstract())
    other = bystander.createData(crocopy.DataCollectorAbstract())
    costs.calc(old, x, u)
    bystander.calc(other, x, u)
    before = other.cost
    for change in changes:
        _apply(costs, change)
        costs.calc(old, x, u)
        costs.calcDiff(old, x, u)
        fresh = costs.createData(crocopy.DataCollectorAbstract())
        costs.calc(fresh, x, u)
        costs.calcDiff(fresh, x, u)
        assert old.cost == pytest.approx(fresh.cost, rel=1e-12, abs=1e-14)
        np.testing.assert_allclose(old.Lx, fresh.Lx, rtol=1e-12, atol=1e-14)
        np.testing.assert_allclose(old.Lxx, fresh.Lxx, rtol=1e-12, atol=1e-14)
    refreshed = []
    original = CostStack.refresh

    def counting(stack, terminal):
        refreshed.append(stack)
        original(stack, terminal)

    CostStack.refresh = counting
    try:
        bystander.calc(other, x, u)
    finally:
        CostStack.refresh = original
    assert other.cost == before and other.stack not in refreshed


def test_activation_parameters_are_read_only():
    costs = _cost_sum(crocopy.StateVector(4), 4)
    with pytest.raises(ValueError, match="read-only"):
        costs.costs["wquad"].cost.activation.weights[0] = 3.0
    with pytest.raises(ValueError, match="read-only"):
        costs.costs["barrier"].cost.activation.bounds.lb[0] = -3.0


def _contact_dam(kinds: str = "36"):
    """Talos legs on two feet (3D and/or 6D contacts, LOCAL, with Baumgarte gains): the rigid path applies."""
    model = load("talos_legs")
    state = crocopy.StateMultibody(model)
    actuation = crocopy.ActuationModelFloatingBase(state)
    nu = actuation.nu
    contacts = crocopy.ContactModelMultiple(state, nu)
    for foot, kind in zip(("left_sole_link", "right_sole_link"), kinds):
        if kind == "3":
            contact = crocopy.ContactModel3D(state, foot, np.array([0.0, 0.1, 0.0]), pin.LOCAL, nu, [4.0, 2.0])
        else:
            contact = crocopy.ContactModel6D(state, foot, pin.SE3.Identity(), pin.LOCAL, nu, [4.0, 2.0])
        contacts.addContact(foot, contact)
    costs = crocopy.CostModelSum(state, nu)
    costs.addCost("u", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, nu)), 1e-3)
    dam = crocopy.DifferentialActionModelContactFwdDynamics(state, actuation, contacts, costs)
    rng = np.random.default_rng(5)
    np.random.seed(5)
    return dam, state.rand(), rng.normal(size=nu)


def _xout(dam, data, x, u) -> np.ndarray:
    dam.calc(data, x, u)
    return data.xout.copy()


@pytest.mark.parametrize(
    "change",
    ["xref", "pref", "gains3", "gains6", "status"],
)
def test_contact_changes_after_create_data_reach_the_rigid_path(change):
    dam, x, u = _contact_dam()
    data = dam.createData()
    first = _xout(dam, data, x, u)
    assert data.rigid is not None
    items = dam.contacts.contacts
    if change == "xref":
        items["left_sole_link"].contact.reference = np.array([0.3, -0.2, 0.1])
    elif change == "pref":
        items["right_sole_link"].contact.reference = pin.SE3(np.eye(3), np.array([0.0, 0.2, -0.1]))
    elif change == "gains3":
        items["left_sole_link"].contact.gains = np.array([9.0, 1.0])
    elif change == "gains6":
        items["right_sole_link"].contact.gains = np.array([0.5, 7.0])
    else:
        dam.contacts.changeContactStatus("right_sole_link", False)
    after = _xout(dam, data, x, u)
    fresh = _xout(dam, dam.createData(), x, u)
    np.testing.assert_allclose(after, fresh, rtol=1e-10, atol=1e-10)
    assert not np.allclose(after, first, rtol=1e-6)


def test_unrelated_changes_keep_the_constraint_models():
    """Only the contact set's own parameters rebuild its Pinocchio constraint models."""
    dam, x, u = _contact_dam()
    data = dam.createData()
    dam.calc(data, x, u)
    built = data.rigid
    dam.costs.costs["u"].weight = 2e-3
    crocopy.ActivationModelWeightedQuad(np.ones(2)).weights = np.zeros(2)
    other, _, _ = _contact_dam()
    other.contacts.contacts["left_sole_link"].contact.gains = np.array([1.0, 1.0])
    dam.calc(data, x, u)
    assert data.rigid is built
    dam.contacts.contacts["left_sole_link"].contact.gains = np.array([1.0, 1.0])
    dam.calc(data, x, u)
    assert data.rigid is not built and data.rigid is not None


def test_contact_parameters_change_through_their_setters_only():
    dam, x, u = _contact_dam("36")
    point, frame = (item.contact for item in dam.contacts.contacts.values())
    with pytest.raises(ValueError, match="read-only"):
        point.reference[0] = 1.0
    with pytest.raises(ValueError, match="read-only"):
        frame.gains[0] = 1.0
    data = dam.createData()
    first = _xout(dam, data, x, u)
    frame.reference.translation = np.ones(3)  # a 6D contact's placement is live: the next evaluation sees it
    np.testing.assert_array_equal(frame.reference.translation, np.ones(3))
    moved = _xout(dam, data, x, u)
    assert not np.allclose(moved, first)
    np.testing.assert_allclose(moved, _xout(dam, dam.createData(), x, u), rtol=1e-12, atol=1e-12)


def test_a_copied_or_pickled_cache_mark_is_never_filled():


    seen = ParametersSeen()
    seen.filled()
    assert not seen.stale(list)
    for other in (copy.deepcopy(seen), pickle.loads(pickle.dumps(seen))):
        assert other.value == -1 and other.stale(list)



def test_datas_are_walked_only_when_one_was_made_stale(monkeypatch):
    """Items added to models whose datas are not made yet (building another problem) move the structure clock
    without making any data stale: ``refresh_datas`` then walks none of the problem's datas. A cost removed from a
    model whose data exists still makes that data stale, and only that node's data is replaced."""
    import crocopy.shooting as shooting
    from crocopy.problems import registry

    problem, xs, us = registry.build("pend")
    walked = []
    real = shooting.holds_stale_data
    monkeypatch.setattr(shooting, "holds_stale_data", lambda data: walked.append(data) or real(data))
    registry.build("pend")
    assert problem.refresh_datas() == [] and walked == []
    problem.runningModels[1].differential.costs.removeCost("control")
    old = list(problem.runningDatas)
    assert problem.refresh_datas() == [1] and len(walked) == problem.T + 1
    assert [d is o for d, o in zip(problem.runningDatas, old)] == [t != 1 for t in range(problem.T)]


def test_value_attributes_stamp_values_and_others_the_layout():
    """A value attribute assigned (a residual's ``reference``, ``dt``) is a change of values; any other public
    assignment (a frame, a residual's reference frame) a change of layout; :func:`changes_since` over a model's
    owners tells which, and a model not touched shows no change."""
    from crocopy.problems import registry
    from crocopy.versioning import LAYOUT, VALUES, changes_since, parameter_owners

    problem, _, _ = registry.build("arm")
    model, other = problem.runningModels[0], problem.runningModels[1]
    owners = parameter_owners(model)
    goal = model.differential.costs.costs["goal"].cost.residual
    assert goal in owners and model.differential.costs in owners and model.state in owners
    clock = ParametersVersion.value
    other.dt = 0.5 * other.dt
    assert changes_since(owners, clock) == 0
    goal.reference = goal.reference + 0.1
    assert changes_since(owners, clock) == VALUES
    clock = ParametersVersion.value
    model.dt = 2.0 * model.dt
    assert changes_since(owners, clock) == VALUES
    goal.id = goal.id - 1
    assert changes_since(owners, clock) == LAYOUT


def test_touched_since_lists_the_objects_whose_values_were_assigned():
    """:func:`touched_since` names the owners :func:`changes_since` counts as values, in order, and None for a layout
    change; :func:`residuals_only` tells a node whose touched objects are its residuals from one whose model was."""
    from crocopy.models.rbd.live_parameters import read_parameters, residuals_only
    from crocopy.problems import registry
    from crocopy.versioning import parameter_owners, touched_since

    problem, _, _ = registry.build("arm")
    model = problem.runningModels[0]
    owners = parameter_owners(model)
    costs = model.differential.costs.costs
    goal, state = costs["goal"].cost.residual, costs["state"].cost.residual
    live = read_parameters([(0, goal), (0, state)], [], lambda kind, r: r.compiled_parameters())
    clock = ParametersVersion.value
    assert touched_since(owners, clock) == []
    state.reference = state.reference + 0.1
    goal.reference = goal.reference + 0.1
    touched = touched_since(owners, clock)
    assert touched == [o for o in owners if o is goal or o is state] and len(touched) == 2
    assert residuals_only(touched, live)
    assert not residuals_only(touched, read_parameters([(0, goal)], [], lambda kind, r: r.compiled_parameters()))
    model.dt = 0.5 * model.dt
    touched = touched_since(owners, clock)
    assert model in touched and not residuals_only(touched, live)
    goal.id = goal.id - 1
    assert touched_since(owners, clock) is None


@pytest.mark.parametrize("name", ["state", "control", "translation", "com", "placement"])
def test_reference_arrays_are_the_compiled_parameters(name):
    """A compiled node's re-read of a residual's parameters (an array from its ``compiled_parameters()``, copied into
    the node's parameters) gives the same numbers as ``compiled_parameters()``, to the bit, after a reference set
    through the setter (and, for the live ``pin.SE3``, moved in place)."""
    from crocopy.models.rbd.live_parameters import LiveParameters

    model = load("talos_arm")
    state = crocopy.StateMultibody(model)
    fid = model.nframes - 1
    rng = np.random.default_rng(7)
    residual = {
        "state": lambda: crocopy.ResidualModelState(state, state.rand(), 3),
        "control": lambda: crocopy.ResidualModelControl(state, rng.standard_normal(3)),
        "translation": lambda: crocopy.ResidualModelFrameTranslation(state, fid, rng.standard_normal(3), 3),
        "com": lambda: crocopy.ResidualModelCoMPosition(state, rng.standard_normal(3), 3),
        "placement": lambda: crocopy.ResidualModelFramePlacement(state, fid, pin.SE3.Random(), 3),
    }[name]()
    if name == "placement":
        residual.reference = pin.SE3.Random()
        residual.reference.translation = rng.standard_normal(3)
    else:
        residual.reference = np.asarray(residual.reference) * np.pi
    expected = np.array(residual.compiled_parameters())
    par = np.full(expected.shape[0] + 2, np.nan)
    entry = (1, 1 + expected.shape[0], 0, residual)
    assert LiveParameters([entry], lambda kind, r: r.compiled_parameters(), [entry]).reread(par)
    assert np.array_equal(par[1:-1], expected) and np.isnan(par[0]) and np.isnan(par[-1])


def test_weights_are_values_and_activity_the_layout_of_a_cost_stack():
    """A cost item's ``weight`` and a weighted activation's ``weights`` are values: :func:`changes_since` says so and
    the cost stack re-reads them into the same arrays, reporting no change of its layout; switching an item off is a
    change of layout, for both."""
    from crocopy.versioning import LAYOUT, VALUES, changes_since, parameter_owners

    state = crocopy.StateVector(4)
    costs = crocopy.CostModelSum(state, 2)
    activation = crocopy.ActivationModelWeightedQuad(np.arange(1.0, 5.0))
    costs.addCost("x", crocopy.CostModelResidual(state, activation, crocopy.ResidualModelState(state, 2)), 2.0)
    costs.addCost("u", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, 2)), 3.0)
    data = costs.createData(crocopy.DataCollectorAbstract())
    x, u = np.linspace(-1.0, 1.0, 4), np.array([0.5, -2.0])
    costs.calc(data, x, u)
    stack = data.stack
    arrays = [stack.weights, stack.item_weights, stack.act_weights]
    owners = parameter_owners(costs)
    clock = ParametersVersion.value
    costs.costs["x"].weight = 5.0
    activation.weights = np.full(4, 0.5)
    assert changes_since(owners, clock) == VALUES
    assert stack.refresh_if_stale(False) is False
    assert [a is b for a, b in zip(arrays, [stack.weights, stack.item_weights, stack.act_weights])] == [True] * 3
    assert sorted(stack.item_weights.tolist()) == [3.0, 5.0] and 0.5 in stack.act_weights
    costs.calc(data, x, u)
    assert data.cost == pytest.approx(5.0 * 0.5 * 0.5 * float(x @ x) + 3.0 * 0.5 * float(u @ u))  # xref = 0
    clock = ParametersVersion.value
    costs.changeCostStatus("u", False)
    assert changes_since(owners, clock) == LAYOUT
    assert stack.refresh_if_stale(False) is True


def test_copies_and_pickles_carry_no_stamps():
    """A copied or unpickled model is one never touched: no clock value of this process travels with it."""
    from crocopy.problems import registry

    problem, _, _ = registry.build("arm")
    model = problem.runningModels[0]
    model.dt = model.dt
    assert "_stamp" in model.__dict__ and "_layout_stamp" in model.__dict__
    for other in (copy.deepcopy(model), pickle.loads(pickle.dumps(model))):
        assert "_stamp" not in other.__dict__ and "_layout_stamp" not in other.__dict__
        assert other.dt == model.dt
