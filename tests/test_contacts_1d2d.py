"""ContactModel1D/2D and the WORLD reference frame: derivatives, physics, force residuals and bad input.

Derivatives are checked against central finite differences as in ``test_contacts.py`` (step ``H``,
relative tolerance ``RTOL``); the contacts are mixed (1D, 2D, 3D, 6D) inside one
``ContactModelMultiple`` under ``DifferentialActionModelContactFwdDynamics``.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from robots import load
from test_contacts import H, assert_close, fd_dam, random_point

import crocopy

LOCAL, LWA, WORLD = pin.LOCAL, pin.LOCAL_WORLD_ALIGNED, pin.WORLD
FEET = ["LF_FOOT", "RF_FOOT", "LH_FOOT", "RH_FOOT"]
AXIS = pin.rpy.rpyToMatrix(0.3, 0.2, -0.4)
# (contact kinds per ANYmal foot: "1L" 1D LOCAL, "1A" 1D LWA, "1W" 1D WORLD, "2" 2D, "3W" 3D WORLD,
#  "6W" 6D WORLD), Baumgarte gains
CASES = [
    ("1L1A1W1L", (0.0, 0.0)),
    ("1L1A1W3W", (5.0, 3.0)),
    ("2222", (0.0, 0.0)),
    ("2222", (4.0, 2.0)),
    ("1A23W6W", (3.0, 1.0)),
]
IDS = [f"{k}-{'gains' if any(g) else 'nogains'}" for k, g in CASES]


def make_contact(state, kind, fid, gains, nu, rng):
    typ = {"L": LOCAL, "A": LWA, "W": WORLD}.get(kind[-1], LOCAL)
    if kind[0] == "1":
        return crocopy.ContactModel1D(state, fid, rng.normal(), typ, AXIS, nu, np.array(gains))
    if kind[0] == "2":
        return crocopy.ContactModel2D(state, fid, rng.normal(size=2), nu, np.array(gains))
    if kind[0] == "3":
        return crocopy.ContactModel3D(state, fid, rng.normal(size=3), typ, nu, np.array(gains))
    return crocopy.ContactModel6D(state, fid, pin.SE3(pin.exp3(rng.normal(size=3)), rng.normal(size=3)), typ, nu,
                                  np.array(gains))


def split(kinds):
    out, i = [], 0
    while i < len(kinds):
        j = i + 1
        while j < len(kinds) and not kinds[j].isdigit():
            j += 1
        out.append(kinds[i:j])
        i = j
    return out


def make_dam(kinds, gains, residual=None, seed=0):
    rng = np.random.default_rng(seed)
    model = load("anymal")
    state = crocopy.StateMultibody(model)
    act = crocopy.ActuationModelFloatingBase(state)
    nu = act.nu
    contacts = crocopy.ContactModelMultiple(state, nu)
    for name, kind in zip(FEET, split(kinds)):
        contacts.addContact(name, make_contact(state, kind, model.getFrameId(name), gains, nu, rng))
    costs = crocopy.CostModelSum(state, nu)
    costs.addCost("x", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, state.zero(), nu)), 0.1)
    costs.addCost("u", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, nu)), 0.01)
    if residual is not None:
        costs.addCost("r", crocopy.CostModelResidual(state, residual(state, model.getFrameId(FEET[0]), nu)), 1e-2)
    dam = crocopy.DifferentialActionModelContactFwdDynamics(state, act, contacts, costs, 0.0, True)
    dam.use_pinocchio_constraints = False
    return dam


@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_dam_derivatives(case):
    dam = make_dam(*case)
    x, u = random_point(dam)
    d = dam.createData()
    dam.calc(d, x, u)
    dam.calcDiff(d, x, u)
    J = fd_dam(dam, x, u)
    nv, ndx = dam.state.nv, dam.state.ndx
    assert_close(d.Fx, J[:nv, :ndx], "Fx")
    assert_close(d.Fu, J[:nv, ndx:], "Fu")
    assert_close(d.Lx, J[nv, :ndx], "Lx")
    assert_close(d.Lu, J[nv, ndx:], "Lu")


def _fd_force(dam, x, u):
    """Central differences of every contact's force rows (its ``force_rows`` of ``f.vector``)."""
    st_, d = dam.state, dam.createData()

    def forces(dx, du):
        dam.calc(d, st_.integrate(x, dx), u + du)
        return np.concatenate([c.f.vector[list(c.force_rows)] for c in d.multibody.contacts.contacts.values()])

    n = st_.ndx + dam.nu
    cols = []
    for i in range(n):
        e = np.zeros(n)
        e[i] = H
        cols.append((forces(e[: st_.ndx], e[st_.ndx:]) - forces(-e[: st_.ndx], -e[st_.ndx:])) / (2 * H))
    return np.array(cols).T


@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_force_jacobians(case):
    dam = make_dam(*case)
    x, u = random_point(dam, seed=2)
    d = dam.createData()
    dam.calc(d, x, u)
    dam.calcDiff(d, x, u)
    J = _fd_force(dam, x, u)
    ndx = dam.state.ndx
    assert_close(d.df_dx, J[:, :ndx], "df_dx")
    assert_close(d.df_du, J[:, ndx:], "df_du")


RESIDUALS = {
    "force1d": ("1A23W6W", lambda s, f, nu: crocopy.ResidualModelContactForce(s, f, pin.Force(np.arange(6.0)), 1, nu)),
    "cone2d": ("2222", lambda s, f, nu: crocopy.ResidualModelContactFrictionCone(
        s, f, crocopy.FrictionCone(AXIS, 0.7, 4, False), nu)),
    "grav1d": ("1L1A1W3W", lambda s, f, nu: crocopy.ResidualModelContactControlGrav(s, nu)),
    "grav2d": ("2222", lambda s, f, nu: crocopy.ResidualModelContactControlGrav(s, nu)),
}


@pytest.mark.parametrize("name", list(RESIDUALS))
def test_force_residual_derivatives(name):
    kinds, residual = RESIDUALS[name]
    dam = make_dam(kinds, (3.0, 2.0), residual)
    x, u = random_point(dam, seed=6)
    d = dam.createData()
    dam.calc(d, x, u)
    dam.calcDiff(d, x, u)
    rd = d.costs.costs["r"].residual
    st_, dd = dam.state, dam.createData()
    n = st_.ndx + dam.nu

    def r(dx, du):
        dam.calc(dd, st_.integrate(x, dx), u + du)
        return dd.costs.costs["r"].residual.r.copy()

    cols = []
    for i in range(n):
        e = np.zeros(n)
        e[i] = H
        cols.append((r(e[: st_.ndx], e[st_.ndx:]) - r(-e[: st_.ndx], -e[st_.ndx:])) / (2 * H))
    J = np.array(cols).T
    assert np.abs(J).max() > 1e-3  # the residual moves with the state and control
    assert_close(rd.Rx, J[:, : st_.ndx], "Rx")
    assert_close(rd.Ru, J[:, st_.ndx:], "Ru")


def test_contact_force_1d_reads_the_axis_component():
    dam = make_dam("1A23W6W", (0.0, 0.0), RESIDUALS["force1d"][1])
    x, u = random_point(dam, seed=3)
    d = dam.createData()
    dam.calc(d, x, u)
    cd = d.multibody.contacts.contacts[FEET[0]]
    assert cd.f.vector[0] == 0.0 and cd.f.vector[1] == 0.0 and cd.f.vector[2] != 0.0
    np.testing.assert_allclose(d.costs.costs["r"].residual.r, [cd.f.vector[2] - 2.0])


@pytest.mark.parametrize("kinds,gains", [("1L1A1W1L", (4.0, 3.0)), ("2222", (4.0, 3.0))])
def test_contact_acceleration_is_baumgarte(kinds, gains):
    """At the solution, each constrained acceleration component equals minus its Baumgarte terms."""
    dam = make_dam(kinds, gains)
    x, u = random_point(dam, seed=5)
    d = dam.createData()
    dam.calc(d, x, u)
    model, nq = dam.state.pinocchio, dam.state.nq
    pd = model.createData()
    pin.forwardKinematics(model, pd, x[:nq], x[nq:], d.xout)
    pin.updateFramePlacements(model, pd)
    kp, kd = gains
    for item in dam.contacts.contacts.values():
        c = item.contact
        oMf = pd.oMf[c.id]
        R, p = oMf.rotation, oMf.translation
        acc = pin.getFrameClassicalAcceleration(model, pd, c.id, LOCAL).linear
        vl = pin.getFrameVelocity(model, pd, c.id, LOCAL).linear
        if c.nc == 1:
            dp = p - c.reference * c.Raxis[:, 2]
            if c.type == LOCAL:
                got, target = c.Raxis[2] @ acc, -c.Raxis[2] @ (kp * R.T @ dp + kd * vl)
            else:
                got, target = c.Raxis[2] @ R @ acc, -c.Raxis[2] @ (kp * dp + kd * R @ vl)
        else:
            got, target = acc[[0, 2]], -(kp * (p[[0, 2]] - c.reference) + kd * vl[[0, 2]])
        np.testing.assert_allclose(got, target, atol=1e-8 * max(1.0, np.abs(target).max()))


@pytest.mark.parametrize("nc", [3, 6])
def test_world_is_local_world_aligned(nc):
    """A WORLD contact gives the same motion, forces and derivatives as a LOCAL_WORLD_ALIGNED one."""
    kinds = {3: ("3W3W3W3W", "3A3A3A3A"), 6: ("6W3W3W3W", "6A3A3A3A")}[nc]

    def dam(kind):
        model = load("anymal")
        state = crocopy.StateMultibody(model)
        act = crocopy.ActuationModelFloatingBase(state)
        contacts = crocopy.ContactModelMultiple(state, act.nu)
        rng = np.random.default_rng(4)
        for name, k in zip(FEET, split(kind)):
            typ = WORLD if k[-1] == "W" else LWA
            fid = model.getFrameId(name)
            c = (crocopy.ContactModel3D(state, fid, rng.normal(size=3), typ, act.nu, [2.0, 1.0]) if k[0] == "3" else
                 crocopy.ContactModel6D(state, fid, pin.SE3.Identity(), typ, act.nu, [2.0, 1.0]))
            contacts.addContact(name, c)
        costs = crocopy.CostModelSum(state, act.nu)
        return crocopy.DifferentialActionModelContactFwdDynamics(state, act, contacts, costs, 0.0, True)

    a, b = dam(kinds[0]), dam(kinds[1])
    assert a.contacts.contacts[FEET[0]].contact.type == WORLD
    x, u = random_point(a, seed=8)
    da, db = a.createData(), b.createData()
    for m, d in ((a, da), (b, db)):
        m.calc(d, x, u)
        m.calcDiff(d, x, u)
    assert (da.rigid is None) == (db.rigid is None)
    for name in ("xout", "Fx", "Fu", "df_dx", "df_du"):
        np.testing.assert_allclose(getattr(da, name), getattr(db, name), atol=1e-9, err_msg=name)


def test_world_impulse_is_local_world_aligned():
    model = load("talos_legs")
    state = crocopy.StateMultibody(model)
    out = []
    for typ in (WORLD, LWA):
        impulses = crocopy.ImpulseModelMultiple(state)
        impulses.addImpulse("l", crocopy.ImpulseModel6D(state, "left_sole_link", typ))
        impulses.addImpulse("r", crocopy.ImpulseModel3D(state, frame="right_sole_link", type=typ))
        costs = crocopy.CostModelSum(state, 0)
        m = crocopy.ActionModelImpulseFwdDynamics(state, impulses, costs, 0.0, 0.0, True)
        np.random.seed(3)
        x = state.rand()
        d = m.createData()
        m.calc(d, x, np.zeros(0))
        m.calcDiff(d, x, np.zeros(0))
        out.append(d)
    for name in ("xnext", "Fx", "df_dx"):
        np.testing.assert_allclose(getattr(out[0], name), getattr(out[1], name), atol=1e-10, err_msg=name)


def test_constructor_overloads_and_setters():
    model = load("anymal")
    state = crocopy.StateMultibody(model)
    fid = model.getFrameId("LF_FOOT")
    c = crocopy.ContactModel1D(state, fid, 0.1, LOCAL, np.array([1.0, 2.0]))
    assert c.nu == state.nv and c.nc == 1 and np.array_equal(c.Raxis, np.eye(3))
    np.testing.assert_array_equal(c.gains, [1.0, 2.0])
    c = crocopy.ContactModel1D(state=state, id=fid, xref=0.1, type=LWA, rotation=AXIS, nu=12, gains=[3.0, 0.0])
    assert c.nu == 12 and c.type == LWA and c.reference == 0.1
    c.reference = 0.5
    c.Raxis = np.eye(3)
    assert c.reference == 0.5 and np.array_equal(c.Raxis, np.eye(3))
    c2 = crocopy.ContactModel2D(state, "LF_FOOT", np.ones(2), np.array([1.0, 2.0]))
    assert c2.nu == state.nv and c2.nc == 2 and c2.type == LOCAL
    c2 = crocopy.ContactModel2D(state=state, id=fid, xref=np.ones(2), nu=12, gains=np.array([1.0, 2.0]))
    assert c2.nu == 12
    assert isinstance(c.createData(model.createData()), crocopy.ContactData1D)
    assert isinstance(c2.createData(model.createData()), crocopy.ContactData2D)


def test_bad_input():
    model = load("anymal")
    state = crocopy.StateMultibody(model)
    fid = model.getFrameId("LF_FOOT")
    with pytest.raises(ValueError, match="rotation"):
        crocopy.ContactModel1D(state, fid, 0.1, LOCAL, np.ones((3, 3)), 12)
    with pytest.raises(ValueError, match="xref"):
        crocopy.ContactModel1D(state, fid, np.zeros(3), LOCAL)
    with pytest.raises(ValueError, match="xref"):
        crocopy.ContactModel2D(state, fid, np.zeros(3))
    with pytest.raises(ValueError, match="gains"):
        crocopy.ContactModel2D(state, fid, np.zeros(2), 12, np.zeros(3))
    with pytest.raises(ValueError, match="type"):
        crocopy.ContactModel1D(state, fid, 0.1, "LOCAL")
    with pytest.raises(ValueError, match="nc must be 1, 3 or 6"):
        crocopy.ResidualModelContactForce(state, fid, pin.Force.Zero(), 2, 12)
    c1 = crocopy.ContactModel1D(state, fid, 0.1, LOCAL, AXIS, 12)
    with pytest.raises(ValueError, match=r"force has shape \(3,\), expected \(1,\)"):
        c1.updateForce(c1.createData(model.createData()), np.zeros(3))
    for kinds, residual, message in (
        ("1L1L1L1L", RESIDUALS["cone2d"][1], "dimension 1, expected >= 2"),
        ("3W3W3W3W", RESIDUALS["force1d"][1], "dimension 3, expected = 1"),
        ("2222", lambda s, f, nu: crocopy.ResidualModelContactForce(s, f, pin.Force.Zero(), 3, nu),
         "dimension 2, expected >= 3"),
    ):
        with pytest.raises(ValueError, match=message):
            make_dam(kinds, (0.0, 0.0), residual).createData()


@settings(max_examples=20, deadline=None)
@given(st.floats(-1.0, 1.0), st.floats(-1.0, 1.0), st.floats(-1.0, 1.0), st.floats(-2.0, 2.0))
def test_1d_is_the_projection_of_a_3d_contact(r, p, y, xref):
    """Jc, a0 and da0_dx of a 1D contact are e_zᵀ Raxis times those of the 3D contact on the point xref Raxis e_z."""
    model = load("anymal")
    state = crocopy.StateMultibody(model)
    Rax = pin.rpy.rpyToMatrix(r, p, y)
    np.random.seed(0)
    x = state.rand()
    q, v = x[: state.nq], x[state.nq:]
    for typ in (LOCAL, LWA):
        one = crocopy.ContactModel1D(state, "LF_FOOT", xref, typ, Rax, 12, [2.0, 3.0])
        three = crocopy.ContactModel3D(state, "LF_FOOT", xref * Rax[:, 2], typ, 12, [2.0, 3.0])
        pd = model.createData()
        pin.computeAllTerms(model, pd, q, v)
        pin.updateFramePlacements(model, pd)
        pin.computeForwardKinematicsDerivatives(model, pd, q, v, np.zeros(model.nv))
        d1, d3 = one.createData(pd), three.createData(pd)
        for m, d in ((one, d1), (three, d3)):
            m.calc(d, x)
            m.calcDiff(d, x)
        np.testing.assert_allclose(d1.Jc, Rax[2:3] @ d3.Jc, atol=1e-12)
        np.testing.assert_allclose(d1.a0, Rax[2:3] @ d3.a0, atol=1e-12)
        np.testing.assert_allclose(d1.da0_dx, Rax[2:3] @ d3.da0_dx, atol=1e-12)
