"""mim-solvers' Python API, served by crocopy: ``import crocopy.mim_solvers as mim_solvers``.

A script written for mim-solvers 0.3.0 (with ``import crocopy as crocoddyl``) runs by changing its
imports: ``SolverSQP``, ``SolverCSQP`` (:mod:`crocopy.solvers.sqp`, :mod:`crocopy.solvers.csqp`),
``CallbackVerbose``, ``CallbackLogger`` and ``plotConvergence`` (mim-solvers' flavours,
:mod:`crocopy.callbacks.sqp`), ``CallbackAbstract``, and the DDP/FDDP solvers mim-solvers still exports.
``SolverPROXQP`` (a dense QP per iteration) is not provided.

mim-solvers 0.3.0's own example scripts run to their end this way, with its iterations and costs
(``crocopy bench --mim-examples``, :mod:`crocopy.bench.mim_examples`).
"""

from __future__ import annotations

from .callbacks.base import CallbackAbstract
from .callbacks.sqp import CallbackSQPLogger as CallbackLogger
from .callbacks.sqp import CallbackSQPVerbose as CallbackVerbose
from .callbacks.sqp import plotSQPConvergence as plotConvergence
from .solvers.csqp import SolverCSQP
from .solvers.ddp import SolverDDP
from .solvers.fddp import SolverFDDP
from .solvers.sqp import SolverSQP
from .std_containers import StdVec_Callback

__all__ = ["CallbackAbstract", "CallbackLogger", "CallbackVerbose", "SolverCSQP", "SolverDDP", "SolverFDDP",
           "SolverSQP", "StdVec_Callback", "plotConvergence"]
