"""crocopy: optimal control for robots in Python, with Crocoddyl's API.

Everything public is re-exported here flat, as in Crocoddyl (``crocopy.SolverFDDP``,
``crocopy.DifferentialActionModelFreeFwdDynamics``, ...).
"""

import builtins as _builtins
from importlib.metadata import PackageNotFoundError as _PackageNotFoundError
from importlib.metadata import version as _version
from types import ModuleType as _ModuleType

from .action_base import ActionDataAbstract, ActionModelAbstract
from .actions import ActionModelLQR, ActionModelUnicycle, DifferentialActionModelLQR
from .actions.control_penalty import ActionModelControlPenalty
from .actions.diff_lqr import DifferentialActionDataLQR
from .actions.lqr import ActionDataLQR
from .actions.unicycle import ActionDataUnicycle
from .activations import (
    ActivationBounds,
    ActivationDataAbstract,
    ActivationModel2NormBarrier,
    ActivationModelAbstract,
    ActivationModelQuad,
    ActivationModelQuadFlatExp,
    ActivationModelQuadFlatLog,
    ActivationModelQuadraticBarrier,
    ActivationModelSmooth1Norm,
    ActivationModelSmooth2Norm,
    ActivationModelWeightedQuad,
    ActivationModelWeightedQuadraticBarrier,
)
from .activations.norms import ActivationDataSmooth1Norm
from .activations.numdiff import ActivationDataNumDiff, ActivationModelNumDiff
from .actuation_base import ActuationDataAbstract, ActuationModelAbstract, JointDataAbstract
from .batch import SolveManyError, SolveResult, WorkerDiedError, solve_many
from .callbacks.base import CallbackAbstract, CallbackLogger, CallbackVerbose
from .callbacks.display import CallbackDisplay, DisplayAbstract
from .callbacks.plotting import plotConvergence, plotFeasibility, plotOCSolution
from .callbacks.save import saveConvergence, saveLogfile, saveOCSolution
from .callbacks.sqp import CallbackSQPLogger, CallbackSQPVerbose, plotSQPConvergence
from .constraints.base import (
    ConstraintDataAbstract,
    ConstraintDataResidual,
    ConstraintModelAbstract,
    ConstraintModelResidual,
    ConstraintType,
)
from .constraints.manager import ConstraintDataManager, ConstraintItem, ConstraintModelManager
from .costs.base import CostDataAbstract, CostDataResidual, CostModelAbstract, CostModelResidual
from .costs.sum import CostDataSum, CostItem, CostModelSum
from .crocoddyl_names import CROCODDYL_NAMES as _CROCODDYL_NAMES
from .crocoddyl_names import CROCODDYL_VERSION as _CROCODDYL_VERSION
from .data_collector import DataCollectorAbstract
from .diff_action_base import DifferentialActionDataAbstract, DifferentialActionModelAbstract
from .enums import AssignmentOp, FeasibilityNorm, Jcomponent, RKType, VerboseLevel
from .integrators.base import IntegratedActionDataAbstract, IntegratedActionModelAbstract
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
from .numdiff.state import StateNumDiff
from .residuals import ResidualModelControl, ResidualModelState
from .residuals.base import ResidualDataAbstract, ResidualModelAbstract
from .rotations import rotationMatrixFromTwoVectors
from .settings import seed, sharedMemory
from .shooting import ShootingProblem
from .solvers import SolverAbstract, SolverDDP, SolverFDDP
from .solvers.box_ddp import SolverBoxDDP
from .solvers.box_fddp import SolverBoxFDDP
from .solvers.box_qp import BoxQP, BoxQPSolution
from .solvers.clamping import SolverClampedDDP
from .solvers.coverage import NodeCoverage, compiled_coverage
from .solvers.csqp import SolverCSQP
from .solvers.hddp import CallbackHDDPLogger, CallbackHDDPVerbose, SolverHDDP
from .solvers.intro import EqualitySolverType, SolverIntro
from .solvers.kkt import SolverKKT
from .solvers.projection import ConstraintRankError, SolverProjection
from .solvers.sqp import SolverSQP
from .solvers.std_vector import StdVec_VectorXs
from .solvers.stopwatch import (
    disable_profiler,
    enable_profiler,
    stop_watch_get_average_time,
    stop_watch_get_max_time,
    stop_watch_get_min_time,
    stop_watch_get_total_time,
    stop_watch_report,
    stop_watch_reset_all,
)
from .squashing.action import ActionModelSquashed
from .squashing.smooth_sat import (
    ActuationSquashingData,
    ActuationSquashingModel,
    SquashingDataAbstract,
    SquashingModelAbstract,
    SquashingModelSmoothSat,
)
from .state import StateAbstract, StateVector
from .std_containers import (  # noqa: F401  (Crocoddyl's container names)
    StdMap_ConstraintData,
    StdMap_ConstraintItem,
    StdMap_ContactData,
    StdMap_ContactItem,
    StdMap_CostData,
    StdMap_CostItem,
    StdMap_ImpulseData,
    StdMap_ImpulseItem,
    StdSet_String,
    StdVec_ActionData,
    StdVec_ActionModel,
    StdVec_Callback,
    StdVec_ControlParametrizationData,
    StdVec_ControlParametrizationModel,
    StdVec_DiffActionData,
    StdVec_DiffActionModel,
    StdVec_MatrixXs,
    StdVec_RowMatrixX,
    StdVec_Thruster,
)

try:
    __version__ = _version("crocopy")
except _PackageNotFoundError:
    __version__ = "0.0.0"

from .models import *  # noqa: E402,F403  (Pinocchio models, re-exported flat)
from .models import ThrusterType as _ThrusterType  # noqa: E402

#: Crocoddyl exports its enumerations' values flat too (``crocoddyl.LInf``, ``crocoddyl.four``, ...).
both, first = Jcomponent.both, Jcomponent.first
setto, addto, rmfrom = AssignmentOp.setto, AssignmentOp.addto, AssignmentOp.rmfrom
two, three, four = RKType.two, RKType.three, RKType.four
Inequality, Equality, Both = ConstraintType.Inequality, ConstraintType.Equality, ConstraintType.Both
LInf, L1 = FeasibilityNorm.LInf, FeasibilityNorm.L1
LuNull, QrNull, Schur = EqualitySolverType.LuNull, EqualitySolverType.QrNull, EqualitySolverType.Schur
CW, CCW = _ThrusterType.CW, _ThrusterType.CCW
#: crocopy has no code generation (CppAD) back-end.
WITH_CODEGEN = False
#: Crocoddyl's exception type; crocopy raises Python's own (ValueError, TypeError, KeyError, ...), which
#: ``except crocopy.Exception`` catches as ``except crocoddyl.Exception`` catches Crocoddyl's.
Exception = _builtins.Exception  # noqa: A001

#: ``from crocopy import *`` gives every public name, as ``from crocoddyl import *`` does.
__all__ = sorted(n for n, v in globals().items() if not n.startswith("_") and not isinstance(v, _ModuleType))

from . import libcrocoddyl_pywrap_float64  # noqa: E402,F401  (Crocoddyl's compiled module's name, an alias)


def __getattr__(name: str):
    """Names that load lazily (``MeshcatDisplay``, HTML export) come from ``crocopy.models``; a name
    of Crocoddyl's API that crocopy lacks raises an ``AttributeError`` saying so."""
    if name.startswith("__"):
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    from . import models

    try:
        return getattr(models, name)
    except AttributeError:
        pass
    if name in _CROCODDYL_NAMES:
        raise AttributeError(
            f"crocopy does not implement Crocoddyl's {name} (a public name of Crocoddyl {_CROCODDYL_VERSION})"
        )
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
