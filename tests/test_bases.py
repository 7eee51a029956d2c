"""Shared bases: Crocoddyl's constructor signatures for subclassing from Python, and what the bases share.

- ``ActionModelAbstract(state, nu, nr=1, ng=0, nh=0, ng_T=0, nh_T=0)`` and the same for
  ``DifferentialActionModelAbstract`` (Crocoddyl 3.2 documents ``nr`` default 1), positional and by keyword;
- ``ContactModelAbstract(state, type, nc, nu=state.nv)``, ``ImpulseModelAbstract(state, type, nc)`` and
  ``ImpulseModelAbstract(state, nc)``, ``ImpulseModel3D/6D(state, frame, type=LOCAL)``;
- the quasi-static Newton loop both action kinds share, on models whose answer is known in closed form;
- the checks cost sums, constraint managers, contact and impulse sets share when an item is added.
"""

from __future__ import annotations

import inspect

import numpy as np
import pinocchio as pin
import pytest
from robots import load

import crocopy

CROCODDYL_ACTION_SIGNATURE = [
    ("state", inspect.Parameter.empty),
    ("nu", inspect.Parameter.empty),
    ("nr", 1),
    ("ng", 0),
    ("nh", 0),
    ("ng_T", 0),
    ("nh_T", 0),
]
ABSTRACTS = [crocopy.ActionModelAbstract, crocopy.DifferentialActionModelAbstract]


class LinearAction(crocopy.ActionModelAbstract):
    """``xnext = x + B u + c`` from Python, constructed with keyword arguments only."""

    def __init__(self, B: np.ndarray, c: np.ndarray) -> None:
        super().__init__(state=crocopy.StateVector(B.shape[0]), nu=B.shape[1], nr=0)
        self.B, self.c = B, c

    def calc(self, data, x, u=None):
        data.xnext[:] = x if u is None else x + self.B @ u + self.c
        data.cost = 0.0

    def calcDiff(self, data, x, u=None):
        data.Fx[:] = np.eye(self.state.ndx)
        data.Fu[:] = self.B


class LinearDifferential(crocopy.DifferentialActionModelAbstract):
    """``xout = A x + B u`` from Python, constructed with keyword arguments only."""

    def __init__(self, A: np.ndarray, B: np.ndarray) -> None:
        super().__init__(state=crocopy.StateVector(A.shape[1]), nu=B.shape[1], nr=0)
        self.A, self.B = A, B

    def calc(self, data, x, u=None):
        data.xout[:] = self.A @ x + (0.0 if u is None else self.B @ u)
        data.cost = 0.0

    def calcDiff(self, data, x, u=None):
        data.Fx[:] = self.A
        data.Fu[:] = self.B


@pytest.mark.parametrize("abstract", ABSTRACTS, ids=lambda c: c.__name__)
def test_action_abstracts_have_crocoddyl_signature(abstract):
    params = list(inspect.signature(abstract.__init__).parameters.values())[1:]
    assert [(p.name, p.default) for p in params] == CROCODDYL_ACTION_SIGNATURE


@pytest.mark.parametrize("abstract", ABSTRACTS, ids=lambda c: c.__name__)
def test_action_abstracts_by_keyword_and_position(abstract):
    state = crocopy.StateVector(4)
    by_keyword = abstract(state=state, nu=2, nr=3, ng=1, nh=2, ng_T=1, nh_T=1)
    by_position = abstract(state, 2, 3, 1, 2, 1, 1)
    for model in (by_keyword, by_position):
        assert (model.nu, model.nr, model.ng, model.nh, model.ng_T, model.nh_T) == (2, 3, 1, 2, 1, 1)
        assert model.state is state
        assert model.g_lb.shape == (1,) and np.all(model.g_lb == -np.inf) and np.all(model.g_ub == np.inf)
        assert model.u_lb.shape == (2,) and not model.has_control_limits
    defaults = abstract(state, 2)
    assert (defaults.nr, defaults.ng, defaults.nh, defaults.ng_T, defaults.nh_T) == (1, 0, 0, 0, 0)
    data = by_keyword.createData()
    assert by_keyword.checkData(data)
    nf = state.ndx if abstract is crocopy.ActionModelAbstract else state.nv
    assert data.Fx.shape == (nf, state.ndx) and data.Fu.shape == (nf, 2) and data.r.shape == (3,)
    assert data.g.shape == (1,) and data.h.shape == (2,) and data.Hu.shape == (2, 2)


@pytest.mark.parametrize("abstract", ABSTRACTS, ids=lambda c: c.__name__)
def test_action_abstracts_reject_bad_state_and_nu(abstract):
    with pytest.raises(ValueError, match="state must be a StateAbstract"):
        abstract(state=np.zeros(3), nu=1)
    with pytest.raises(ValueError, match="nu must be non-negative"):
        abstract(crocopy.StateVector(2), -1)
    model = abstract(crocopy.StateVector(2), 2)
    with pytest.raises(ValueError, match="u_lb"):
        model.u_lb = np.zeros(3)
    model.u_lb, model.u_ub = -np.ones(2), np.ones(2)
    assert model.has_control_limits
    with pytest.raises(NotImplementedError):
        model.calc(model.createData(), np.zeros(2), np.zeros(2))


def test_quasi_static_of_both_kinds():
    """The shared Newton loop: ``B u = -c`` for the discrete model, ``B u = -A x`` for the differential one."""
    rng = np.random.default_rng(0)
    B, c = rng.normal(size=(3, 3)), rng.normal(size=3)
    discrete = LinearAction(B, c)
    u = discrete.quasiStatic(discrete.createData(), rng.normal(size=3))
    np.testing.assert_allclose(B @ u, -c, atol=1e-10)
    A, Bd = rng.normal(size=(2, 4)), rng.normal(size=(2, 2))
    differential = LinearDifferential(A, Bd)
    x = rng.normal(size=4)
    u = differential.quasiStatic(differential.createData(), x)
    np.testing.assert_allclose(Bd @ u, -A @ x, atol=1e-10)
    integrated = crocopy.IntegratedActionModelEuler(differential, 0.1)
    np.testing.assert_allclose(integrated.quasiStatic(integrated.createData(), x), u, atol=1e-12)
    with pytest.raises(ValueError, match="x"):
        differential.quasiStatic(differential.createData(), np.zeros(3))


def test_actuation_control_bounds_are_checked():
    actuation = crocopy.ActuationModelAbstract(state=crocopy.StateVector(4), nu=2)
    assert np.all(actuation.u_lb == -np.inf) and actuation.u_ub.shape == (2,)
    actuation.u_ub = np.zeros(2)
    actuation.u_lb = np.ones(2)  # above u_ub for now: the pair is checked where it is used
    actuation.u_ub = 2.0 * np.ones(2)
    np.testing.assert_array_equal(actuation.u_lb, 1.0)
    with pytest.raises(ValueError, match="u_lb"):
        actuation.u_lb = np.array([0.0, np.nan])
    with pytest.raises(ValueError, match="u_ub"):
        actuation.u_ub = np.zeros(3)
    assert not hasattr(actuation, "has_control_limits")
    with pytest.raises(ValueError, match="nu must be non-negative"):
        crocopy.ActuationModelAbstract(crocopy.StateVector(4), -2)


def _anymal():
    model = load("anymal")
    return model, crocopy.StateMultibody(model)


def test_contact_and_impulse_abstracts_have_crocoddyl_signatures():
    model, state = _anymal()
    contact = crocopy.ContactModelAbstract(state=state, type=pin.LOCAL_WORLD_ALIGNED, nc=3)
    assert (contact.nc, contact.nu, contact.type, contact.id) == (3, state.nv, pin.LOCAL_WORLD_ALIGNED, 0)
    contact = crocopy.ContactModelAbstract(state, pin.LOCAL, 6, nu=12)
    assert (contact.nc, contact.nu) == (6, 12)
    impulse = crocopy.ImpulseModelAbstract(state=state, type=pin.LOCAL_WORLD_ALIGNED, nc=6)
    assert (impulse.nc, impulse.ni, impulse.nu, impulse.type) == (6, 6, 0, pin.LOCAL_WORLD_ALIGNED)
    impulse = crocopy.ImpulseModelAbstract(state, 3)
    assert (impulse.nc, impulse.type) == (3, pin.LOCAL)
    fid = model.getFrameId("LF_FOOT")
    point = crocopy.ImpulseModel3D(state, frame=fid, type=pin.LOCAL_WORLD_ALIGNED)
    assert (point.id, point.nc, point.type) == (fid, 3, pin.LOCAL_WORLD_ALIGNED)
    assert crocopy.ImpulseModel6D(state, "LF_FOOT").nc == 6
    with pytest.raises(ValueError, match="type"):
        crocopy.ContactModelAbstract(state, "LOCAL", 3)
    with pytest.raises(ValueError, match="StateMultibody"):
        crocopy.ImpulseModelAbstract(crocopy.StateVector(4), pin.LOCAL, 3)
    with pytest.raises(ValueError, match="nu must be non-negative"):
        crocopy.ContactModelAbstract(state, pin.LOCAL, 3, -1)


def test_contact_and_impulse_data_share_crocoddyls_force_data():
    """Both data derive from ``ForceDataAbstract`` and hold its fields with the model's shapes."""
    model, state = _anymal()
    pdata = model.createData()
    contact = crocopy.ContactModel3D(state, "LF_FOOT", np.zeros(3), pin.LOCAL, 12)
    impulse = crocopy.ImpulseModel6D(state, "RF_FOOT")
    for m, nu in ((contact, 12), (impulse, 0)):
        d = m.createData(pdata)
        assert isinstance(d, crocopy.ForceDataAbstract)
        assert d.pinocchio is pdata and d.frame == m.id and d.type == m.type
        assert d.Jc.shape == (m.nc, state.nv) and d.df_dx.shape == (m.nc, state.ndx) and d.df_du.shape == (m.nc, nu)
        assert d.joint == model.frames[m.id].parentJoint
        m.updateForce(d, np.arange(1.0, m.nc + 1.0))
        assert np.linalg.norm(d.fext.vector) > 0.0
        m.setZeroForce(d)
        assert not np.any(d.f.vector) and not np.any(d.fext.vector)


@pytest.mark.parametrize("kind", ["3", "6"])
def test_contact_and_impulse_share_the_joint_force_maps(kind):
    """A contact and an impulse on the same frame map the same force to the same ``fext`` and RNEA term."""
    model, state = _anymal()
    pdata = model.createData()
    q = pin.randomConfiguration(model, -np.ones(model.nq), np.ones(model.nq))
    pin.computeJointJacobians(model, pdata, q)
    pin.updateFramePlacements(model, pdata)
    lwa = pin.LOCAL_WORLD_ALIGNED
    if kind == "3":
        contact = crocopy.ContactModel3D(state, "LF_FOOT", np.zeros(3), lwa)
        impulse = crocopy.ImpulseModel3D(state, "LF_FOOT", lwa)
    else:
        contact = crocopy.ContactModel6D(state, "LF_FOOT", pin.SE3.Identity(), lwa)
        impulse = crocopy.ImpulseModel6D(state, "LF_FOOT", lwa)
    force = np.random.default_rng(1).normal(size=contact.nc)
    dtau = []
    for m in (contact, impulse):
        d = m.createData(pdata)
        d.fJf[:] = pin.getFrameJacobian(model, pdata, m.id, pin.LOCAL)
        m.updateForce(d, force)
        out = np.zeros((state.nv, state.nv))
        m.addRneaDiff(d, out)
        dtau.append((d.fext.vector.copy(), out))
    R = pdata.oMf[contact.id].rotation
    f_local = np.concatenate([R.T @ force[:3], R.T @ force[3:] if kind == "6" else np.zeros(3)])
    expected = model.frames[contact.id].placement.act(pin.Force(f_local)).vector
    np.testing.assert_allclose(dtau[0][0], expected, atol=1e-12)
    np.testing.assert_allclose(dtau[1][0], expected, atol=1e-12)
    np.testing.assert_allclose(dtau[0][1], dtau[1][1], atol=1e-12)
    assert np.linalg.norm(dtau[0][1]) > 0.0


def test_registries_share_their_checks():
    """Cost sums, constraint managers, contact and impulse sets refuse the same kinds of items alike."""
    model, state = _anymal()
    other = crocopy.StateVector(5)
    nu = 12
    costs = crocopy.CostModelSum(state, nu)
    constraints = crocopy.ConstraintModelManager(state, nu)
    contacts = crocopy.ContactModelMultiple(state, nu)
    impulses = crocopy.ImpulseModelMultiple(state)
    assert crocopy.CostModelSum(state).nu == state.nv == crocopy.ContactModelMultiple(state).nu
    residual = crocopy.ResidualModelControl(state, nu)
    cost = crocopy.CostModelResidual(state, residual)
    constraint = crocopy.ConstraintModelResidual(state, residual)
    contact = crocopy.ContactModel3D(state, "LF_FOOT", np.zeros(3), pin.LOCAL, nu)
    impulse = crocopy.ImpulseModel3D(state, "LF_FOOT")
    adders = [
        (costs.addCost, cost, (1.0,)),
        (constraints.addConstraint, constraint, ()),
        (contacts.addContact, contact, ()),
        (impulses.addImpulse, impulse, ()),
    ]
    for add, item, extra in adders:
        with pytest.raises(ValueError, match="must be a"):
            add("bad", object(), *extra)
        add("one", item, *extra)
        with pytest.raises(ValueError, match="already exists"):
            add("one", item, *extra)
    with pytest.raises(ValueError, match="has nu = 10, expected nu = 12"):
        costs.addCost("nu", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, 10)), 1.0)
    with pytest.raises(ValueError, match="has nu = 18, expected nu = 12"):
        contacts.addContact("nu", crocopy.ContactModel3D(state, "RF_FOOT", np.zeros(3), pin.LOCAL))
    with pytest.raises(ValueError, match="another dimension"):
        constraints.addConstraint("x", crocopy.ConstraintModelResidual(other, crocopy.ResidualModelState(other, nu)))
    with pytest.raises(ValueError, match="another robot"):
        solo = crocopy.StateMultibody(load("solo12"))
        impulses.addImpulse("solo", crocopy.ImpulseModel3D(solo, "FL_FOOT"))
    with pytest.raises(ValueError, match="StateMultibody"):
        crocopy.ContactModelMultiple(other)
    with pytest.raises(ValueError, match="StateAbstract"):
        crocopy.CostModelSum(object())
    assert costs.getCostStatus("one") and constraints.getConstraintStatus("one")
    costs.changeCostStatus("one", False)
    assert not costs.getCostStatus("one") and costs.inactive_set == {"one"}
    for registry in (costs, constraints, contacts, impulses):
        assert repr(registry).startswith(type(registry).__name__ + "(one: ")
