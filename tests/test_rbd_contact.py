"""The compiled contact kernels (models/rbd/contact_kernel.py) give crocopy's Python contact path's numbers.

References: ``ContactModel3D``/``ContactModel6D`` ``calc``/``calcDiff`` on Pinocchio's kinematics (contact
kinematics), ``computeRNEADerivatives`` with the contact forces as ``fext`` plus ``updateRneaDiff`` (RNEA
derivatives with contact forces) and ``DifferentialActionModelContactFwdDynamics`` on its explicit KKT path
(dynamics and derivatives); every derivative is also checked against central differences of the kernels'
own values.  Errors are compared with ``tol · max(1, max |reference|)`` (:func:`test_rbd_dynamics.close`).
"""

from __future__ import annotations

import numba
import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from robots import frame
from test_rbd_dynamics import close, lowered, state

import crocopy
from crocopy.models.rbd import contact_kernel as C
from crocopy.models.rbd import dynamics_kernel as K
from crocopy.models.rbd.lowering import make_workspace

ROBOTS = ("anymal", "solo12", "talos_legs", "talos", "talos_arm", "kinova")
REFERENCES = (pin.LOCAL, pin.LOCAL_WORLD_ALIGNED)
SEEDS = st.integers(0, 2**32 - 1)
EPS = 1e-6
NO_GAINS = np.zeros(2)


def seeded(test):
    """``test(..., seed)`` for two Hypothesis seeds."""
    return settings(max_examples=2, deadline=None)(given(seed=SEEDS)(test))


def reference_placement(rng):
    """A random placement ``(R, p)``."""
    return pin.exp3(rng.uniform(-1.0, 1.0, 3)), rng.standard_normal(3)


def contact_model(model, fid, nc, reference, gains, R_ref, p_ref, nu=None):
    """crocopy's Python ``ContactModel3D``/``ContactModel6D`` with its data on a fresh ``pinocchio.Data``."""
    state_ = crocopy.StateMultibody(model)
    nu = model.nv if nu is None else nu
    if nc == 3:
        contact = crocopy.ContactModel3D(state_, fid, p_ref, reference, nu, gains)
    else:
        contact = crocopy.ContactModel6D(state_, fid, pin.SE3(R_ref, p_ref), reference, nu, gains)
    pd = model.createData()
    return contact, contact.createData(pd), pd


def contact_acceleration(rb, ws, cw, fid, nc, reference, gains, R_ref, p_ref, q, v, a):
    """``Jc a + a0`` at ``(q, v)`` from the value kernels (for finite differences)."""
    Jc, a0, acc = np.zeros((nc, rb.nv)), np.zeros(nc), np.zeros(rb.nv)
    K.forward_dynamics(rb, ws, q, v, ws.zero, acc)
    C.contact_calc(rb, ws, cw, fid, nc, int(reference), gains[0], gains[1], R_ref, p_ref, 0, Jc, a0)
    return Jc @ a + a0, Jc


def tangent_differences(model, q, v, f):
    """Central differences of ``f(q, v)`` in the tangent of ``q`` then in ``v``: ``(m, 2 nv)``."""
    cols = []
    for k in range(2 * model.nv):
        d = np.zeros(2 * model.nv)
        d[k] = EPS
        plus = f(pin.integrate(model, q, d[: model.nv]), v + d[model.nv :])
        minus = f(pin.integrate(model, q, -d[: model.nv]), v - d[model.nv :])
        cols.append((plus - minus) / (2 * EPS))
    return np.array(cols).T


@pytest.mark.parametrize("robot", ROBOTS)
@pytest.mark.parametrize("nc", (3, 6))
@seeded
def test_contact_kinematics_match_the_contact_models(robot, nc, seed):
    """``Jc``, ``a0`` (at zero acceleration) and ``∂(Jc a + a0)/∂x`` (at a random ``a``) as ``calc``/``calcDiff``."""
    model, _, rb, ws = lowered(robot)
    cw = C.make_contact_workspace(rb, nc)
    q, v, a, _ = state(model, seed)
    rng = np.random.default_rng(seed)
    fid = model.getFrameId(frame(robot))
    x = np.concatenate([q, v])
    Jc, a0, da0 = np.zeros((nc, model.nv)), np.zeros(nc), np.zeros((nc, 2 * model.nv))
    for reference in REFERENCES:
        for gains in (np.zeros(2), rng.uniform(0.5, 5.0, 2)):
            R_ref, p_ref = reference_placement(rng)
            contact, cdata, pd = contact_model(model, fid, nc, reference, gains, R_ref, p_ref)
            pin.computeForwardKinematicsDerivatives(model, pd, q, v, 0 * a)
            pin.computeJointJacobians(model, pd, q)
            pin.updateFramePlacements(model, pd)
            contact.calc(cdata, x)
            acc = np.zeros(model.nv)
            K.forward_dynamics(rb, ws, q, v, ws.zero, acc)
            C.contact_calc(rb, ws, cw, fid, nc, int(reference), gains[0], gains[1], R_ref, p_ref, 0, Jc, a0)
            close(Jc, cdata.Jc, 1e-10)
            close(a0, cdata.a0, 1e-10)
            pin.computeForwardKinematicsDerivatives(model, pd, q, v, a)
            contact.calcDiff(cdata, x)
            K.dynamics_derivatives(rb, ws, q, v, a, np.zeros((model.nv, model.nv)), np.zeros((model.nv, model.nv)))
            C.contact_calc_diff(rb, ws, cw, fid, nc, int(reference), gains[0], gains[1], R_ref, p_ref, 0, da0)
            close(da0, cdata.da0_dx, 1e-10)


@pytest.mark.parametrize("robot", ("anymal", "talos_legs", "kinova"))
@pytest.mark.parametrize("nc", (3, 6))
@seeded
def test_contact_kinematics_derivatives_by_finite_differences(robot, nc, seed):
    model, _, rb, ws = lowered(robot)
    cw = C.make_contact_workspace(rb, nc)
    q, v, a, _ = state(model, seed)
    rng = np.random.default_rng(seed)
    fid = model.getFrameId(frame(robot))
    gains = rng.uniform(0.5, 5.0, 2)
    R_ref, p_ref = reference_placement(rng)
    da0 = np.zeros((nc, 2 * model.nv))
    for reference in REFERENCES:
        args = (fid, nc, int(reference), gains, R_ref, p_ref)
        fd = tangent_differences(model, q, v, lambda q_, v_, c=args: contact_acceleration(rb, ws, cw, *c, q_, v_, a)[0])
        K.dynamics_derivatives(rb, ws, q, v, a, np.zeros((model.nv, model.nv)), np.zeros((model.nv, model.nv)))
        C.contact_calc_diff(rb, ws, cw, fid, nc, int(reference), gains[0], gains[1], R_ref, p_ref, 0, da0)
        close(da0, fd, 1e-6)


@pytest.mark.parametrize("robot", ("anymal", "solo12", "talos", "talos_arm"))
@pytest.mark.parametrize("nc", (3, 6))
@seeded
def test_rnea_derivatives_with_a_contact_force(robot, nc, seed):
    """``∂(RNEA - Jcᵀ λ)/∂q`` as Pinocchio's RNEA derivatives with ``fext`` plus crocopy's ``updateRneaDiff``,
    and as finite differences of ``RNEA(q, v, a) - Jc(q)ᵀ λ``."""
    model, _, rb, ws = lowered(robot)
    cw = C.make_contact_workspace(rb, nc)
    q, v, a, _ = state(model, seed)
    rng = np.random.default_rng(seed)
    fid = model.getFrameId(frame(robot))
    lam = rng.standard_normal(nc) * 10.0
    n = model.nv
    x = np.concatenate([q, v])
    dq, dv = np.zeros((n, n)), np.zeros((n, n))
    for reference in REFERENCES:
        state_ = crocopy.StateMultibody(model)
        contacts = crocopy.ContactModelMultiple(state_, n)
        R_ref, p_ref = reference_placement(rng)
        contact = contact_model(model, fid, nc, reference, NO_GAINS, R_ref, p_ref)[0]
        contacts.addContact("c", contact)
        pd = model.createData()
        cdata = contacts.createData(pd)
        pin.computeAllTerms(model, pd, q, v)
        pin.updateFramePlacements(model, pd)
        contacts.calc(cdata, x)
        contacts.updateForce(cdata, lam)
        pin.computeRNEADerivatives(model, pd, q, v, a, cdata.fext)
        contacts.updateRneaDiff(cdata, pd)
        K.dynamics_derivatives(rb, ws, q, v, a, dq, dv)
        C.contact_force_derivatives(rb, ws, fid, nc, int(reference), np.zeros((3, 3)), lam, 0, dq)
        close(dq, pd.dtau_dq, 1e-10)
        close(dv, pd.dtau_dv, 1e-10)

        def generalized_force(q_, v_, args=(fid, nc, reference, NO_GAINS, R_ref, p_ref)):
            Jc = contact_acceleration(rb, ws, cw, *args, q_, v_, a)[1]
            K.dynamics_derivatives(rb, ws, q_, v_, a, np.zeros((n, n)), np.zeros((n, n)))
            return ws.tau - Jc.T @ lam

        close(np.hstack([dq, dv]), tangent_differences(model, q, v, generalized_force), 1e-6)


CASES = {
    "anymal-4-lwa": ("anymal", ("LF_FOOT", "RF_FOOT", "LH_FOOT", "RH_FOOT"), 3, pin.LOCAL_WORLD_ALIGNED),
    "anymal-4-local": ("anymal", ("LF_FOOT", "RF_FOOT", "LH_FOOT", "RH_FOOT"), 3, pin.LOCAL),
    "anymal-2-world": ("anymal", ("LF_FOOT", "RH_FOOT"), 3, pin.WORLD),
    "anymal-0": ("anymal", (), 3, pin.LOCAL),
    "talos-2-6d-local": ("talos", ("left_sole_link", "right_sole_link"), 6, pin.LOCAL),
    "talos-2-6d-lwa": ("talos", ("left_sole_link", "right_sole_link"), 6, pin.LOCAL_WORLD_ALIGNED),
}


def contact_problem(case, seed, damping, with_armature):
    """crocopy's Python contact dynamics of ``CASES[case]`` (explicit KKT path, ``enable_force``) and the
    kernels' inputs: the lowered model with the dynamics' armature, ``S``, the contacts' kernel arguments and
    names in stacking order (by name)."""
    robot, feet, nc, reference = CASES[case]
    model, _, rb, _ = lowered(robot)
    rng = np.random.default_rng(seed)
    state_ = crocopy.StateMultibody(model)
    actuation = crocopy.ActuationModelFloatingBase(state_)
    contacts = crocopy.ContactModelMultiple(state_, actuation.nu)
    rows = []
    for name in feet:
        gains = rng.uniform(0.5, 5.0, 2)
        R_ref, p_ref = reference_placement(rng)
        fid = model.getFrameId(name)
        contacts.addContact(name, contact_model(model, fid, nc, reference, gains, R_ref, p_ref, actuation.nu)[0])
        rows.append((name, fid, gains, R_ref, p_ref))
    rows.sort()
    dam = crocopy.DifferentialActionModelContactFwdDynamics(
        state_, actuation, contacts, crocopy.CostModelSum(state_, actuation.nu), damping, True
    )
    dam.use_pinocchio_constraints = False
    armature = rng.uniform(0.0, 0.2, model.nv) if with_armature else np.zeros(model.nv)
    dam.armature = armature
    S = np.zeros((model.nv, actuation.nu))
    S[6:] = np.eye(actuation.nu)
    rb = rb._replace(armature=rb.armature + armature)
    kernel_contacts = [(fid, nc, int(reference), gains, R_ref, p_ref) for _, fid, gains, R_ref, p_ref in rows]
    return dam, rb, S, kernel_contacts, [row[0] for row in rows]


def contact_dynamics(rb, ws, cw, contacts, q, v, tau, damping):
    """``(a, λ, Jc, a0)`` of the contact forward dynamics from the kernels."""
    nc = sum(c[1] for c in contacts)
    a, lam, Jc, a0 = np.zeros(rb.nv), np.zeros(nc), np.zeros((nc, rb.nv)), np.zeros(nc)
    K.forward_dynamics(rb, ws, q, v, tau, a)
    row = 0
    for fid, n, reference, gains, R_ref, p_ref in contacts:
        C.contact_calc(rb, ws, cw, fid, n, reference, gains[0], gains[1], R_ref, p_ref, row, Jc, a0)
        row += n
    C.contact_forward_dynamics(rb, ws, cw, tau, Jc, a0, nc, damping, a, lam)
    return a, lam, Jc, a0


def contact_dynamics_diff(rb, ws, cw, contacts, q, v, S, a, lam, Jc):
    """``(Fx, Fu, df_dx, df_du)`` from the kernels, after :func:`contact_dynamics` at the same point."""
    n, nc = rb.nv, len(lam)
    dq, dv, da0 = np.zeros((n, n)), np.zeros((n, n)), np.zeros((nc, 2 * n))
    out = np.zeros((n, 2 * n)), np.zeros((n, S.shape[1])), np.zeros((nc, 2 * n)), np.zeros((nc, S.shape[1]))
    K.dynamics_derivatives(rb, ws, q, v, a, dq, dv)
    row = 0
    for fid, m, reference, gains, R_ref, p_ref in contacts:
        C.contact_force_derivatives(rb, ws, fid, m, reference, np.zeros((3, 3)), lam, row, dq)
        C.contact_calc_diff(rb, ws, cw, fid, m, reference, gains[0], gains[1], R_ref, p_ref, row, da0)
        row += m
    C.contact_dynamics_derivatives(rb, ws, cw, Jc, nc, dq, dv, da0, S, *out)
    return out


@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize(("damping", "with_armature"), ((0.0, False), (1e-2, True)))
@seeded
def test_contact_dynamics_match_the_python_dynamics(case, damping, with_armature, seed):
    """``a``, ``λ``, ``Fx``, ``Fu``, ``df_dx``, ``df_du`` as ``DifferentialActionModelContactFwdDynamics``."""
    dam, rb, S, contacts, names = contact_problem(case, seed, damping, with_armature)
    model = dam.state.pinocchio
    ws, cw = make_workspace(rb), C.make_contact_workspace(rb, 12)
    q, v, _, _ = state(model, seed)
    u = np.random.default_rng(seed).standard_normal(S.shape[1]) * 20.0
    x = np.concatenate([q, v])
    data = dam.createData()
    dam.calc(data, x, u)
    dam.calcDiff(data, x, u)
    a, lam, Jc, _ = contact_dynamics(rb, ws, cw, contacts, q, v, S @ u, damping)
    Fx, Fu, df_dx, df_du = contact_dynamics_diff(rb, ws, cw, contacts, q, v, S, a, lam, Jc)
    items = data.multibody.contacts.items
    ref_lam = np.concatenate([items[name].f.vector[: c[1]] for name, c in zip(names, contacts, strict=True)] or [[]])
    close(a, data.xout, 1e-10)
    close(lam, ref_lam, 1e-10)
    close(Fx, data.Fx, 1e-10)
    close(Fu, data.Fu, 1e-10)
    if contacts:
        close(df_dx, data.df_dx, 1e-10)
        close(df_du, data.df_du, 1e-10)


@pytest.mark.parametrize("case", ("anymal-4-lwa", "anymal-2-world", "talos-2-6d-lwa"))
def test_contact_dynamics_derivatives_by_finite_differences(case):
    _, rb, S, contacts, _ = contact_problem(case, 3, 1e-2, True)
    model = lowered(CASES[case][0])[0]
    ws, cw = make_workspace(rb), C.make_contact_workspace(rb, 12)
    q, v, _, _ = state(model, 3)
    u = np.random.default_rng(3).standard_normal(S.shape[1]) * 20.0
    a, lam, Jc, _ = contact_dynamics(rb, ws, cw, contacts, q, v, S @ u, 1e-2)
    Fx, Fu, df_dx, df_du = contact_dynamics_diff(rb, ws, cw, contacts, q, v, S, a, lam, Jc)

    def solution(q_, v_, u_=u):
        a_, lam_, _, _ = contact_dynamics(rb, ws, cw, contacts, q_, v_, S @ u_, 1e-2)
        return np.concatenate([a_, lam_])

    fd = tangent_differences(model, q, v, solution)
    close(np.vstack([Fx, df_dx]), fd, 1e-6)
    fd_u = np.array([(solution(q, v, u + EPS * e) - solution(q, v, u - EPS * e)) / (2 * EPS)
                     for e in np.eye(len(u))]).T
    close(np.vstack([Fu, df_du]), fd_u, 1e-6)


@numba.njit
def _node(rb, ws, cw, q, v, tau, S, fids, R_ref, p_ref, out):
    """A compiled caller, as the contact node will be: 3D LOCAL_WORLD_ALIGNED contacts with gains (2, 1)."""
    a, lam, Jc, a0, dq, dv, da0, Fx, Fu, df_dx, df_du = out
    K.forward_dynamics(rb, ws, q, v, tau, a)
    for k in range(len(fids)):
        C.contact_calc(rb, ws, cw, fids[k], 3, 2, 2.0, 1.0, R_ref, p_ref, 3 * k, Jc, a0)
    C.contact_forward_dynamics(rb, ws, cw, tau, Jc, a0, 3 * len(fids), 0.0, a, lam)
    K.dynamics_derivatives(rb, ws, q, v, a, dq, dv)
    for k in range(len(fids)):
        C.contact_force_derivatives(rb, ws, fids[k], 3, 2, R_ref, lam, 3 * k, dq)  # R_ref: unused by a 3D contact
        C.contact_calc_diff(rb, ws, cw, fids[k], 3, 2, 2.0, 1.0, R_ref, p_ref, 3 * k, da0)
    C.contact_dynamics_derivatives(rb, ws, cw, Jc, 3 * len(fids), dq, dv, da0, S, Fx, Fu, df_dx, df_du)


@numba.njit
def _repeat(rb, ws, cw, q, v, tau, S, fids, R_ref, p_ref, out, n):
    for _ in range(n):
        _node(rb, ws, cw, q, v, tau, S, fids, R_ref, p_ref, out)


def test_kernels_run_compiled_without_allocating():
    """Called from a compiled function the kernels give the Python calls' numbers, and numba's allocation
    counters grow no more for four calls than for one."""
    from numba.core.runtime import _nrt_python, rtsys

    _, rb, S, contacts, _ = contact_problem("anymal-4-lwa", 5, 0.0, False)
    R_ref, p_ref = contacts[0][4], contacts[0][5]
    contacts = [(c[0], 3, 2, np.array([2.0, 1.0]), R_ref, p_ref) for c in contacts]  # as _node's
    model = lowered("anymal")[0]
    q, v, _, _ = state(model, 5)
    tau = S @ np.random.default_rng(5).standard_normal(S.shape[1])
    n, nc = model.nv, 12
    ws, cw = make_workspace(rb), C.make_contact_workspace(rb, nc)
    out = (np.zeros(n), np.zeros(nc), np.zeros((nc, n)), np.zeros(nc), np.zeros((n, n)), np.zeros((n, n)),
           np.zeros((nc, 2 * n)), np.zeros((n, 2 * n)), np.zeros((n, S.shape[1])), np.zeros((nc, 2 * n)),
           np.zeros((nc, S.shape[1])))
    fids = np.array([c[0] for c in contacts])
    args = (rb, ws, cw, q, v, tau, S, fids, R_ref, p_ref, out)
    _repeat(*args, 1)
    a, lam, Jc, _ = contact_dynamics(rb, ws, cw, contacts, q, v, tau, 0.0)
    expected = contact_dynamics_diff(rb, ws, cw, contacts, q, v, S, a, lam, Jc)
    close(out[0], a, 1e-12)
    close(out[1], lam, 1e-12)
    for got, ref in zip(out[7:], expected, strict=True):
        close(got, ref, 1e-12)
    _nrt_python.memsys_enable_stats()
    try:
        counts = []
        for calls in (1, 4):
            before = rtsys.get_allocation_stats().alloc
            _repeat(*args, calls)
            counts.append(rtsys.get_allocation_stats().alloc - before)
    finally:
        _nrt_python.memsys_disable_stats()
    assert counts[0] == counts[1]
