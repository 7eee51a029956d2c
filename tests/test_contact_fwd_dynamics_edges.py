"""Contact dynamics at the edge: no active contact and a mass matrix that cannot be inverted (a solver's
trial step that diverged) gives a non-finite acceleration for the line search to reject, not an exception."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

import crocopy


def massless_pendulum() -> pin.Model:
    model = pin.Model()
    joint = model.addJoint(0, pin.JointModelRZ(), pin.SE3.Identity(), "hinge")
    model.appendBodyToJoint(joint, pin.Inertia.Zero(), pin.SE3.Identity())
    model.addFrame(pin.Frame("tip", joint, 0, pin.SE3.Identity(), pin.FrameType.OP_FRAME))
    return model


def test_singular_inertia_without_contact_gives_nan_not_an_exception():
    state = crocopy.StateMultibody(massless_pendulum())
    actuation = crocopy.ActuationModelFull(state)
    contacts = crocopy.ContactModelMultiple(state, actuation.nu)
    contacts.addContact("tip", crocopy.ContactModel3D(state, state.pinocchio.getFrameId("tip"), np.zeros(3),
                                                       pin.LOCAL, actuation.nu), active=False)
    dam = crocopy.DifferentialActionModelContactFwdDynamics(state, actuation, contacts,
                                                            crocopy.CostModelSum(state, actuation.nu))
    data = dam.createData()
    dam.calc(data, np.zeros(2), np.ones(1))
    assert np.isnan(data.xout).all()
