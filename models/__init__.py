"""Pinocchio-backed models of crocopy (imported as ``crocopy.models``)."""

from .actuations import (
    ActuationModelFloatingBase,
    ActuationModelFloatingBaseThrusters,
    ActuationModelFull,
    Thruster,
    ThrusterType,
)
from .data_collectors import (
    DataCollectorActMultibody,
    DataCollectorActMultibodyInContact,
    DataCollectorActuation,
    DataCollectorContact,
    DataCollectorImpulse,
    DataCollectorJoint,
    DataCollectorJointActMultibody,
    DataCollectorJointActMultibodyInContact,
    DataCollectorJointActuation,
    DataCollectorMultibody,
    DataCollectorMultibodyInContact,
    DataCollectorMultibodyInImpulse,
)
from .state_multibody import StateMultibody

__all__ = [
    "ActuationModelFloatingBase",
    "ActuationModelFloatingBaseThrusters",
    "ActuationModelFull",
    "DataCollectorActMultibody",
    "DataCollectorActMultibodyInContact",
    "DataCollectorActuation",
    "DataCollectorContact",
    "DataCollectorImpulse",
    "DataCollectorJoint",
    "DataCollectorJointActMultibody",
    "DataCollectorJointActMultibodyInContact",
    "DataCollectorJointActuation",
    "DataCollectorMultibody",
    "DataCollectorMultibodyInContact",
    "DataCollectorMultibodyInImpulse",
    "StateMultibody",
    "Thruster",
    "ThrusterType",
]
