"""Contacts and DifferentialActionModelContactFwdDynamics: derivatives, physics and bad input.

Derivatives are checked against central finite differences on the tangent space with step
``H = 1e-6`` (truncation ~1e-12, round-off ~1e-10 relative); Jacobians must agree to
``RTOL = 1e-5`` relative to their largest entry (the contact dynamics has entries ~1e3).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from robots import load

import crocopy

H = 1e-6
RTOL = 1e-5
LOCAL, LWA = pin.LOCAL, pin.LOCAL_WORLD_ALIGNED
FEET = {
    "anymal": ["LF_FOOT", "RF_FOOT", "LH_FOOT", "RH_FOOT"],
    "solo12": ["FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT"],
    "talos_legs": ["left_sole_link", "right_sole_link"],
}
# (robot, contact kinds per foot, reference frame, Baumgarte gains)
CASES = [
    ("anymal", "3333", LOCAL, (0.0, 0.0)),
    ("anymal", "3333", LWA, (10.0, 5.0)),
    ("solo12", "3333", LOCAL, (3.0, 2.0)),
    ("solo12", "3333", LWA, (0.0, 0.0)),
    ("talos_legs", "66", LOCAL, (0.0, 0.0)),
    ("talos_legs", "66", LWA, (4.0, 3.0)),
    ("talos_legs", "63", LOCAL, (2.0, 1.0)),
    ("talos_legs", "36", LWA, (0.0, 2.0)),
]
IDS = [f"{r}-{k}-{'LWA' if t == LWA else 'LOCAL'}-{'gains' if any(g) else 'nogains'}" for r, k, t, g in CASES]


def make_dam(robot, kinds, typ, gains, force_cost=True, seed=0, kkt=False):
    """A contact DAM with state, control, frame and contact-force costs (forces enter the cost).

    ``kkt`` forces the explicit KKT path instead of Pinocchio's constraint dynamics.
    """
    rng = np.random.default_rng(seed)
    model = load(robot)
    state = crocopy.StateMultibody(model)
    act = crocopy.ActuationModelFloatingBase(state)
    nu = act.nu
    contacts = crocopy.ContactModelMultiple(state, nu)
    for name, kind in zip(FEET[robot], kinds):
        fid = model.getFrameId(name)
        if kind == "3":
            c = crocopy.ContactModel3D(state, fid, rng.normal(size=3), typ, nu, np.array(gains))
        else:
            c = crocopy.ContactModel6D(state, fid, pin.SE3.Random(), typ, nu, np.array(gains))
        contacts.addContact(name, c)
    costs = crocopy.CostModelSum(state, nu)
    costs.addCost("x", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, state.zero(), nu)), 0.1)
    costs.addCost("u", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, nu)), 0.01)
    base = model.getFrameId("root_joint")
    place = crocopy.ResidualModelFramePlacement(state, base, pin.SE3.Random(), nu)
    costs.addCost("place", crocopy.CostModelResidual(state, place), 0.1)
    vel = crocopy.ResidualModelFrameVelocity(state, base, pin.Motion.Random(), LWA, nu)
    costs.addCost("vel", crocopy.CostModelResidual(state, vel), 0.1)
    if force_cost:
        fid = model.getFrameId(FEET[robot][0])
        nc = 3 if kinds[0] == "3" else 6
        force = crocopy.ResidualModelContactForce(state, fid, pin.Force(np.arange(6.0)), nc, nu)
        costs.addCost("f", crocopy.CostModelResidual(state, force), 1e-3)
    dam = crocopy.DifferentialActionModelContactFwdDynamics(state, act, contacts, costs, 0.0, True)
    dam.use_pinocchio_constraints = not kkt
    return dam


def random_point(model, seed=1):
    np.random.seed(seed)
    return model.state.rand(), np.random.default_rng(seed).normal(size=model.nu)


def fd_dam(dam, x, u):
    """Central differences of (xout, cost, stacked forces) w.r.t. (dx, du)."""
    st, d = dam.state, dam.createData()
    n = st.ndx + dam.nu

    def out(dx, du):
        dam.calc(d, st.integrate(x, dx), u + du)
        f = np.concatenate([c.f.vector[: c.Jc.shape[0]] for c in d.multibody.contacts.contacts.values()])
        return np.concatenate([d.xout, [d.cost], f])

    cols = []
    for i in range(n):
        e = np.zeros(n)
        e[i] = H
        cols.append((out(e[: st.ndx], e[st.ndx:]) - out(-e[: st.ndx], -e[st.ndx:])) / (2 * H))
    return np.array(cols).T


def assert_close(A, B, name):
    scale = max(1.0, np.abs(B).max())
    err = np.abs(A - B).max()
    assert err <= RTOL * scale, f"{name}: max error {err:.3e} (scale {scale:.3e})"


def assert_matches_fd(dam, d, x, u):
    """``Fx, Fu, Lx, Lu, df_dx, df_du`` of ``d`` (after calc/calcDiff at ``(x, u)``) against :func:`fd_dam`."""
    J = fd_dam(dam, x, u)
    nv, ndx = dam.state.nv, dam.state.ndx
    assert_close(d.Fx, J[:nv, :ndx], "Fx")
    assert_close(d.Fu, J[:nv, ndx:], "Fu")
    assert_close(d.Lx, J[nv, :ndx], "Lx")
    assert_close(d.Lu, J[nv, ndx:], "Lu")
    assert_close(d.df_dx, J[nv + 1:, :ndx], "df_dx")
    assert_close(d.df_du, J[nv + 1:, ndx:], "df_du")


@pytest.mark.parametrize("kkt", [False, True], ids=["pinocchio", "kkt"])
@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_dam_derivatives(case, kkt):
    dam = make_dam(*case, kkt=kkt)
    x, u = random_point(dam)
    d = dam.createData()
    dam.calc(d, x, u)
    dam.calcDiff(d, x, u)
    assert (d.rigid is None) == (kkt or (case[2] == LWA and "6" in case[1] and case[3][0] != 0.0))
    assert_matches_fd(dam, d, x, u)
    i = 0
    for cd in d.multibody.contacts.contacts.values():
        nc = cd.Jc.shape[0]
        assert np.array_equal(cd.df_dx, d.df_dx[i:i + nc])
        i += nc


INTEGRATED = [
    (CASES[1], "euler"), (CASES[1], "rk4"), (CASES[4], "euler"), (CASES[4], "rk2"),
    (CASES[5], "rk4"), (CASES[2], "rk3"), (CASES[7], "euler"), (CASES[7], "rk4"),
]


def integrate(dam, kind):
    if kind == "euler":
        return crocopy.IntegratedActionModelEuler(dam, 1e-2)
    rk = {"rk2": crocopy.RKType.two, "rk3": crocopy.RKType.three, "rk4": crocopy.RKType.four}[kind]
    return crocopy.IntegratedActionModelRK(dam, rk, 1e-2)


@pytest.mark.parametrize("case,kind", INTEGRATED, ids=[f"{IDS[CASES.index(c)]}-{k}" for c, k in INTEGRATED])
def test_integrated_derivatives(case, kind):
    model = integrate(make_dam(*case, kkt=kind == "rk2"), kind)
    x, u = random_point(model, seed=3)
    st, d = model.state, model.createData()
    model.calc(d, x, u)
    model.calcDiff(d, x, u)
    n = st.ndx + model.nu
    x0 = d.xnext.copy()
    J = np.zeros((st.ndx + 1, n))
    for i in range(n):
        e = np.zeros(n)
        e[i] = H
        model.calc(d, st.integrate(x, e[: st.ndx]), u + e[st.ndx:])
        xp, cp = st.diff(x0, d.xnext), d.cost
        model.calc(d, st.integrate(x, -e[: st.ndx]), u - e[st.ndx:])
        J[:, i] = np.r_[xp - st.diff(x0, d.xnext), cp - d.cost] / (2 * H)
    model.calc(d, x, u)
    model.calcDiff(d, x, u)
    assert_close(d.Fx, J[: st.ndx, : st.ndx], "Fx")
    assert_close(d.Fu, J[: st.ndx, st.ndx:], "Fu")
    assert_close(d.Lx, J[st.ndx, : st.ndx], "Lx")
    assert_close(d.Lu, J[st.ndx, st.ndx:], "Lu")


@pytest.mark.parametrize("kkt", [False, True], ids=["pinocchio", "kkt"])
@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_contact_acceleration_is_baumgarte(case, kkt):
    """The contact-frame acceleration at the solution equals minus the Baumgarte terms."""
    dam = make_dam(*case, force_cost=False, kkt=kkt)
    x, u = random_point(dam, seed=5)
    d = dam.createData()
    dam.calc(d, x, u)
    model, nq = dam.state.pinocchio, dam.state.nq
    pd = model.createData()
    pin.forwardKinematics(model, pd, x[:nq], x[nq:], d.xout)
    pin.updateFramePlacements(model, pd)
    kp, kd = case[3]
    for item in dam.contacts.contacts.values():
        c = item.contact
        oMf = pd.oMf[c.id]
        v = pin.getFrameVelocity(model, pd, c.id, LOCAL)
        if c.nc == 3:
            acc = pin.getFrameClassicalAcceleration(model, pd, c.id, LOCAL).linear
            target = -(kp * oMf.rotation.T @ (oMf.translation - c.reference) + kd * v.linear)
        else:
            acc = pin.getFrameAcceleration(model, pd, c.id, LOCAL).vector
            target = -(kp * pin.log6(c.reference.inverse() * oMf).vector + kd * v.vector)
        np.testing.assert_allclose(acc, target, atol=1e-8 * max(1.0, np.abs(target).max()))


def test_local_and_world_aligned_give_same_motion():
    """LOCAL and LOCAL_WORLD_ALIGNED 6D contacts give the same acceleration; forces differ by R."""
    a, b = make_dam("talos_legs", "66", LOCAL, (0.0, 0.0)), make_dam("talos_legs", "66", LWA, (0.0, 0.0))
    x, u = random_point(a, seed=7)
    da, db = a.createData(), b.createData()
    a.calc(da, x, u)
    b.calc(db, x, u)
    np.testing.assert_allclose(da.xout, db.xout, atol=1e-9)
    for name, ca in da.multibody.contacts.contacts.items():
        R = db.pinocchio.oMf[ca.frame].rotation
        cb = db.multibody.contacts.contacts[name]
        np.testing.assert_allclose(R @ ca.f.linear, cb.f.linear, atol=1e-8)
        np.testing.assert_allclose(R @ ca.f.angular, cb.f.angular, atol=1e-8)


def anymal_stance():
    model = load("anymal")
    state = crocopy.StateMultibody(model)
    q0 = model.referenceConfigurations["standing"].copy()
    pd = model.createData()
    pin.framesForwardKinematics(model, pd, q0)
    act = crocopy.ActuationModelFloatingBase(state)
    contacts = crocopy.ContactModelMultiple(state, act.nu)
    for name in FEET["anymal"]:
        fid = model.getFrameId(name)
        contacts.addContact(name, crocopy.ContactModel3D(state, fid, pd.oMf[fid].translation, LWA, act.nu, [0, 50]))
    costs = crocopy.CostModelSum(state, act.nu)
    dam = crocopy.DifferentialActionModelContactFwdDynamics(state, act, contacts, costs)
    return dam, np.concatenate([q0, np.zeros(model.nv)])


def test_quasi_static_anymal_stance():
    dam, x0 = anymal_stance()
    d = dam.createData()
    u = dam.quasiStatic(d, x0)
    dam.calc(d, x0, u)
    np.testing.assert_allclose(d.xout, 0.0, atol=1e-8)
    fz = sum(c.f.linear[2] for c in d.multibody.contacts.contacts.values())
    mass = sum(i.mass for i in dam.state.pinocchio.inertias)
    assert fz == pytest.approx(mass * 9.81, rel=1e-6)
    assert np.all(np.abs(u) <= dam.u_ub)


def test_control_limits_from_urdf():
    dam, _ = anymal_stance()
    effort = dam.state.pinocchio.effortLimit[6:]
    np.testing.assert_array_equal(dam.u_ub, effort)
    np.testing.assert_array_equal(dam.u_lb, -effort)
    assert not dam.has_control_limits
    assert crocopy.IntegratedActionModelEuler(dam, 1e-2).has_control_limits


def test_inactive_contact_equals_removed_contact():
    dam, x0 = anymal_stance()
    dam.contacts.changeContactStatus("LF_FOOT", False)
    assert dam.contacts.nc == 9 and dam.contacts.nc_total == 12
    assert dam.contacts.active_set == {"RF_FOOT", "LH_FOOT", "RH_FOOT"}
    assert dam.contacts.inactive_set == {"LF_FOOT"}
    ref, _ = anymal_stance()
    ref.contacts.removeContact("LF_FOOT")
    ref = crocopy.DifferentialActionModelContactFwdDynamics(ref.state, ref.actuation, ref.contacts, ref.costs)
    x, u = x0.copy(), np.linspace(-1, 1, dam.nu)
    d, dr = dam.createData(), ref.createData()
    dam.calc(d, x, u)
    ref.calc(dr, x, u)
    np.testing.assert_allclose(d.xout, dr.xout, atol=1e-10)
    assert np.all(d.multibody.contacts.contacts["LF_FOOT"].f.vector == 0.0)


def test_terminal_calc_gives_cost_only():
    dam = make_dam(*CASES[0], force_cost=False)
    x, _ = random_point(dam)
    d = dam.createData()
    dam.calc(d, x)
    dam.calcDiff(d, x)
    assert np.isfinite(d.cost) and d.Lx.shape == (dam.state.ndx,)


def test_bad_input():
    model = load("anymal")
    state = crocopy.StateMultibody(model)
    fid = model.getFrameId("LF_FOOT")
    with pytest.raises(ValueError, match="id"):
        crocopy.ContactModel3D(state, model.nframes + 3, np.zeros(3), LOCAL, 12)
    with pytest.raises(ValueError, match="no frame named"):
        crocopy.ContactModel6D(state, "NO_SUCH_FOOT", pin.SE3.Identity(), LOCAL, 12)
    with pytest.raises(ValueError, match="xref"):
        crocopy.ContactModel3D(state, fid, np.zeros(4), LOCAL, 12)
    with pytest.raises(ValueError, match="gains"):
        crocopy.ContactModel3D(state, fid, np.zeros(3), LOCAL, 12, np.zeros(3))
    with pytest.raises(ValueError, match="type"):
        crocopy.ContactModel3D(state, fid, np.zeros(3), "LOCAL", 12)
    with pytest.raises(ValueError, match="pref"):
        crocopy.ContactModel6D(state, fid, np.zeros(3), LOCAL, 12)
    contacts = crocopy.ContactModelMultiple(state, 12)
    c = crocopy.ContactModel3D(state, "LF_FOOT", np.zeros(3), LOCAL, 12)
    contacts.addContact("lf", c)
    with pytest.raises(ValueError, match="already exists"):
        contacts.addContact("lf", c)
    with pytest.raises(ValueError, match="nu"):
        contacts.addContact("other", crocopy.ContactModel3D(state, fid, np.zeros(3), LOCAL))
    with pytest.raises(KeyError):
        contacts.removeContact("nope")
    with pytest.raises(KeyError):
        contacts.changeContactStatus("nope", False)
    other = crocopy.StateMultibody(load("solo12"))
    with pytest.raises(ValueError, match="another robot"):
        contacts.addContact("solo", crocopy.ContactModel3D(other, "FL_FOOT", np.zeros(3), LOCAL, 12))
    act = crocopy.ActuationModelFloatingBase(state)
    costs = crocopy.CostModelSum(state, act.nu)
    with pytest.raises(ValueError, match="contacts.nu"):
        crocopy.DifferentialActionModelContactFwdDynamics(state, act, crocopy.ContactModelMultiple(state), costs)
    dam = crocopy.DifferentialActionModelContactFwdDynamics(state, act, contacts, costs)
    d = dam.createData()
    with pytest.raises(ValueError, match="x has shape"):
        dam.calc(d, np.zeros(5), np.zeros(12))
    with pytest.raises(ValueError, match="u has shape"):
        dam.calc(d, state.zero(), np.zeros(3))
    with pytest.raises(ValueError, match="inv_damping"):
        dam.JMinvJt_damping = -1.0


def test_fddp_stance_reaches_com_target():
    """ANYmal on its four feet shifts its CoM by 4 cm forward with FDDP (contact dynamics, Euler)."""
    dam0, x0 = anymal_stance()
    state, act, nu = dam0.state, dam0.actuation, dam0.nu
    model = state.pinocchio
    com0 = pin.centerOfMass(model, model.createData(), x0[: state.nq])
    target = com0 + np.array([0.04, 0.0, 0.0])

    def node(terminal):
        costs = crocopy.CostModelSum(state, nu)
        w = np.r_[np.zeros(3), np.full(3, 10.0), np.ones(model.nv - 6), np.ones(model.nv)]
        xres = crocopy.ResidualModelState(state, x0, nu)
        costs.addCost("x", crocopy.CostModelResidual(state, crocopy.ActivationModelWeightedQuad(w**2), xres), 1.0)
        if terminal:
            costs.addCost("com", crocopy.CostModelResidual(state, crocopy.ResidualModelCoMPosition(state, target, nu)),
                          1e4)
        else:
            costs.addCost("u", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, nu)), 1e-3)
        dam = crocopy.DifferentialActionModelContactFwdDynamics(state, act, dam0.contacts, costs)
        return crocopy.IntegratedActionModelEuler(dam, 0.0 if terminal else 2e-2)

    problem = crocopy.ShootingProblem(x0, [node(False) for _ in range(25)], node(True))
    xs = [x0] * 26
    us = problem.quasiStatic(xs[:-1])
    solver = crocopy.SolverFDDP(problem)
    assert solver.solve(xs, us, 50)
    com = pin.centerOfMass(model, model.createData(), solver.xs[-1][: state.nq])
    assert np.linalg.norm(com - target) < 5e-3


def test_contacts_sharing_a_joint():
    """Two 3D contacts on one foot (same joint) plus the other foot: forces add up in ``fext``;
    with ``inv_damping`` (rank-deficient Jc) the damped KKT path still has exact derivatives
    (damping 1e-3 keeps the finite differences well conditioned)."""
    model = load("talos_legs")
    state = crocopy.StateMultibody(model)
    act = crocopy.ActuationModelFloatingBase(state)
    contacts = crocopy.ContactModelMultiple(state, act.nu)
    for name in ("left_sole_link", "leg_left_6_link"):
        contacts.addContact(name, crocopy.ContactModel3D(state, name, np.zeros(3), LWA, act.nu, [0.0, 2.0]))
    contacts.addContact("right", crocopy.ContactModel6D(state, "right_sole_link", pin.SE3.Identity(), LOCAL, act.nu))
    costs = crocopy.CostModelSum(state, act.nu)
    costs.addCost("grav", crocopy.CostModelResidual(state, crocopy.ResidualModelContactControlGrav(state, act.nu)), 1.0)
    dam = crocopy.DifferentialActionModelContactFwdDynamics(state, act, contacts, costs, 1e-3, True)
    x, u = random_point(dam, seed=9)
    d = dam.createData()
    dam.calc(d, x, u)
    dam.calcDiff(d, x, u)
    assert d.rigid is None
    cds = d.multibody.contacts.contacts
    joint = cds["left_sole_link"].joint
    assert cds["leg_left_6_link"].joint == joint
    expected = cds["left_sole_link"].fext.vector + cds["leg_left_6_link"].fext.vector
    np.testing.assert_allclose(d.multibody.contacts.fext[joint].vector, expected)
    J = fd_dam(dam, x, u)
    nv, ndx = dam.state.nv, dam.state.ndx
    assert_close(d.Fx, J[:nv, :ndx], "Fx")
    assert_close(d.Fu, J[:nv, ndx:], "Fu")
    assert_close(d.df_dx, J[nv + 1:, :ndx], "df_dx")


def test_reference_and_gain_changes_reach_both_paths():
    """Changing a contact's reference or gains after createData changes the dynamics on both paths alike."""
    fast, kkt = make_dam(*CASES[1]), make_dam(*CASES[1], kkt=True)
    x, u = random_point(fast, seed=12)
    df, dk = fast.createData(), kkt.createData()
    for step in range(3):
        if step == 1:
            for dam in (fast, kkt):
                dam.contacts.contacts["LF_FOOT"].contact.reference = np.array([0.3, 0.1, -0.2])
        if step == 2:
            for dam in (fast, kkt):
                dam.contacts.contacts["RH_FOOT"].contact.gains = np.array([7.0, 1.0])
        fast.calc(df, x, u)
        kkt.calc(dk, x, u)
        np.testing.assert_allclose(df.xout, dk.xout, atol=1e-9 * max(1.0, np.abs(dk.xout).max()))
        assert df.rigid is not None and dk.rigid is None


@pytest.mark.parametrize("typ", [LOCAL, LWA])
def test_joint_forces_are_brought_up_to_date_when_read(typ):
    """The dynamics defer the joint-frame forces; reading ``fext`` gives each contact's full update."""
    dam = make_dam("anymal", "3333", typ, [0.0, 0.0])
    x, u = random_point(dam, seed=4)
    d = dam.createData()
    dam.calc(d, x, u)
    cdata = d.multibody.contacts
    fext = cdata.fext
    reference = dam.createData().multibody.contacts.contacts
    for name, item in dam.contacts.contacts.items():
        cd, ref = cdata.contacts[name], reference[name]
        ref.pinocchio = d.pinocchio
        item.contact.updateForce(ref, cd.f.linear.copy())
        np.testing.assert_allclose(fext[cd.joint].vector, ref.fext.vector, atol=1e-12)
        np.testing.assert_allclose(cd.fext.vector, ref.fext.vector, atol=1e-12)
    x2 = x.copy()
    x2[-1] += 0.5
    dam.calc(d, x2, u)
    assert cdata.fext is fext
    assert not np.allclose(cdata.fext[cdata.contacts["LF_FOOT"].joint].vector, reference["LF_FOOT"].fext.vector)


@pytest.mark.parametrize("case", [CASES[0], CASES[4]], ids=[IDS[0], IDS[4]])
def test_rigid_calcdiff_leaves_the_kinematic_derivatives_of_the_motion(case):
    """After the constraint-dynamics ``calcDiff``, ``data.pinocchio`` holds what residuals read (joint Jacobians
    and their derivatives, velocities, accelerations): those of ``computeForwardKinematicsDerivatives`` at
    ``(q, v, xout)``, so the DAM does not call it again."""
    dam = make_dam(*case)
    x, u = random_point(dam)
    data = dam.createData()
    dam.calc(data, x, u)
    dam.calcDiff(data, x, u)
    assert data.rigid is not None
    model, pd = dam.pinocchio, data.pinocchio
    fresh = model.createData()
    pin.computeForwardKinematicsDerivatives(model, fresh, x[: model.nq], x[model.nq :], data.xout)
    for name in ("J", "dJ"):
        np.testing.assert_allclose(getattr(pd, name), getattr(fresh, name), atol=1e-10, err_msg=name)
    for name in ("ov", "oa", "v", "a"):
        for mine, ref in zip(getattr(pd, name), getattr(fresh, name)):
            np.testing.assert_allclose(mine.vector, ref.vector, atol=1e-10, err_msg=name)
    frame = model.getFrameId(FEET[case[0]][0])
    for ref_frame in (LOCAL, LWA, pin.WORLD):
        for derivatives in (pin.getFrameVelocityDerivatives, pin.getFrameAccelerationDerivatives):
            for mine, ref in zip(derivatives(model, pd, frame, ref_frame), derivatives(model, fresh, frame, ref_frame)):
                np.testing.assert_allclose(mine, ref, atol=1e-10, err_msg=derivatives.__name__)
