"""Small cached loaders of example-robot-data models shared by the multibody tests."""

from __future__ import annotations

import functools

import example_robot_data
import pinocchio as pin

#: Robots the multibody tests run on: legged (free flyer), humanoid legs, quadruped, arms.
ROBOTS = ("anymal", "talos_legs", "solo12", "talos_arm", "kinova")
#: Robots whose first joint is a free flyer.
FLOATING = ("anymal", "talos_legs", "solo12")


@functools.cache
def load(name: str) -> pin.Model:
    """The Pinocchio model of ``example_robot_data.load(name)`` (cached; do not modify it)."""
    return example_robot_data.load(name).model


@functools.cache
def frame(name: str) -> str:
    """A distal frame of robot ``name`` used by frame residual tests (foot or end effector)."""
    return {
        "anymal": "LF_FOOT",
        "talos_legs": "left_sole_link",
        "solo12": "FL_FOOT",
        "talos_arm": "gripper_left_joint",
        "kinova": "j2s6s200_end_effector",
        "talos": "left_sole_link",
    }[name]
