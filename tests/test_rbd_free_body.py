"""One body on a free flyer (a quadrotor): the dynamics kernels' joint-frame path gives Pinocchio's numbers.

``dynamics_kernel.forward_dynamics`` and ``rnea_derivatives`` take the joint frame (``free_body_kernel``: ``S = I``,
constant ``M``) when the model is a single body on a free flyer.  The robots of ``tests/test_rbd_dynamics.py`` cover
iris (identity joint placement, standard gravity, no armature); here the cases that path must carry besides: a joint
placement that is not the identity, an armature, a gravity with an angular part (in the forward dynamics: Pinocchio's
derivatives take a linear one), and the workspace fields the contact kernels read afterwards (``oa`` at zero joint
acceleration, ``tau = b``), generated from Hypothesis seeds.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from hypothesis import given, settings
from hypothesis import strategies as st

from crocopy.models.rbd import dynamics_kernel as K
from crocopy.models.rbd import free_body_kernel
from crocopy.models.rbd.lowering import lower_model, make_workspace


def random_body(seed: int):
    """A random single body on a free flyer: joint placement, inertia, armature and 6D gravity from ``seed``."""
    rng = np.random.default_rng(seed)
    model = pin.Model()
    placement = pin.SE3(pin.exp3(rng.uniform(-2.0, 2.0, 3)), rng.uniform(-1.0, 1.0, 3))
    joint = model.addJoint(0, pin.JointModelFreeFlyer(), placement, "base")
    A = rng.standard_normal((3, 3))
    inertia = pin.Inertia(rng.uniform(0.5, 3.0), rng.uniform(-0.5, 0.5, 3), A @ A.T + np.eye(3))
    model.appendBodyToJoint(joint, inertia, pin.SE3.Identity())
    model.armature = rng.uniform(0.0, 0.5, 6) * (rng.uniform(size=6) < 0.5)
    model.gravity = pin.Motion(rng.uniform(-10.0, 10.0, 6))
    q = pin.integrate(model, pin.neutral(model), rng.uniform(-np.pi, np.pi, 6))
    v, a, tau = (rng.standard_normal(6) for _ in range(3))
    return model, q, v, a, tau


def close(x, ref, tol=1e-9):
    scale = max(1.0, float(np.abs(ref).max()))
    assert float(np.abs(np.asarray(x) - ref).max()) <= tol * scale


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_free_body_dynamics_and_derivatives_equal_pinocchio(seed):
    model, q, v, a, tau = random_body(seed)
    data = model.createData()
    rb = lower_model(model)
    ws = make_workspace(rb)
    assert free_body_kernel.free_body(rb)
    acc, Minv = np.zeros(6), np.zeros((6, 6))
    K.forward_dynamics(rb, ws, q, v, tau, acc)
    K.mass_inverse(rb.dof_parent, ws.L, ws.dinv, Minv)
    M = pin.crba(model, data, q)
    M = np.triu(M) + np.triu(M, 1).T
    close(ws.M, M)
    close(acc, pin.aba(model, data, q, v, tau), 1e-8)
    close(ws.tau, pin.rnea(model, data, q, v, np.zeros(6)))  # b, read by the contact dynamics
    pin.forwardKinematics(model, data, q, v, np.zeros(6))
    close(ws.oa[1], data.oMi[1].act(data.a[1]).vector - model.gravity.vector)  # oa at zero joint acceleration
    close(Minv, np.linalg.inv(M), 1e-8)
    model.gravity = pin.Motion(model.gravity.linear, np.zeros(3))  # Pinocchio's derivatives take a linear gravity
    rb = lower_model(model)
    dq, dv = np.zeros((6, 6)), np.zeros((6, 6))
    K.dynamics_derivatives(rb, ws, q, v, a, dq, dv)
    pin.computeRNEADerivatives(model, data, q, v, a)
    close(dq, data.dtau_dq)
    close(dv, data.dtau_dv)
    close(ws.tau, pin.rnea(model, data, q, v, a))
    pin.forwardKinematics(model, data, q, v, a)
    close(ws.oa[1], data.oMi[1].act(data.a[1]).vector - model.gravity.vector)
