"""crocopy: optimal control for robots in Python, with Crocoddyl's API.

Everything public is re-exported here flat, as in Crocoddyl (``crocopy.SolverFDDP``,
``crocopy.DifferentialActionModelFreeFwdDynamics``, ...).
"""

from importlib.metadata import PackageNotFoundError, version

from .action_base import ActionDataAbstract, ActionModelAbstract
from .actions import ActionModelLQR, ActionModelUnicycle, DifferentialActionModelLQR
from .actions.control_penalty import ActionModelControlPenalty
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
from .batch import SolveManyError, SolveResult, WorkerDiedError, solve_many
from .callbacks.base import CallbackAbstract, CallbackLogger, CallbackVerbose
from .callbacks.display import CallbackDisplay
from .callbacks.plotting import plotConvergence, plotFeasibility, plotOCSolution
from .constraints.base import ConstraintDataAbstract, ConstraintModelAbstract, ConstraintModelResidual, ConstraintType
from .constraints.manager import ConstraintDataManager, ConstraintItem, ConstraintModelManager
from .costs.base import CostDataAbstract, CostDataResidual, CostModelAbstract, CostModelResidual
from .costs.sum import CostDataSum, CostItem, CostModelSum
from .data_collector import DataCollectorAbstract
from .diff_action_base import DifferentialActionDataAbstract, DifferentialActionModelAbstract
from .enums import AssignmentOp, Jcomponent, RKType, VerboseLevel
from .integrators.base import IntegratedActionModelAbstract
from .integrators.control_base import ControlParametrizationDataAbstract, ControlParametrizationModelAbstract
from .integrators.control_poly import (
    ControlParametrizationDataPolyOne,
    ControlParametrizationDataPolyTwoRK,
    ControlParametrizationModelPolyOne,
    ControlParametrizationModelPolyTwoRK,
    ControlParametrizationModelPolyZero,
)
from .integrators.euler import IntegratedActionDataEuler, IntegratedActionModelEuler
from .integrators.rk import IntegratedActionDataRK, IntegratedActionModelRK
from .kernels import kernels_enabled, set_kernels, use_kernels
from .numdiff import (
    ActionDataNumDiff,
    ActionModelNumDiff,
    DifferentialActionDataNumDiff,
    DifferentialActionModelNumDiff,
)
from .residuals import ResidualModelControl, ResidualModelState
from .residuals.base import ResidualDataAbstract, ResidualModelAbstract
from .shooting import ShootingProblem
from .solvers import SolverAbstract, SolverDDP, SolverFDDP
from .solvers.box_ddp import SolverBoxDDP
from .solvers.box_fddp import SolverBoxFDDP
from .solvers.box_qp import BoxQP, BoxQPSolution
from .solvers.clamping import SolverClampedDDP
from .solvers.hddp import CallbackHDDPLogger, CallbackHDDPVerbose, SolverHDDP
from .solvers.projection import ConstraintRankError, SolverProjection
from .squashing.action import ActionModelSquashed
from .squashing.smooth_sat import (
    ActuationSquashingModel,
    SquashingDataAbstract,
    SquashingModelAbstract,
    SquashingModelSmoothSat,
)
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
