"""The compiled centre of mass and its Jacobian (models/rbd/com_kernel.py) give Pinocchio's numbers."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_rbd_dynamics import close, lowered, state

from crocopy.models.rbd import dynamics_kernel as K
from crocopy.models.rbd.com_kernel import (
    center_of_mass,
    centroidal_momentum,
    centroidal_momentum_derivatives,
    com_velocity_derivatives,
)

ROBOTS = ("anymal", "solo12", "talos_legs", "talos", "talos_arm", "kinova", "panda")


@pytest.mark.parametrize("robot", ROBOTS)
@settings(max_examples=2, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_center_of_mass_and_jacobian(robot, seed):
    """As ``pin.jacobianCenterOfMass``, and the Jacobian as central differences of the kernel's own value."""
    model, data, rb, ws = lowered(robot)
    q, v, _, _ = state(model, seed)
    com, Jcom = np.zeros(3), np.zeros((3, model.nv))
    K.forward_kinematics(rb, ws, q, v)
    center_of_mass(rb, ws, com, Jcom)
    close(Jcom, pin.jacobianCenterOfMass(model, data, q), 1e-10)
    close(com, data.com[0], 1e-10)
    close(com, pin.centerOfMass(model, data, q), 1e-10)
    fd = np.zeros((3, model.nv))
    eps, c = 1e-6, np.zeros(3)
    for k in range(model.nv):
        for sign in (1.0, -1.0):
            K.forward_kinematics(rb, ws, pin.integrate(model, q, sign * eps * np.eye(model.nv)[k]), v)
            center_of_mass(rb, ws, c, np.zeros((3, model.nv)))
            fd[:, k] += sign * c / (2 * eps)
    close(Jcom, fd, 1e-7)


@pytest.mark.parametrize("robot", (*ROBOTS, "iris", "joint_chain"))
@settings(max_examples=2, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_centroidal_momentum_and_derivatives(robot, seed):
    """As ``pin.computeCentroidalMomentum`` and ``computeCentroidalDynamicsDerivatives``' ``dh_dq`` and ``Ag``; the
    ``q`` columns also as central differences of the kernel's own value."""
    model, data, rb, ws = lowered(robot)
    q, v, _, _ = state(model, seed)
    nv = model.nv
    com, Jcom, h, dh = np.zeros(3), np.zeros((3, nv)), np.zeros(6), np.zeros((6, 2 * nv))
    K.forward_kinematics(rb, ws, q, v)
    centroidal_momentum(rb, ws, com, Jcom, h)
    centroidal_momentum_derivatives(rb, ws, com, Jcom, dh)
    close(h, pin.computeCentroidalMomentum(model, data, q, v).vector, 1e-10)
    dh_dq, _, _, Ag = pin.computeCentroidalDynamicsDerivatives(model, model.createData(), q, v, np.zeros(nv))
    close(dh[:, :nv], dh_dq, 1e-9)
    close(dh[:, nv:], Ag, 1e-10)
    fd = np.zeros((6, nv))
    eps, hh = 1e-6, np.zeros(6)
    for k in range(nv):
        for sign in (1.0, -1.0):
            K.forward_kinematics(rb, ws, pin.integrate(model, q, sign * eps * np.eye(nv)[k]), v)
            centroidal_momentum(rb, ws, np.zeros(3), np.zeros((3, nv)), hh)
            fd[:, k] += sign * hh / (2 * eps)
    close(dh[:, :nv], fd, 1e-6)


@pytest.mark.parametrize("robot", (*ROBOTS, "iris", "joint_chain"))
@settings(max_examples=2, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_com_velocity_derivatives(robot, seed):
    """As ``pin.getCenterOfMassVelocityDerivatives`` after ``pin.centerOfMass(q, v)``."""
    model, data, rb, ws = lowered(robot)
    q, v, _, _ = state(model, seed)
    out = np.zeros((3, model.nv))
    K.forward_kinematics(rb, ws, q, v)
    com_velocity_derivatives(rb, ws, out)
    pin.centerOfMass(model, data, q, v)
    close(out, pin.getCenterOfMassVelocityDerivatives(model, data), 1e-10)
