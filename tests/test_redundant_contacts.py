"""Redundant contacts and impulses (issue 14, reproducer 2): least-squares KKT, derivatives against numdiff."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
import test_contacts
from robots import load
from test_contacts import assert_matches_fd
from test_impulses import assert_close as assert_close_impulse

import crocopy
from crocopy.models.contact_fwd_dynamics import turning_forces

LOCAL, LWA = pin.LOCAL, pin.LOCAL_WORLD_ALIGNED
# (robot, [(name, frame, kind)], frame type, gains, contacts dropped for the reference)
CASES = [
    ("anymal", [("a", "LF_FOOT", "3"), ("b", "LF_FOOT", "3"), ("c", "RF_FOOT", "3")], LWA, (0.0, 0.0), ["b"]),
    ("anymal", [("a", "LF_FOOT", "3"), ("b", "LF_FOOT", "3"), ("c", "RH_FOOT", "3")], LOCAL, (10.0, 5.0), ["b"]),
    ("talos_legs", [("a", "left_sole_link", "6"), ("b", "left_sole_link", "3"), ("c", "right_sole_link", "6")],
     LWA, (0.0, 0.0), ["b"]),
    ("talos_legs", [("a", "left_sole_link", "6"), ("b", "left_sole_link", "6")], LOCAL, (2.0, 1.0), ["b"]),
]
IDS = ["anymal-33-LWA", "anymal-33-LOCAL-gains", "talos-6+3-LWA", "talos-6+6-LOCAL-gains"]


def contact_dam(robot, items, typ, gains, drop=(), seed=0):
    model = load(robot)
    state = crocopy.StateMultibody(model)
    act = crocopy.ActuationModelFloatingBase(state)
    contacts = crocopy.ContactModelMultiple(state, act.nu)
    made = {}
    for name, frame, kind in items:
        key = (frame, kind)
        if key not in made:  # the same contact object when repeated, as in the reproducer
            fid = model.getFrameId(frame)
            made[key] = (crocopy.ContactModel3D(state, fid, np.zeros(3), typ, act.nu, np.array(gains)) if kind == "3"
                         else crocopy.ContactModel6D(state, fid, pin.SE3.Identity(), typ, act.nu, np.array(gains)))
        if name not in drop:
            contacts.addContact(name, made[key])
    costs = crocopy.CostModelSum(state, act.nu)
    costs.addCost("u", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, act.nu)), 0.1)
    fid = model.getFrameId(items[0][1])
    nc = 3 if items[0][2] == "3" else 6
    force = crocopy.ResidualModelContactForce(state, fid, pin.Force(np.arange(6.0)), nc, act.nu)
    costs.addCost("f", crocopy.CostModelResidual(state, force), 1e-3)
    return crocopy.DifferentialActionModelContactFwdDynamics(state, act, contacts, costs, 0.0, True)


def point(dam, seed=3):
    np.random.seed(seed)
    return dam.state.rand(), np.random.default_rng(seed).normal(size=dam.nu)


@pytest.mark.parametrize("kkt", [False, True], ids=["pinocchio", "kkt"])
@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_redundant_contacts_give_the_motion_of_the_independent_set(case, kkt):
    robot, items, typ, gains, drop = case
    dam, ref = contact_dam(robot, items, typ, gains), contact_dam(robot, items, typ, gains, drop)
    for m in (dam, ref):
        m.use_pinocchio_constraints = not kkt
    x, u = point(dam)
    if items[0][2] != items[1][2]:
        # a 6D and a 3D contact on one frame agree only at rest: the 6D drift is the spatial
        # acceleration, the 3D one the classical acceleration (least squares splits the difference)
        x[dam.state.nq:] = 0.0
    d, dr = dam.createData(), ref.createData()
    dam.calc(d, x, u)
    ref.calc(dr, x, u)
    assert d.lstsq and not dr.lstsq
    np.testing.assert_allclose(d.xout, dr.xout, rtol=1e-7, atol=1e-7)
    forces = {n: cd.f.vector.copy() for n, cd in d.multibody.contacts.contacts.items()}
    ref_forces = {n: cd.f.vector for n, cd in dr.multibody.contacts.contacts.items()}
    if items[0][2] == items[1][2]:  # the same contact twice: each carries half the force
        np.testing.assert_allclose(forces["a"], forces["b"], rtol=1e-7, atol=1e-7)
        np.testing.assert_allclose(forces["a"] + forces["b"], ref_forces["a"], rtol=1e-7, atol=1e-6)


@pytest.mark.parametrize("kkt", [False, True], ids=["pinocchio", "kkt"])
@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_redundant_contact_derivatives_match_finite_differences(case, kkt):
    dam = contact_dam(*case[:4])
    dam.use_pinocchio_constraints = not kkt
    x, u = point(dam)
    d = dam.createData()
    dam.calc(d, x, u)
    dam.calcDiff(d, x, u)
    assert np.isfinite(d.Fx).all() and np.isfinite(d.Fu).all()
    assert_matches_fd(dam, d, x, u)


def test_an_independent_contact_set_keeps_pinocchios_path():
    dam = contact_dam("anymal", [("a", "LF_FOOT", "3"), ("c", "RF_FOOT", "3")], LWA, (0.0, 0.0))
    d = dam.createData()
    dam.calc(d, *point(dam))
    assert not d.lstsq and d.rigid is not None


def impulse_model(robot, items, typ, r_coeff, drop=()):
    model = load(robot)
    state = crocopy.StateMultibody(model)
    impulses = crocopy.ImpulseModelMultiple(state)
    made = {}
    for name, frame, kind in items:
        if (frame, kind) not in made:
            cls = crocopy.ImpulseModel3D if kind == "3" else crocopy.ImpulseModel6D
            made[frame, kind] = cls(state, model.getFrameId(frame), typ)
        if name not in drop:
            impulses.addImpulse(name, made[frame, kind])
    costs = crocopy.CostModelSum(state, 0)
    costs.addCost("x", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, state.zero(), 0)), 0.1)
    costs.addCost("com", crocopy.CostModelResidual(state, crocopy.ResidualModelImpulseCoM(state)), 1.0)
    return crocopy.ActionModelImpulseFwdDynamics(state, impulses, costs, r_coeff, 0.0, True)


IMPULSE_CASES = [
    ("anymal", [("a", "LF_FOOT", "3"), ("b", "LF_FOOT", "3"), ("c", "RF_FOOT", "3")], LWA, 0.0),
    ("talos_legs", [("a", "left_sole_link", "6"), ("b", "left_sole_link", "3"), ("c", "right_sole_link", "6")],
     LOCAL, 0.5),
]


@pytest.mark.parametrize("case", IMPULSE_CASES, ids=["anymal-33", "talos-6+3"])
def test_redundant_impulses_velocity_and_derivatives(case):
    model, ref = impulse_model(*case), impulse_model(*case, drop=["b"])
    np.random.seed(5)
    x = model.state.rand()
    st, d, dr = model.state, model.createData(), ref.createData()
    u = np.zeros(0)
    model.calc(d, x, u)
    ref.calc(dr, x, u)
    assert d.lstsq and not dr.lstsq
    np.testing.assert_allclose(d.xnext, dr.xnext, rtol=1e-7, atol=1e-7)
    model.calcDiff(d, x, u)
    x0, H = d.xnext.copy(), 1e-6
    J = np.zeros((st.ndx + 1, st.ndx))
    for i in range(st.ndx):
        e = np.zeros(st.ndx)
        e[i] = H
        model.calc(d, st.integrate(x, e), u)
        plus = np.r_[st.diff(x0, d.xnext), d.cost]
        model.calc(d, st.integrate(x, -e), u)
        J[:, i] = (plus - np.r_[st.diff(x0, d.xnext), d.cost]) / (2 * H)
    model.calc(d, x, u)
    model.calcDiff(d, x, u)
    assert_close_impulse(d.Fx, J[: st.ndx], "Fx")
    assert_close_impulse(d.Lx, J[st.ndx], "Lx")


# Contact sets whose Jacobian loses rank at every configuration (no two contacts on one body): 6D contacts on the
# four 3-dof legs of ANYmal, 3D contacts on the four 2-dof legs of solo8 and "quadruped".
FEET = {"anymal": ["LF_FOOT", "RF_FOOT", "LH_FOOT", "RH_FOOT"], "solo8": ["FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT"],
        "quadruped": ["BL_contact", "BR_contact", "FL_contact", "FR_contact"], "talos_legs": ["left_sole_link",
                                                                                          "right_sole_link"]}
RANK_DEFICIENT = [("anymal", "6"), ("solo8", "3"), ("quadruped", "3")]
FULL_RANK = [("anymal", "3"), ("solo8", "3-front"), ("talos_legs", "6")]


def four_feet(robot, kind, damping=0.0, gains=(0.0, 0.0)):
    feet = FEET[robot][:2] if kind.endswith("-front") else FEET[robot]
    items = [(foot, foot, kind[0]) for foot in feet]
    dam = contact_dam(robot, items, LOCAL if kind[0] == "6" else LWA, gains)
    dam.JMinvJt_damping = damping
    return dam


@pytest.mark.parametrize(("robot", "kind"), RANK_DEFICIENT + FULL_RANK)
def test_a_contact_set_of_deficient_rank_is_redundant(robot, kind):
    dam = four_feet(robot, kind)
    assert dam._redundant_contacts() == ((robot, kind) in RANK_DEFICIENT)
    assert not four_feet(robot, kind, damping=1e-6)._redundant_contacts()
    d = dam.createData()
    dam.calc(d, *point(dam))
    assert d.lstsq == ((robot, kind) in RANK_DEFICIENT)


@pytest.mark.parametrize(("robot", "kind"), RANK_DEFICIENT)
def test_least_squares_is_the_limit_of_vanishing_damping_and_meets_the_contacts(robot, kind):
    """At rest without gains the contacts are consistent: the least-squares accelerations meet them
    (``Jc a + a0 = 0``) and are the limit of the damped KKT solution; the forces are finite."""
    dam, damped = four_feet(robot, kind), four_feet(robot, kind, damping=1e-9)
    x, u = point(dam)
    x[dam.state.nq:] = 0.0
    d, dd = dam.createData(), damped.createData()
    dam.calc(d, x, u)
    damped.calc(dd, x, u)
    assert d.lstsq and not dd.lstsq
    cd = d.multibody.contacts
    residual = cd.Jc @ d.xout + cd.a0
    assert np.abs(residual).max() <= 1e-8 * max(1.0, np.abs(d.xout).max())
    np.testing.assert_allclose(d.xout, dd.xout, rtol=1e-5, atol=1e-5 * max(1.0, np.abs(d.xout).max()))
    forces = np.concatenate([c.f.vector for c in cd.contacts.values()])
    assert np.isfinite(forces).all() and np.abs(forces).max() < 1e6


@pytest.mark.parametrize(("robot", "kind"), RANK_DEFICIENT)
def test_derivatives_of_a_rank_deficient_set_at_rest_match_finite_differences(robot, kind, monkeypatch):
    """At rest without position gains (consistent rows), every derivative is exact, the forces' configuration
    derivatives thanks to the turning of the redundant directions (:func:`turning_forces`), without which they
    would be off by O(1).  Central differences with a step of 1e-5: the accelerations reach 1e4 here and a step
    of 1e-6 leaves 2e-5 of round-off."""
    monkeypatch.setattr(test_contacts, "H", 1e-5)
    dam = four_feet(robot, kind)
    d = dam.createData()
    x, u = point(dam)
    rng = np.random.default_rng(3)
    for _ in range(10):  # a posture where the rank is the generic one: where it drops further, the forces are not
        x[dam.state.nq:] = 0.0  # differentiable (state.rand() of "quadruped" draws such postures)
        dam.calc(d, x, u)
        if np.linalg.matrix_rank(d.multibody.contacts.Jc, 1e-9) == dam._generic_rank():
            break
        x = np.r_[pin.integrate(dam.pinocchio, pin.neutral(dam.pinocchio), rng.uniform(-1.0, 1.0, dam.state.nv)),
                  np.zeros(dam.state.nv)]
    assert d.lstsq and np.linalg.matrix_rank(d.multibody.contacts.Jc, 1e-9) == dam._generic_rank()
    dam.calcDiff(d, x, u)
    assert_matches_fd(dam, d, x, u)
    pd = d.pinocchio
    turning = turning_forces(dam.pinocchio, pd, x[:dam.state.nq], dam.contacts._active, d.multibody.contacts.Jc,
                             d.lam)
    assert np.abs(turning).max() > 1e-1


def contact_problem(robot, kind, T=6):
    """Standing still on four feet, a control cost only (the force residual of :func:`contact_dam` has no compiled
    form)."""
    dam, last = four_feet(robot, kind, gains=(0.0, 20.0)), four_feet(robot, kind)
    for m in (dam, last):
        m.costs.removeCost("f")
    state = dam.state
    q0 = load(robot).referenceConfigurations["standing"] if "standing" in load(robot).referenceConfigurations \
        else pin.neutral(dam.pinocchio)
    x0 = np.concatenate([q0, np.zeros(state.nv)])
    running = crocopy.IntegratedActionModelEuler(dam, 0.01)
    terminal = crocopy.IntegratedActionModelEuler(last, 0.0)
    return crocopy.ShootingProblem(x0, [running] * T, terminal), running


@pytest.mark.skipif(not crocopy.kernels_enabled(), reason="compiled nodes need numba")
@pytest.mark.parametrize(("robot", "kind"), RANK_DEFICIENT)
def test_a_rank_deficient_set_solves_alike_with_and_without_kernels(robot, kind):
    from node_checks import make_solver

    problem, running = contact_problem(robot, kind)
    assert running._compiled_node(running.createData(), False, {}) is None
    damped, damped_running = contact_problem(robot, kind)
    damped_running.differential.JMinvJt_damping = 1e-6
    assert damped_running._compiled_node(damped_running.createData(), False, {}) is not None
    results = []
    for compiled in (True, False):
        s = make_solver("SolverFDDP", problem, compiled)
        solved = s.solve([], [], 10)
        results.append((solved, s.iter, s.reason, s.cost))
    assert results[0][:3] == results[1][:3]
    assert results[0][3] == pytest.approx(results[1][3], rel=1e-8, abs=1e-14)
    assert np.isfinite(results[0][3]) and results[0][3] < 1e3
