"""The compiled centre of mass and its Jacobian (models/rbd/com_kernel.py) give Pinocchio's numbers."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_rbd_dynamics import close, lowered, state

from crocopy.models.rbd import dynamics_kernel as K
from crocopy.models.rbd.com_kernel import center_of_mass

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
