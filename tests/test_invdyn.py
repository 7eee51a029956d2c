"""Inverse-dynamics DAMs (free, contact) × robot × integrator and control parametrization, against
central differences, plus their equalities checked against Pinocchio and their API edges.

Every value of a node (next state or acceleration, cost, equality ``h``) is differenced along the
tangent of ``x`` and along ``u`` (step ``H = 1e-6``) and compared with ``Fx, Fu``, ``Lx, Lu``,
``Hx, Hu`` to ``RTOL = 1e-5`` relative to the largest entry.  The cost stacks hold the residuals that
read the inverse-dynamics data (joint effort and acceleration, contact force and friction cone), so
the joint and contact data collectors are checked through them.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from robots import frame, load
from test_free_fwd_dynamics import finite_differences_terminal

import crocopy

H = 1e-6
RTOL = 1e-5
DT = 1e-2
FEET = ("LF_FOOT", "RF_FOOT", "LH_FOOT")
SOLES = ("left_sole_link", "right_sole_link")


def _thrusters(state):
    thrusters = [crocopy.Thruster(pin.SE3(np.eye(3), np.array(p)), 0.1, t)
                 for p, t in (([0.2, 0.0, 0.0], crocopy.CW), ([0.0, 0.2, 0.0], crocopy.CCW),
                              ([-0.2, 0.0, 0.0], crocopy.CW), ([0.0, -0.2, 0.0], crocopy.CCW))]
    return crocopy.ActuationModelFloatingBaseThrusters(state, thrusters)


def _costs(state, actuation, nu, fid, contact=None):
    costs = crocopy.CostModelSum(state, nu)
    items = {
        "x": crocopy.ResidualModelState(state, state.rand(), nu),
        "u": crocopy.ResidualModelControl(state, nu),
        "place": crocopy.ResidualModelFramePlacement(state, fid, pin.SE3(pin.exp3(np.ones(3)), np.ones(3)), nu),
        "vel": crocopy.ResidualModelFrameVelocity(state, fid, pin.Motion(np.arange(6.0)), pin.LOCAL_WORLD_ALIGNED, nu),
        "effort": crocopy.ResidualModelJointEffort(state, actuation, np.linspace(-1, 1, actuation.nu), nu),
        "acc": crocopy.ResidualModelJointAcceleration(state, np.linspace(-1, 1, state.nv), nu),
        "com": crocopy.ResidualModelCoMPosition(state, np.ones(3), nu),
    }
    if contact is not None:
        cfid, nc = contact
        items["force"] = crocopy.ResidualModelContactForce(state, cfid, pin.Force(np.arange(6.0)), nc, nu, False)
        if nc == 3:
            cone = crocopy.FrictionCone(np.eye(3), 0.7, 4, False)
            items["cone"] = crocopy.ResidualModelContactFrictionCone(state, cfid, cone, nu, False)
    for i, (name, residual) in enumerate(items.items()):
        costs.addCost(name, crocopy.CostModelResidual(state, residual), 0.1 * (i + 1))
    return costs


def free_dam(robot: str):
    """Free inverse dynamics of ``robot`` (``"iris"``: with thrusters) with a user constraint."""
    model = load(robot)
    state = crocopy.StateMultibody(model)
    if robot == "iris":
        actuation = _thrusters(state)
    elif model.joints[1].shortname() == "JointModelFreeFlyer":
        actuation = crocopy.ActuationModelFloatingBase(state)
    else:
        actuation = crocopy.ActuationModelFull(state)
    fid = model.getFrameId(frame(robot)) if robot != "iris" else model.nframes - 1
    constraints = crocopy.ConstraintModelManager(state, state.nv)
    bound = crocopy.ResidualModelFrameTranslation(state, fid, np.zeros(3), state.nv)
    constraints.addConstraint("box", crocopy.ConstraintModelResidual(state, bound, -np.ones(3), np.ones(3)))
    return crocopy.DifferentialActionModelFreeInvDynamics(state, actuation, _costs(state, actuation, state.nv, fid),
                                                          constraints)


def contact_dam(robot: str, inactive: bool = False):
    """Contact inverse dynamics: ANYmal on 3D feet (LOCAL and LWA, Baumgarte gains), Talos legs on 6D soles."""
    model = load(robot)
    state = crocopy.StateMultibody(model)
    actuation = crocopy.ActuationModelFloatingBase(state)
    six = robot == "talos_legs"
    names = SOLES if six else FEET
    nu = state.nv + (6 if six else 3) * len(names)
    contacts = crocopy.ContactModelMultiple(state, nu)
    rng = np.random.default_rng(7)
    frames = (pin.LOCAL, pin.LOCAL_WORLD_ALIGNED, pin.LOCAL_WORLD_ALIGNED)
    gains = ((0.0, 40.0), (10.0, 5.0), (3.0, 0.0))
    for i, name in enumerate(names):
        fid = model.getFrameId(name)
        if six:
            ref = pin.SE3(pin.exp3(0.3 * rng.normal(size=3)), rng.normal(size=3))
            contact = crocopy.ContactModel6D(state, fid, ref, frames[i], nu, np.array(gains[i]))
        else:
            contact = crocopy.ContactModel3D(state, fid, rng.normal(size=3), frames[i], nu, np.array(gains[i]))
        contacts.addContact(f"{name}_contact", contact, not (inactive and i == len(names) - 1))
    fid = model.getFrameId(names[1])
    costs = _costs(state, actuation, nu, model.getFrameId(frame(robot)), (fid, 6 if six else 3))
    return crocopy.DifferentialActionModelContactInvDynamics(state, actuation, contacts, costs)


def integrate(dam, integrator: str):
    if integrator == "none":
        return dam
    rk = {"rk2": crocopy.RKType.two, "rk3": crocopy.RKType.three, "rk4": crocopy.RKType.four}
    if integrator == "euler":
        return crocopy.IntegratedActionModelEuler(dam, DT)
    if integrator in rk:
        return crocopy.IntegratedActionModelRK(dam, rk[integrator], DT)
    if integrator == "euler-poly1":
        return crocopy.IntegratedActionModelEuler(dam, crocopy.ControlParametrizationModelPolyOne(dam.nu), DT)
    if integrator == "rk3-poly2rk3":
        control = crocopy.ControlParametrizationModelPolyTwoRK(dam.nu, crocopy.RKType.three)
        return crocopy.IntegratedActionModelRK(dam, control, crocopy.RKType.three, DT)
    raise ValueError(integrator)


def sample(model, seed: int = 0):
    rng = np.random.default_rng(seed)
    state = model.state
    m = state.pinocchio
    q = pin.integrate(m, pin.neutral(m), 0.4 * rng.normal(size=m.nv))
    return np.concatenate([q, rng.normal(size=m.nv)]), 2.0 * rng.normal(size=model.nu)


def _values(model, data, x, u):
    model.calc(data, x, u)
    out = data.xout if hasattr(data, "xout") else data.xnext
    return out.copy(), np.array([data.cost]), data.h.copy(), data.g.copy()


def numeric_jacobians(model, x, u):
    """Central differences of (dynamics, cost, h, g) along the tangent of ``x`` and along ``u``."""
    state, data = model.state, model.createData()
    base = _values(model, data, x, u)
    is_dam = not hasattr(data, "xnext")
    # pinocchio.difference of unbounded revolute joints returns 0 below ~1e-8: next states are
    # differenced from x (far away) and mapped to the tangent space at xnext by Jdiff
    Jd = None if is_dam else state.Jdiff(x, base[0])[1]
    n = state.ndx + model.nu
    cols = [[] for _ in base]
    for i in range(n):
        dx, du = np.zeros(state.ndx), np.zeros(model.nu)
        (dx if i < state.ndx else du)[i if i < state.ndx else i - state.ndx] = H
        plus = _values(model, data, state.integrate(x, dx), u + du)
        minus = _values(model, data, state.integrate(x, -dx), u - du)
        for k in range(len(base)):
            p, m = plus[k], minus[k]
            diff = p - m if k or is_dam else np.linalg.solve(Jd, state.diff(x, p) - state.diff(x, m))
            cols[k].append(diff / (2 * H))
    return [np.array(c).T.reshape(len(c[0]), n) for c in cols]


def assert_close(analytic, numeric, name):
    scale = max(1.0, float(np.abs(numeric).max())) if numeric.size else 1.0
    err = float(np.abs(analytic - numeric).max()) if numeric.size else 0.0
    assert analytic.shape == numeric.shape, name
    assert err <= RTOL * scale, f"{name}: max error {err:.3e} (scale {scale:.3e})"


INTEGRATORS = ("none", "euler", "rk2", "rk3", "rk4", "euler-poly1", "rk3-poly2rk3")
BUILDERS = {
    "free-anymal": lambda: free_dam("anymal"),
    "free-kinova": lambda: free_dam("kinova"),
    "free-iris": lambda: free_dam("iris"),
    "contact-anymal": lambda: contact_dam("anymal"),
    "contact-anymal-inactive": lambda: contact_dam("anymal", inactive=True),
    "contact-talos_legs": lambda: contact_dam("talos_legs"),
}


@pytest.mark.parametrize("integrator", INTEGRATORS)
@pytest.mark.parametrize("case", BUILDERS)
def test_derivatives_vs_finite_differences(case, integrator):
    model = integrate(BUILDERS[case](), integrator)
    x, u = sample(model)
    data = model.createData()
    model.calc(data, x, u)
    model.calcDiff(data, x, u)
    nd = model.state.ndx
    F, L, Hh, G = numeric_jacobians(model, x, u)
    assert_close(np.hstack([data.Fx, data.Fu]), F, "F")
    assert_close(np.concatenate([data.Lx, data.Lu]), L[0], "L")
    assert data.h.shape[0] == model.nh and model.nh > 0 or case == "free-kinova"
    assert_close(np.hstack([data.Hx, data.Hu]), Hh, "H")
    assert_close(np.hstack([data.Gx, data.Gu]), G, "G")
    assert F.shape[1] == nd + model.nu


@pytest.mark.parametrize("case", BUILDERS)
def test_terminal_node_has_no_internal_equality(case):
    dam = BUILDERS[case]()
    x, _ = sample(dam, 1)
    data = dam.createData()
    dam.calc(data, x)
    dam.calcDiff(data, x)
    assert dam.nh_T == 0
    _, _, grad, _ = finite_differences_terminal(dam, x)
    assert_close(data.Lx, grad, "terminal Lx")


@pytest.mark.parametrize(("robot", "unset"), [("anymal", 6), ("iris", 2)])
def test_free_invdyn_equality_is_the_unactuated_rnea_torque(robot, unset):
    """Floating base: the 6 base rows; thrusters: the 2 horizontal forces; the commands reproduce the rest."""
    dam = free_dam(robot)
    x, u = sample(dam, 2)
    data = dam.createData()
    dam.calc(data, x, u)
    model = dam.pinocchio
    tau = pin.rnea(model, model.createData(), x[: model.nq], x[model.nq :], u)
    assert dam.nu == model.nv and dam.nh == unset and list(dam.constraints.constraints) == ["box", "tau"]
    assert np.allclose(data.constraints.constraints["tau"].residual.r, tau[:unset])
    assert np.allclose(data.xout, u) and np.allclose(data.multibody.joint.a, u)
    assert np.allclose(data.multibody.actuation.tau[unset:], tau[unset:])
    if robot == "anymal":
        assert np.allclose(data.multibody.joint.tau, tau[6:])


def test_full_actuation_has_no_equality():
    dam = free_dam("kinova")
    assert dam.nh == 0 and "tau" not in dam.constraints.constraints


def test_contact_equalities_are_rnea_and_contact_accelerations():
    dam = contact_dam("anymal")
    x, u = sample(dam, 4)
    data = dam.createData()
    dam.calc(data, x, u)
    model, nv = dam.pinocchio, dam.state.nv
    q, v, a = x[: model.nq], x[model.nq :], u[:nv]
    pd = model.createData()
    pin.forwardKinematics(model, pd, q, v, a)
    pin.computeJointJacobians(model, pd, q)
    pin.updateFramePlacements(model, pd)
    tau = pin.rnea(model, model.createData(), q, v, a)
    for i, name in enumerate(sorted(f"{f}_contact" for f in FEET)):
        contact = dam.contacts.contacts[name].contact
        f = u[nv + 3 * i : nv + 3 * i + 3]
        J = pin.getFrameJacobian(model, pd, contact.id, pin.LOCAL)[:3]
        R = pd.oMf[contact.id].rotation
        Jc = J if contact.type == pin.LOCAL else R @ J
        tau -= Jc.T @ f
        acc = pin.getFrameClassicalAcceleration(model, pd, contact.id, pin.LOCAL).linear
        kp, kd = contact.gains
        acc = acc + kp * R.T @ (pd.oMf[contact.id].translation - contact.reference)
        acc = acc + kd * pin.getFrameVelocity(model, pd, contact.id, pin.LOCAL).linear
        expected = acc if contact.type == pin.LOCAL else R @ acc
        assert np.allclose(data.constraints.constraints[f"{name}_acc"].residual.r, expected), name
        assert np.allclose(data.multibody.contacts.contacts[name].f.linear, f)
    assert np.allclose(data.constraints.constraints["tau"].residual.r, tau[:6])
    assert dam.nu == nv + 9 and dam.nh == 6 + 9


def test_contact_status_switches_the_acceleration_and_force_equalities():
    dam = contact_dam("anymal")
    name = "LH_FOOT_contact"
    x, u = sample(dam, 5)
    dam.contacts.changeContactStatus(name, False)
    data = dam.createData()
    dam.calc(data, x, u)
    assert not dam.constraints.getConstraintStatus(f"{name}_acc")
    assert dam.constraints.getConstraintStatus(f"{name}_force")
    force = data.constraints.constraints[f"{name}_force"].residual.r
    assert np.allclose(force, u[dam.state.nv + 3 : dam.state.nv + 6])  # LF, LH, RF: the inactive force must vanish
    dam.contacts.changeContactStatus(name, True)
    dam.calc(data, x, u)
    assert dam.constraints.getConstraintStatus(f"{name}_acc") and dam.nh == 15


def test_quasi_static_holds_the_robot_without_unactuated_torque():
    dam = contact_dam("talos_legs")
    x, _ = sample(dam, 6)
    x[dam.state.nq :] = 0.0
    data = dam.createData()
    u = dam.quasiStatic(data, x)
    assert np.allclose(u[: dam.state.nv], 0.0)
    dam.calc(data, x, u)
    assert np.abs(data.constraints.constraints["tau"].residual.r).max() < 1e-8
    free = free_dam("anymal")
    assert np.allclose(free.quasiStatic(free.createData(), x[: 37]), 0.0)


def test_nested_names_and_standalone_residuals():
    M = crocopy.DifferentialActionModelContactInvDynamics
    F = crocopy.DifferentialActionModelFreeInvDynamics
    state = crocopy.StateMultibody(load("anymal"))
    assert F.ResidualModelActuation(state, 12).nr == 6 and F.ResidualModelActuation(state, 12).nu == 18
    r = M.ResidualModelActuation(state, 12, 9)
    assert (r.nr, r.nu) == (6, 27) and repr(r) == "ResidualModelActuation {nx=37, ndx=36, nu=27, na=12}"
    c = M.ResidualModelContact(state, "LF_FOOT", 3, 9)
    assert (c.nr, c.nu) == (3, 27) and repr(c) == "ResidualModelContact {frame=LF_FOOT, nr=3}"
    data = contact_dam("anymal").createData()
    assert isinstance(data, M.DifferentialActionDataContactInvDynamics)
    assert isinstance(data.constraints.constraints["tau"].residual, M.DifferentialActionDataContactInvDynamics
                      .ResidualDataActuation)
    assert isinstance(free_dam("anymal").createData(), F.DifferentialActionDataFreeInvDynamics)
    with pytest.raises(ValueError, match="actuation data"):
        F.ResidualModelActuation(state, 12).createData(crocopy.DataCollectorMultibody(load("anymal").createData()))


def test_bad_arguments_name_what_is_wrong():
    state = crocopy.StateMultibody(load("anymal"))
    actuation = crocopy.ActuationModelFloatingBase(state)
    with pytest.raises(ValueError, match=r"costs.nu = 12, expected 18"):
        crocopy.DifferentialActionModelFreeInvDynamics(state, actuation, crocopy.CostModelSum(state, 12))
    with pytest.raises(ValueError, match="state must be a StateMultibody"):
        crocopy.DifferentialActionModelFreeInvDynamics(crocopy.StateVector(3), actuation, crocopy.CostModelSum(state))
    with pytest.raises(ValueError, match="contacts must be a ContactModelMultiple"):
        crocopy.DifferentialActionModelContactInvDynamics(state, actuation, None, crocopy.CostModelSum(state))
    contacts = crocopy.ContactModelMultiple(state, 21)
    contacts.addContact("c", crocopy.ContactModel3D(state, "LF_FOOT", np.zeros(3), pin.LOCAL, 21))
    with pytest.raises(ValueError, match="reserved"):
        constraints = crocopy.ConstraintModelManager(state, 21)
        taken = crocopy.ConstraintModelResidual(state, crocopy.ResidualModelControl(state, 21))
        constraints.addConstraint("c_acc", taken)
        crocopy.DifferentialActionModelContactInvDynamics(state, actuation, contacts, crocopy.CostModelSum(state, 21),
                                                          constraints)


def test_contacts_added_after_construction_are_refused():
    dam = contact_dam("anymal")
    x, u = sample(dam, 9)
    data = dam.createData()
    extra = crocopy.ContactModel3D(dam.state, "RH_FOOT", np.zeros(3), pin.LOCAL, dam.nu)
    dam.contacts.addContact("RH_FOOT_contact", extra)
    with pytest.raises(ValueError, match="contact set changed"):
        dam.calc(data, x, u)


_DAMS = {name: BUILDERS[name]() for name in ("free-anymal", "contact-anymal-inactive", "contact-talos_legs")}


@settings(max_examples=30, deadline=None)
@given(name=st.sampled_from(sorted(_DAMS)), seed=st.integers(0, 2**16), scale=st.floats(0.1, 10.0))
def test_equalities_are_affine_in_the_control(name, seed, scale):
    """τ is affine in (a, f) and the contact acceleration in a: ``h(x, u) = h(x, 0) + Hu u`` exactly."""
    dam = _DAMS[name]
    x, u = sample(dam, seed)
    u = scale * u
    data = dam.createData()
    dam.calc(data, x, u)
    dam.calcDiff(data, x, u)
    h, Hu = data.h.copy(), data.Hu.copy()
    dam.calc(data, x, np.zeros(dam.nu))
    np.testing.assert_allclose(h, data.h + Hu @ u, rtol=1e-9, atol=1e-9 * max(1.0, np.abs(h).max()))


@settings(max_examples=20, deadline=None)
@given(na=st.integers(-5, 40), nc=st.integers(-3, 12))
def test_actuation_residual_dimensions(na, nc):
    state = crocopy.StateMultibody(load("anymal"))
    residual = crocopy.DifferentialActionModelContactInvDynamics.ResidualModelActuation
    if not 0 <= na <= state.nv or nc < 0:
        with pytest.raises(ValueError, match="nu .the actuation dimension.|nc must be non-negative"):
            residual(state, na, nc)
        return
    r = residual(state, na, nc)
    assert (r.nr, r.nu, r.na) == (state.nv - na, state.nv + nc, na)
