"""The compiled inverse-dynamics nodes of a problem's running horizon (:class:`InvDynHorizon`): a range of nodes in one
compiled call (:mod:`.invdyn_horizon_kernel`), on ``problem.nthreads`` threads (:mod:`.node_threads`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from . import invdyn_horizon_kernel as horizons
from .euler_horizon import EulerHorizon

if TYPE_CHECKING:
    from .invdyn_node import InvDynNode


class InvDynHorizon(EulerHorizon):
    """:class:`.euler_horizon.EulerHorizon` over :class:`.invdyn_node.InvDynNode` evaluators: the same tables, plus
    each node's inverse-dynamics items (``iints[joff[t]:joff[t+1]]``).  The nodes have no Python residuals (the
    evaluator declines them), so every call is one compiled call per range; SolverSQP/SolverCSQP's trial point is
    the states and controls, :meth:`calc_ranges`, then the gaps (:func:`.trial_kernel.trial`)."""

    fused_trial = False
    calc_diff_kernel = staticmethod(horizons.invdyn_horizon_calc_diff)
    calc_kernel = staticmethod(horizons.invdyn_horizon_calc)
    rollout_kernel = staticmethod(horizons.invdyn_horizon_rollout)

    def __init__(self, nodes: list[InvDynNode | None], nus: list[int], nthreads: int = 1) -> None:
        super().__init__(nodes, nus, nthreads)
        self.joff = np.cumsum([0] + [0 if n is None else n.iints.shape[0] for n in nodes], dtype=np.int64)
        self.iints = np.concatenate([n.iints for n in nodes if n is not None])

    def _head(self) -> tuple:
        return self.ints, self.ioff, self.par, self.poff, self.iints, self.joff
