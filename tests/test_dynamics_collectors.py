"""Residuals that read the data collector, under every dynamics kind: the value is the quantity the
residual names (computed here independently with Pinocchio), it moves with ``x`` and ``u``, and its
Jacobians match central differences of the values computed by the whole action model.

A residual stuck at ``-ref`` with zero Jacobians passes a numerical-differentiation check, so the
values are checked against the physics, not only against themselves.  Dynamics kinds: free, contact
(Pinocchio's constraint path and the explicit KKT path) and impulse.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from robots import load

import crocopy

H = 1e-6
RTOL = 1e-5
FEET = ("LF_FOOT", "RH_FOOT")
KINDS = ("free", "contact-pinocchio", "contact-kkt", "impulse")
#: residuals whose value the collector supplies, by the dynamics kinds that provide it
COLLECTOR_RESIDUALS = {
    "joint_effort": ("free", "contact-pinocchio", "contact-kkt"),
    "joint_acceleration": ("free", "contact-pinocchio", "contact-kkt"),
    "control_grav": ("free", "contact-pinocchio", "contact-kkt"),
    "com": KINDS,
    "centroidal": KINDS,
    "frame_velocity": KINDS,
    "contact_force": ("contact-pinocchio", "contact-kkt", "impulse"),
    "impulse_com": ("impulse",),
    "contact_control_grav": ("contact-pinocchio", "contact-kkt"),
}
CASES = [(name, kind) for name, kinds in COLLECTOR_RESIDUALS.items() for kind in kinds]


def make_residual(name: str, state, actuation, nu: int, rng: np.random.Generator):
    fid = state.pinocchio.getFrameId(FEET[0])
    if name == "joint_effort":
        return crocopy.ResidualModelJointEffort(state, actuation, rng.normal(size=actuation.nu), nu)
    if name == "joint_acceleration":
        return crocopy.ResidualModelJointAcceleration(state, rng.normal(size=state.nv), nu)
    if name == "control_grav":
        return crocopy.ResidualModelControlGrav(state, nu)
    if name == "com":
        return crocopy.ResidualModelCoMPosition(state, rng.normal(size=3), nu)
    if name == "centroidal":
        return crocopy.ResidualModelCentroidalMomentum(state, rng.normal(size=6), nu)
    if name == "frame_velocity":
        return crocopy.ResidualModelFrameVelocity(state, fid, pin.Motion(rng.normal(size=6)), pin.WORLD, nu)
    if name == "contact_force":
        return crocopy.ResidualModelContactForce(state, fid, pin.Force(rng.normal(size=6)), 3, nu)
    if name == "contact_control_grav":
        return crocopy.ResidualModelContactControlGrav(state, nu)
    return crocopy.ResidualModelImpulseCoM(state)


def make_model(name: str, kind: str):
    """The action model of ``kind`` on ANYmal with one cost ``r`` on residual ``name``."""
    model = load("anymal")
    state = crocopy.StateMultibody(model)
    actuation = crocopy.ActuationModelFloatingBase(state)
    nu = 0 if kind == "impulse" else actuation.nu
    costs = crocopy.CostModelSum(state, nu)
    costs.addCost("r", crocopy.CostModelResidual(state, make_residual(name, state, actuation, nu,
                                                                      np.random.default_rng(5))), 1.0)
    if kind == "free":
        return crocopy.DifferentialActionModelFreeFwdDynamics(state, actuation, costs)
    if kind == "impulse":
        impulses = crocopy.ImpulseModelMultiple(state)
        for foot in FEET:
            impulses.addImpulse(foot, crocopy.ImpulseModel3D(state, model.getFrameId(foot), pin.LOCAL))
        return crocopy.ActionModelImpulseFwdDynamics(state, impulses, costs, 0.0, 0.0, True)
    contacts = crocopy.ContactModelMultiple(state, nu)
    for foot in FEET:
        contacts.addContact(foot, crocopy.ContactModel3D(state, model.getFrameId(foot), np.zeros(3), pin.LOCAL, nu,
                                                         np.array([0.0, 20.0])))
    dam = crocopy.DifferentialActionModelContactFwdDynamics(state, actuation, contacts, costs, 0.0, True)
    dam.use_pinocchio_constraints = kind == "contact-pinocchio"
    return dam


def sample(state, nu: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    q = pin.integrate(state.pinocchio, pin.neutral(state.pinocchio), 0.3 * rng.normal(size=state.nv))
    return np.concatenate([q, rng.normal(size=state.nv)]), rng.normal(size=nu)


def expected(name: str, residual, dam, data, x: np.ndarray, u: np.ndarray) -> np.ndarray:
    """The residual's value computed from ``x``, ``u`` and the model's dynamics output, not from its data."""
    model = dam.state.pinocchio
    pd = model.createData()
    q, v = x[: model.nq], x[model.nq :]
    if name == "joint_effort":
        return u - residual.reference
    if name == "joint_acceleration":
        return data.xout - residual.reference
    if name == "control_grav":
        return np.concatenate([np.zeros(6), u]) - pin.computeGeneralizedGravity(model, pd, q)
    if name == "com":
        return pin.centerOfMass(model, pd, q) - residual.reference
    if name == "impulse_com":
        return pin.jacobianCenterOfMass(model, pd, q) @ (data.xnext[model.nq :] - v)
    if name == "centroidal":
        return pin.computeCentroidalMomentum(model, pd, q, v).vector - residual.reference
    if name == "frame_velocity":
        pin.forwardKinematics(model, pd, q, v)
        return (pin.getFrameVelocity(model, pd, residual.id, pin.WORLD) - residual.reference).vector
    # the contact forces (LOCAL frames) from Pinocchio's own contact solver
    fid = model.getFrameId(FEET[0])
    cms = [pin.RigidConstraintModel(pin.ContactType.CONTACT_3D, model, model.frames[model.getFrameId(f)].parentJoint,
                                    model.frames[model.getFrameId(f)].placement, pin.LOCAL) for f in FEET]
    for c in cms:
        gains = c.m_baumgarte_parameters
        gains.Kd = gains.Kd * 0.0 + 20.0
        c.m_baumgarte_parameters = gains
    cds = [c.createData() for c in cms]
    prox = pin.ProximalSettings(1e-14, 0.0, 1)
    pin.initConstraintDynamics(model, pd, cms, cds)
    if isinstance(dam, crocopy.ActionModelImpulseFwdDynamics):
        pin.impulseDynamics(model, pd, q, v, cms, cds, 0.0, prox)
        force = pd.impulse_c[:3]
    else:
        tau = np.concatenate([np.zeros(6), u])
        pin.constraintDynamics(model, pd, q, v, tau, cms, cds, prox)
        force = pd.lambda_c[:3]
    assert model.frames[fid].parentJoint == cms[0].joint1_id
    if name == "contact_control_grav":  # u - (g(q) - Σ Jcᵀ f): the contact forces as joint forces
        fext = [pin.Force.Zero() for _ in range(model.njoints)]
        for i, c in enumerate(cms):
            fext[c.joint1_id] += c.joint1_placement.act(pin.Force(pd.lambda_c[3 * i : 3 * i + 3], np.zeros(3)))
        return tau - pin.computeStaticTorque(model, model.createData(), q, fext)
    return np.concatenate([force, np.zeros(3)])[: residual.nr] - residual.reference.vector[: residual.nr]


def evaluate(dam, data, x, u):
    if isinstance(dam, crocopy.ActionModelImpulseFwdDynamics):
        dam.calc(data, x)
        return
    dam.calc(data, x, u)


@pytest.mark.parametrize("name,kind", CASES, ids=[f"{n}-{k}" for n, k in CASES])
def test_collector_residual_is_the_named_quantity(name, kind):
    dam = make_model(name, kind)
    nu = dam.nu
    residual = dam.costs.costs["r"].cost.residual
    data = dam.createData()
    values = []
    for seed in (1, 2):
        x, u = sample(dam.state, nu, seed)
        evaluate(dam, data, x, u)
        r = data.costs.costs["r"].residual.r.copy()
        want = expected(name, residual, dam, data, x, u)
        assert np.abs(r - want).max() <= 1e-8 * max(1.0, np.abs(want).max()), f"{name} under {kind}: {r} != {want}"
        values.append(r)
    assert np.abs(values[0] - values[1]).max() > 1e-3, f"{name} under {kind} does not move with x and u"


@pytest.mark.parametrize("name,kind", CASES, ids=[f"{n}-{k}" for n, k in CASES])
def test_collector_residual_jacobians(name, kind):
    dam = make_model(name, kind)
    state, nu = dam.state, dam.nu
    data = dam.createData()
    x, u = sample(state, nu, 3)
    evaluate(dam, data, x, u)
    if isinstance(dam, crocopy.ActionModelImpulseFwdDynamics):
        dam.calcDiff(data, x)
    else:
        dam.calcDiff(data, x, u)
    rdata = data.costs.costs["r"].residual
    Rx, Ru = rdata.Rx.copy(), rdata.Ru.copy()
    probe = dam.createData()

    def r(dx: np.ndarray, du: np.ndarray) -> np.ndarray:
        evaluate(dam, probe, state.integrate(x, dx), u + du)
        return probe.costs.costs["r"].residual.r.copy()

    n = state.ndx + nu
    J = np.zeros((Rx.shape[0], n))
    for i in range(n):
        e = np.zeros(n)
        e[i] = H
        J[:, i] = (r(e[: state.ndx], e[state.ndx :]) - r(-e[: state.ndx], -e[state.ndx :])) / (2 * H)
    assert np.abs(J).max() > 1e-3, f"{name} under {kind} has a constant value"
    scale = max(1.0, np.abs(J).max())
    assert np.abs(np.hstack([Rx, Ru]) - J).max() <= RTOL * scale, f"{name} under {kind}: Jacobian off"


@pytest.mark.parametrize("name", ["joint_effort", "joint_acceleration", "control_grav", "contact_control_grav"])
def test_residuals_needing_joints_or_actuation_are_refused_under_impulse_dynamics(name):
    """An impulse node has no control, actuation or joint data (as in Crocoddyl): a clear error."""
    with pytest.raises(ValueError, match="collector"):
        make_model(name, "impulse").createData()
