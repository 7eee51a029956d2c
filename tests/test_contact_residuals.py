"""Contact residuals and cones: values, derivatives against finite differences, bad input.

Force residuals depend on ``x`` and ``u`` through the contact dynamics, so their Jacobians are
checked by central differences of the residual computed by the whole action model (step
``H = 1e-6``, tolerance ``RTOL = 1e-5`` relative to the largest entry).
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
ROT = pin.rpy.rpyToMatrix(0.3, -0.2, 0.5)
BOX = np.array([0.2, 0.1])


def residuals(state, fid, nc, nu):
    """Name → residual model for a contact of dimension ``nc`` on frame ``fid``."""
    res = {
        "force": crocopy.ResidualModelContactForce(state, fid, pin.Force(np.arange(1.0, 7.0)), nc, nu),
        "friction": crocopy.ResidualModelContactFrictionCone(state, fid, crocopy.FrictionCone(ROT, 0.7, 6), nu),
        "grav": crocopy.ResidualModelContactControlGrav(state, nu),
    }
    if nc == 6:
        res["wrench"] = crocopy.ResidualModelContactWrenchCone(state, fid, crocopy.WrenchCone(ROT, 0.6, BOX), nu)
        res["cop"] = crocopy.ResidualModelContactCoPPosition(state, fid, crocopy.CoPSupport(ROT, BOX), nu)
    return res


CASES = [("anymal", "LF_FOOT", 3, LOCAL), ("solo12", "FL_FOOT", 3, LWA), ("talos_legs", "left_sole_link", 6, LWA),
         ("talos_legs", "right_sole_link", 6, LOCAL)]
IDS = [f"{r}-{n}D-{'LWA' if t == LWA else 'LOCAL'}" for r, _, n, t in CASES]


def make_dam(robot, frame, nc, typ):
    model = load(robot)
    state = crocopy.StateMultibody(model)
    act = crocopy.ActuationModelFloatingBase(state)
    contacts = crocopy.ContactModelMultiple(state, act.nu)
    fid = model.getFrameId(frame)
    cls = crocopy.ContactModel3D if nc == 3 else crocopy.ContactModel6D
    ref = np.zeros(3) if nc == 3 else pin.SE3.Identity()
    contacts.addContact("c", cls(state, fid, ref, typ, act.nu, np.array([1.0, 2.0])))
    costs = crocopy.CostModelSum(state, act.nu)
    for name, r in residuals(state, fid, nc, act.nu).items():
        costs.addCost(name, crocopy.CostModelResidual(state, r), 1.0)
    return crocopy.DifferentialActionModelContactFwdDynamics(state, act, contacts, costs, 0.0, True)


def assert_close(A, B, name):
    scale = max(1.0, np.abs(B).max())
    err = np.abs(A - B).max()
    assert err <= RTOL * scale, f"{name}: max error {err:.3e} (scale {scale:.3e})"


@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_force_residual_derivatives(case):
    dam = make_dam(*case)
    np.random.seed(11)
    x, u = dam.state.rand(), np.random.default_rng(3).normal(size=dam.nu)
    st, d = dam.state, dam.createData()
    names = [n for n in dam.costs.costs if n != "grav"]
    n = st.ndx + dam.nu

    def r_all(dx, du):
        dam.calc(d, st.integrate(x, dx), u + du)
        return np.concatenate([d.costs.costs[k].residual.r for k in names])

    J = np.zeros((sum(dam.costs.costs[k].cost.residual.nr for k in names), n))
    for i in range(n):
        e = np.zeros(n)
        e[i] = H
        J[:, i] = (r_all(e[: st.ndx], e[st.ndx:]) - r_all(-e[: st.ndx], -e[st.ndx:])) / (2 * H)
    dam.calc(d, x, u)
    dam.calcDiff(d, x, u)
    i = 0
    for k in names:
        rd = d.costs.costs[k].residual
        assert_close(rd.Rx, J[i:i + rd.r.size, : st.ndx], f"{k}.Rx")
        assert_close(rd.Ru, J[i:i + rd.r.size, st.ndx:], f"{k}.Ru")
        i += rd.r.size
    cd = d.multibody.contacts.contacts["c"]
    f = cd.f.vector
    np.testing.assert_allclose(d.costs.costs["force"].residual.r, (f - np.arange(1.0, 7.0))[: case[2]])
    np.testing.assert_allclose(d.costs.costs["friction"].residual.r, dam.costs.costs["friction"].cost.residual
                               .reference.A @ f[:3])


@pytest.mark.parametrize("case", CASES[:3], ids=IDS[:3])
def test_contact_control_grav(case):
    """r = τ - g(q) + Σ Jᵀ f; its Jacobians follow the contact forces as they move with x and u."""
    dam = make_dam(*case)
    np.random.seed(5)
    x, u = dam.state.rand(), np.random.default_rng(5).normal(size=dam.nu)
    st, d = dam.state, dam.createData()
    dam.calc(d, x, u)
    dam.calcDiff(d, x, u)
    rd = d.costs.costs["grav"].residual
    model, nq = st.pinocchio, st.nq
    cd = d.multibody.contacts.contacts["c"]
    pdata = model.createData()
    g = pin.computeGeneralizedGravity(model, pdata, x[:nq])
    pin.computeJointJacobians(model, pdata, x[:nq])
    pin.updateFramePlacements(model, pdata)
    Jc = pin.getFrameJacobian(model, pdata, cd.frame, case[3])[: case[2]]
    expected = d.multibody.actuation.tau - g + Jc.T @ cd.f.vector[: case[2]]
    np.testing.assert_allclose(rd.r, expected, atol=1e-9 * max(1.0, np.abs(expected).max()))
    probe = dam.createData()
    n = st.ndx + dam.nu
    J = np.zeros((st.nv, n))
    for i in range(n):
        e = np.zeros(n)
        e[i] = H
        dam.calc(probe, st.integrate(x, e[: st.ndx]), u + e[st.ndx :])
        rp = probe.costs.costs["grav"].residual.r.copy()
        dam.calc(probe, st.integrate(x, -e[: st.ndx]), u - e[st.ndx :])
        J[:, i] = (rp - probe.costs.costs["grav"].residual.r) / (2 * H)
    assert_close(rd.Rx, J[:, : st.ndx], "Rx")
    assert_close(rd.Ru, J[:, st.ndx :], "Ru")


def test_friction_cone_geometry():
    cone = crocopy.FrictionCone(np.eye(3), 0.5, 4, True, 2.0, 50.0)
    assert cone.A.shape == (5, 3)
    mu = 0.5 * np.cos(np.pi / 4)
    np.testing.assert_allclose(cone.A[0], [1.0, 0.0, -mu])
    np.testing.assert_array_equal(cone.lb, [-np.inf] * 4 + [2.0])
    np.testing.assert_array_equal(cone.ub, [0.0] * 4 + [50.0])
    inside, outside = np.array([0.1, 0.1, 10.0]), np.array([8.0, 0.0, 10.0])
    assert np.all(cone.A @ inside <= cone.ub) and np.all(cone.A @ inside >= cone.lb)
    assert np.any(cone.A @ outside > cone.ub)
    rotated = crocopy.FrictionCone(ROT, 0.5, 4, True, 2.0, 50.0)
    np.testing.assert_allclose(rotated.A @ (ROT @ outside), cone.A @ outside, atol=1e-12)
    outer = crocopy.FrictionCone(np.eye(3), 0.5, 4, False)
    np.testing.assert_allclose(outer.A[0], [1.0, 0.0, -0.5])


def test_wrench_cone_and_cop_geometry():
    wc = crocopy.WrenchCone(np.eye(3), 0.7, BOX, 4, True, 0.0, 100.0)
    assert wc.A.shape == (17, 6) and wc.lb[4] == 0.0 and wc.ub[4] == 100.0
    centred = np.array([0.0, 0.0, 50.0, 0.0, 0.0, 0.0])
    assert np.all(wc.A @ centred <= wc.ub + 1e-12)
    off_box = np.array([0.0, 0.0, 50.0, 0.0, 0.2 * 50.0, 0.0])
    cop = crocopy.CoPSupport(np.eye(3), BOX)
    assert np.any(cop.A @ off_box > 0.0) and np.any(wc.A @ off_box > wc.ub)
    cop_r = crocopy.CoPSupport(ROT, BOX)
    w_r = np.r_[ROT @ off_box[:3], ROT @ off_box[3:]]
    np.testing.assert_allclose(cop_r.A @ w_r, cop.A @ off_box, atol=1e-12)


def test_bad_input():
    model = load("anymal")
    state = crocopy.StateMultibody(model)
    fid = model.getFrameId("LF_FOOT")
    with pytest.raises(ValueError, match="nf"):
        crocopy.FrictionCone(np.eye(3), 0.7, 3)
    with pytest.raises(ValueError, match="mu"):
        crocopy.FrictionCone(np.eye(3), -0.1)
    with pytest.raises(ValueError, match="R"):
        crocopy.FrictionCone(np.ones((3, 3)), 0.7)
    with pytest.raises(ValueError, match="min_nforce"):
        crocopy.FrictionCone(np.eye(3), 0.7, 4, True, 10.0, 1.0)
    with pytest.raises(ValueError, match="box"):
        crocopy.WrenchCone(np.eye(3), 0.7, np.array([0.1, 0.2, 0.3]))
    with pytest.raises(ValueError, match="nc"):
        crocopy.ResidualModelContactForce(state, fid, pin.Force.Zero(), 4, 12)
    with pytest.raises(ValueError, match="fref"):
        crocopy.ResidualModelContactForce(state, fid, np.zeros(6), 3, 12)
    with pytest.raises(ValueError, match="FrictionCone"):
        crocopy.ResidualModelContactFrictionCone(state, fid, crocopy.WrenchCone(np.eye(3), 0.7, BOX), 12)
    with pytest.raises(ValueError, match="id"):
        crocopy.ResidualModelContactForce(state, 10_000, pin.Force.Zero(), 3, 12)
    dam = make_dam("anymal", "LF_FOOT", 3, LOCAL)
    d = dam.createData()
    elsewhere = crocopy.ResidualModelContactForce(state, model.getFrameId("RH_FOOT"), pin.Force.Zero(), 3, 12)
    with pytest.raises(ValueError, match="no contact or impulse on frame"):
        elsewhere.createData(d.multibody)
    wrench = crocopy.ResidualModelContactWrenchCone(state, fid, crocopy.WrenchCone(np.eye(3), 0.7, BOX), 12)
    with pytest.raises(ValueError, match="dimension 3"):
        wrench.createData(d.multibody)
    with pytest.raises(ValueError, match="contacts or impulses"):
        elsewhere.createData(crocopy.DataCollectorMultibody(model.createData()))
