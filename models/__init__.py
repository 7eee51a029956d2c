"""Pinocchio-backed models of crocopy (imported as ``crocopy.models``)."""

from .actuations import (
    ActuationModelFloatingBase,
    ActuationModelFloatingBaseThrusters,
    ActuationModelFull,
    ActuationModelLinear,
    Thruster,
    ThrusterType,
)
from .cones import CoPSupport, FrictionCone, WrenchCone
from .contact_1d import ContactData1D, ContactModel1D
from .contact_2d import ContactData2D, ContactModel2D
from .contact_base import ContactDataAbstract, ContactModelAbstract
from .contact_fwd_dynamics import DifferentialActionDataContactFwdDynamics, DifferentialActionModelContactFwdDynamics
from .contact_invdyn import DifferentialActionModelContactInvDynamics
from .contact_multiple import ContactDataMultiple, ContactItem, ContactModelMultiple
from .contacts import ContactData3D, ContactData6D, ContactModel3D, ContactModel6D
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
from .force_base import ForceDataAbstract
from .free_fwd_dynamics import DifferentialActionDataFreeFwdDynamics, DifferentialActionModelFreeFwdDynamics
from .free_invdyn import DifferentialActionModelFreeInvDynamics
from .impulse_base import ImpulseDataAbstract, ImpulseModelAbstract
from .impulse_fwd_dynamics import ActionDataImpulseFwdDynamics, ActionModelImpulseFwdDynamics
from .impulse_multiple import ImpulseDataMultiple, ImpulseItem, ImpulseModelMultiple
from .impulses import ImpulseData3D, ImpulseData6D, ImpulseModel3D, ImpulseModel6D
from .residual_numba import NodeKinematics, ResidualDataNumba, ResidualModelNumba, check_residual_derivatives
from .residuals_contact import (
    ResidualDataContactControlGrav,
    ResidualDataContactCoPPosition,
    ResidualDataContactForce,
    ResidualDataContactFrictionCone,
    ResidualDataContactWrenchCone,
    ResidualDataImpulseCoM,
    ResidualModelContactControlGrav,
    ResidualModelContactCoPPosition,
    ResidualModelContactForce,
    ResidualModelContactFrictionCone,
    ResidualModelContactWrenchCone,
    ResidualModelImpulseCoM,
)
from .residuals_dynamics import (
    ResidualDataCentroidalMomentum,
    ResidualDataCoMPosition,
    ResidualDataControlGrav,
    ResidualModelCentroidalMomentum,
    ResidualModelCoMPosition,
    ResidualModelControlGrav,
    ResidualModelJointAcceleration,
    ResidualModelJointEffort,
)
from .residuals_frame import (
    ResidualDataFramePlacement,
    ResidualDataFrameRotation,
    ResidualDataFrameTranslation,
    ResidualDataFrameVelocity,
    ResidualModelFramePlacement,
    ResidualModelFrameRotation,
    ResidualModelFrameTranslation,
    ResidualModelFrameVelocity,
)
from .state_multibody import StateMultibody

__all__ = [
    "CoPSupport",
    "FrictionCone",
    "WrenchCone",
    "ContactData1D",
    "ContactData2D",
    "ContactModel1D",
    "ContactModel2D",
    "ContactDataAbstract",
    "ContactModelAbstract",
    "DifferentialActionDataContactFwdDynamics",
    "DifferentialActionModelContactFwdDynamics",
    "DifferentialActionModelContactInvDynamics",
    "ContactDataMultiple",
    "ContactItem",
    "ContactModelMultiple",
    "ContactData3D",
    "ContactData6D",
    "ContactModel3D",
    "ContactModel6D",
    "ForceDataAbstract",
    "ImpulseDataAbstract",
    "ImpulseModelAbstract",
    "ActionDataImpulseFwdDynamics",
    "ActionModelImpulseFwdDynamics",
    "ImpulseDataMultiple",
    "ImpulseItem",
    "ImpulseModelMultiple",
    "ImpulseData3D",
    "ImpulseData6D",
    "ImpulseModel3D",
    "ImpulseModel6D",
    "ResidualDataContactControlGrav",
    "ResidualDataContactCoPPosition",
    "ResidualDataContactForce",
    "ResidualDataContactFrictionCone",
    "ResidualDataContactWrenchCone",
    "ResidualDataImpulseCoM",
    "ResidualModelContactControlGrav",
    "ResidualModelContactCoPPosition",
    "ResidualModelContactForce",
    "ResidualModelContactFrictionCone",
    "ResidualModelContactWrenchCone",
    "ResidualModelImpulseCoM",
    "ActuationModelFloatingBase",
    "ActuationModelFloatingBaseThrusters",
    "ActuationModelFull",
    "ActuationModelLinear",
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
    "DifferentialActionDataFreeFwdDynamics",
    "DifferentialActionModelFreeFwdDynamics",
    "DifferentialActionModelFreeInvDynamics",
    "ResidualDataCentroidalMomentum",
    "ResidualDataCoMPosition",
    "ResidualDataControlGrav",
    "ResidualModelCentroidalMomentum",
    "ResidualModelCoMPosition",
    "ResidualModelControlGrav",
    "ResidualDataFramePlacement",
    "ResidualDataFrameRotation",
    "ResidualDataFrameTranslation",
    "ResidualDataFrameVelocity",
    "ResidualModelFramePlacement",
    "ResidualModelFrameRotation",
    "ResidualModelFrameTranslation",
    "ResidualModelFrameVelocity",
    "NodeKinematics",
    "ResidualDataNumba",
    "ResidualModelNumba",
    "check_residual_derivatives",
    "ResidualModelJointAcceleration",
    "ResidualModelJointEffort",
    "StateMultibody",
    "Thruster",
    "ThrusterType",
]

_LAZY_DISPLAY = ("MeshcatDisplay", "export_html", "export_html_from_solver")


def __getattr__(name: str):
    """Import the meshcat display and HTML export lazily (meshcat is only needed to display)."""
    if name in _LAZY_DISPLAY:
        from . import display

        return getattr(display, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
