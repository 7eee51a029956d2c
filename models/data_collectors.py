"""Data collectors of the multibody models: containers shared by every residual of a node.

A differential action model fills ``pinocchio`` (the node's ``pinocchio.Data``) once per
``calc``/``calcDiff``; the actuation, joint, contact and impulse data are the node's own data
objects.  Class names and constructor arguments follow Crocoddyl.
"""

from __future__ import annotations

from typing import Any

import pinocchio as pin

from crocopy.actuation_base import ActuationDataAbstract, JointDataAbstract
from crocopy.data_collector import DataCollectorAbstract


class DataCollectorMultibody(DataCollectorAbstract):
    """``DataCollectorMultibody(pinocchio)``: holds the node's ``pinocchio.Data``."""

    def __init__(self, pinocchio: pin.Data) -> None:
        self.pinocchio = pinocchio


class DataCollectorActuation(DataCollectorAbstract):
    """``DataCollectorActuation(actuation)``: holds the actuation data."""

    def __init__(self, actuation: ActuationDataAbstract) -> None:
        self.actuation = actuation


class DataCollectorJoint(DataCollectorAbstract):
    """``DataCollectorJoint(joint)``: holds the joint data (efforts and accelerations)."""

    def __init__(self, joint: JointDataAbstract) -> None:
        self.joint = joint


class DataCollectorContact(DataCollectorAbstract):
    """``DataCollectorContact(contacts)``: holds the contact data."""

    def __init__(self, contacts: Any) -> None:
        self.contacts = contacts


class DataCollectorImpulse(DataCollectorAbstract):
    """``DataCollectorImpulse(impulses)``: holds the impulse data."""

    def __init__(self, impulses: Any) -> None:
        self.impulses = impulses


class DataCollectorActMultibody(DataCollectorMultibody, DataCollectorActuation):
    """``DataCollectorActMultibody(pinocchio, actuation)``."""

    def __init__(self, pinocchio: pin.Data, actuation: ActuationDataAbstract) -> None:
        self.pinocchio = pinocchio
        self.actuation = actuation


class DataCollectorJointActuation(DataCollectorActuation, DataCollectorJoint):
    """``DataCollectorJointActuation(actuation, joint)``."""

    def __init__(self, actuation: ActuationDataAbstract, joint: JointDataAbstract) -> None:
        self.actuation = actuation
        self.joint = joint


class DataCollectorJointActMultibody(DataCollectorActMultibody, DataCollectorJoint):
    """``DataCollectorJointActMultibody(pinocchio, actuation, joint)``."""

    def __init__(self, pinocchio: pin.Data, actuation: ActuationDataAbstract, joint: JointDataAbstract) -> None:
        self.pinocchio = pinocchio
        self.actuation = actuation
        self.joint = joint


class DataCollectorMultibodyInContact(DataCollectorMultibody, DataCollectorContact):
    """``DataCollectorMultibodyInContact(pinocchio, contacts)``."""

    def __init__(self, pinocchio: pin.Data, contacts: Any) -> None:
        self.pinocchio = pinocchio
        self.contacts = contacts


class DataCollectorActMultibodyInContact(DataCollectorActMultibody, DataCollectorContact):
    """``DataCollectorActMultibodyInContact(pinocchio, actuation, contacts)``."""

    def __init__(self, pinocchio: pin.Data, actuation: ActuationDataAbstract, contacts: Any) -> None:
        self.pinocchio = pinocchio
        self.actuation = actuation
        self.contacts = contacts


class DataCollectorJointActMultibodyInContact(DataCollectorJointActMultibody, DataCollectorContact):
    """``DataCollectorJointActMultibodyInContact(pinocchio, actuation, joint, contacts)``."""

    def __init__(
        self, pinocchio: pin.Data, actuation: ActuationDataAbstract, joint: JointDataAbstract, contacts: Any
    ) -> None:
        self.pinocchio = pinocchio
        self.actuation = actuation
        self.joint = joint
        self.contacts = contacts


class DataCollectorMultibodyInImpulse(DataCollectorMultibody, DataCollectorImpulse):
    """``DataCollectorMultibodyInImpulse(pinocchio, impulses)``."""

    def __init__(self, pinocchio: pin.Data, impulses: Any) -> None:
        self.pinocchio = pinocchio
        self.impulses = impulses
