"""crocopy: optimal control for robots in Python, with Crocoddyl's API.

Everything public is re-exported here flat, as in Crocoddyl (``crocopy.SolverFDDP``,
``crocopy.DifferentialActionModelFreeFwdDynamics``, ...).
"""

from importlib.metadata import PackageNotFoundError, version

from .action_base import ActionDataAbstract, ActionModelAbstract
from .actions import ActionModelLQR, ActionModelUnicycle, DifferentialActionModelLQR
from .activations import (
    ActivationBounds,
    ActivationDataAbstract,
    ActivationModel2NormBarrier,
    ActivationModelAbstract,
    ActivationModelQuad,
    ActivationModelQuadraticBarrier,
    ActivationModelSmooth1Norm,
    ActivationModelSmooth2Norm,
    ActivationModelWeightedQuad,
    ActivationModelWeightedQuadraticBarrier,
)
from .actuation_base import ActuationDataAbstract, ActuationModelAbstract, JointDataAbstract
from .batch import SolveManyError, SolveResult, solve_many
from .box_qp import BoxQP, BoxQPSolution
from .callback_display import CallbackDisplay
from .callbacks import CallbackAbstract, CallbackLogger, CallbackVerbose
from .constraints import (
    ConstraintDataAbstract,
    ConstraintDataManager,
    ConstraintItem,
    ConstraintModelAbstract,
    ConstraintModelManager,
    ConstraintModelResidual,
    ConstraintType,
)
from .costs import (
    CostDataAbstract,
    CostDataResidual,
    CostDataSum,
    CostItem,
    CostModelAbstract,
    CostModelResidual,
    CostModelSum,
)
from .data_collector import DataCollectorAbstract
from .diff_action_base import DifferentialActionDataAbstract, DifferentialActionModelAbstract
from .enums import AssignmentOp, Jcomponent, RKType, VerboseLevel
from .integrator_base import IntegratedActionModelAbstract
from .integrator_euler import IntegratedActionDataEuler, IntegratedActionModelEuler
from .integrator_rk import IntegratedActionDataRK, IntegratedActionModelRK
from .numdiff import (
    ActionDataNumDiff,
    ActionModelNumDiff,
    DifferentialActionDataNumDiff,
    DifferentialActionModelNumDiff,
)
from .penalty import ActionModelControlPenalty
from .plotting import plotConvergence, plotFeasibility, plotOCSolution
from .residual_base import ResidualDataAbstract, ResidualModelAbstract
from .residuals import ResidualModelControl, ResidualModelState
from .shooting import ShootingProblem
from .solvers import SolverAbstract, SolverDDP, SolverFDDP
from .solvers.box_ddp import SolverBoxDDP
from .solvers.box_fddp import SolverBoxFDDP
from .solvers.clamping import SolverClampedDDP
from .solvers.hddp import CallbackHDDPLogger, CallbackHDDPVerbose, SolverHDDP
from .solvers.projection import ConstraintRankError, SolverProjection
from .squashing_action import ActionModelSquashed
from .state import StateAbstract, StateVector

try:
    __version__ = version("crocopy")
except PackageNotFoundError:
    __version__ = "0.0.0"

from .models import *  # noqa: E402,F403  (Pinocchio models, re-exported flat)


def __getattr__(name: str):
    """``crocopy.MeshcatDisplay`` and the HTML export helpers load lazily from ``crocopy.models``."""
    from . import models

    return getattr(models, name)
