"""Small cached loaders of example-robot-data models shared by the multibody tests."""

from __future__ import annotations

import functools

import example_robot_data
import numpy as np
import pinocchio as pin

#: Robots the multibody tests run on: legged (free flyer), humanoid legs, quadruped, arms.
ROBOTS = ("anymal", "talos_legs", "solo12", "talos_arm", "kinova")
#: Robots whose first joint is a free flyer.
FLOATING = ("anymal", "talos_legs", "solo12")


JOINT_CHAIN = "joint_chain"
"""The name :func:`load` gives :func:`joint_chain`."""


@functools.cache
def load(name: str) -> pin.Model:
    """The Pinocchio model of ``example_robot_data.load(name)``, or :func:`joint_chain` for :data:`JOINT_CHAIN` (cached;
    do not modify it)."""
    if name == JOINT_CHAIN:
        return joint_chain()
    return example_robot_data.load(name).model


def joint_chain(seed: int = 4) -> pin.Model:
    """A free flyer carrying a chain of the joint types the compiled kernels lower besides the revolute and prismatic
    ones (spherical, planar, translation, helical on an axis and unaligned), each with a random placement, body and
    armature, and a frame ``tip`` at its end."""
    rng = np.random.default_rng(seed)
    model = pin.Model()
    joints = [pin.JointModelFreeFlyer(), pin.JointModelSpherical(), pin.JointModelPlanar(), pin.JointModelHX(0.2),
              pin.JointModelTranslation(), pin.JointModelHelicalUnaligned(np.array([0.0, 0.6, 0.8]), -0.15),
              pin.JointModelRY(), pin.JointModelHZ(0.05)]
    parent = 0
    for n, joint in enumerate(joints):
        placement = pin.SE3(pin.exp3(rng.uniform(-1.0, 1.0, 3)), rng.uniform(-0.2, 0.2, 3))
        parent = model.addJoint(parent, joint, placement, f"joint_{n}")
        body = pin.Inertia(rng.uniform(0.5, 2.0), rng.uniform(-0.1, 0.1, 3), np.diag(rng.uniform(0.01, 0.1, 3)))
        model.appendBodyToJoint(parent, body, pin.SE3.Identity())
    model.armature = rng.uniform(0.0, 0.05, model.nv)
    tip = pin.SE3(pin.exp3(rng.uniform(-1.0, 1.0, 3)), rng.uniform(-0.2, 0.2, 3))
    model.addFrame(pin.Frame("tip", parent, 0, tip, pin.FrameType.OP_FRAME))
    return model


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


QUADRUPED_FEET = {
    **dict.fromkeys(("anymal", "anymal_c", "anymal_kinova"), ("LF_FOOT", "RF_FOOT", "LH_FOOT", "RH_FOOT")),
    **dict.fromkeys(("b1", "b1_z1", "go1", "go2", "a1", "laikago"), ("FL_foot", "FR_foot", "RL_foot", "RR_foot")),
    "hyq": ("lf_foot", "rf_foot", "lh_foot", "rh_foot"),
    **dict.fromkeys(("solo8", "solo12"), ("FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT")),
    "quadruped": ("BL_contact", "BR_contact", "FL_contact", "FR_contact"),
    "centauro": ("contact_1", "contact_2", "contact_3", "contact_4"),
    "bolt": ("FL_FOOT", "FR_FOOT"),
}
"""Point feet of the example-robot-data robots (3D contacts)."""

BIPED_SOLES = {
    **dict.fromkeys(("talos", "talos_box", "talos_full", "talos_full_box", "talos_legs"),
                    ("left_sole_link", "right_sole_link")),
    **dict.fromkeys(("romeo", "icub", "icub_reduced"), ("l_sole", "r_sole")),
    "human": ("left_foot", "right_foot"),
    "alexander": ("LEFT_FOOT", "RIGHT_FOOT"),
    **dict.fromkeys(("g1", "g1_with_hands"), ("left_ankle_roll_link", "right_ankle_roll_link")),
    **dict.fromkeys(("simple_humanoid", "simple_humanoid_classical"), ("l_ankle", "r_ankle")),
}
"""Soles of the example-robot-data humanoids (6D contacts)."""


def reaching_node(state, tip: int, target, tip_weight: float, terminal: bool, armature: float = 0.0):
    """An Euler node (dt 0.01) of a fully actuated reach: posture (1e-2), control (1e-3, running nodes) and the
    frame ``tip`` to ``target`` (``tip_weight``), with ``armature`` on every joint."""
    import crocopy

    act = crocopy.ActuationModelFull(state)
    costs = crocopy.CostModelSum(state, act.nu)
    costs.addCost("x", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, state.zero(), act.nu)), 1e-2)
    if not terminal:
        costs.addCost("u", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, act.nu)), 1e-3)
    goal = crocopy.ResidualModelFrameTranslation(state, tip, np.asarray(target, dtype=float), act.nu)
    costs.addCost("tip", crocopy.CostModelResidual(state, goal), tip_weight)
    dam = crocopy.DifferentialActionModelFreeFwdDynamics(state, act, costs)
    if armature:
        dam.armature = armature * np.ones(state.nv)
    return crocopy.IntegratedActionModelEuler(dam, 0.0 if terminal else 0.01)
