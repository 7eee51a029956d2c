"""The joint codes of a lowered model cover the robots' configuration and tangent spaces exactly once."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from crocopy.models.rbd.joint_types import NQ, NV, NotLowerable, joint_arrays

example_robot_data = pytest.importorskip("example_robot_data")


@pytest.mark.parametrize("robot", ["iris", "double_pendulum", "kinova", "panda", "anymal", "talos"])
def test_joint_arrays_cover_q_and_v(robot):
    model = example_robot_data.load(robot).model
    jtype, idx_q, idx_v, axis = joint_arrays(model)
    assert jtype[0] == -1
    q_seen, v_seen = np.zeros(model.nq, dtype=int), np.zeros(model.nv, dtype=int)
    for i in range(1, model.njoints):
        q_seen[idx_q[i]: idx_q[i] + NQ[jtype[i]]] += 1
        v_seen[idx_v[i]: idx_v[i] + NV[jtype[i]]] += 1
        if jtype[i] != 0:
            assert np.linalg.norm(axis[i]) == pytest.approx(1.0)
    assert (q_seen == 1).all() and (v_seen == 1).all()


def test_unaligned_axis_and_unsupported_joint():
    model = pin.Model()
    model.addJoint(0, pin.JointModelRevoluteUnaligned(0.0, 0.6, 0.8), pin.SE3.Identity(), "hinge")
    assert np.allclose(joint_arrays(model)[3][1], [0.0, 0.6, 0.8])
    model.addJoint(1, pin.JointModelSpherical(), pin.SE3.Identity(), "ball")
    with pytest.raises(NotLowerable, match="'ball' is a JointModelSpherical"):
        joint_arrays(model)
