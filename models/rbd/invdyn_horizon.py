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

    def __init__(self, nodes: list[InvDynNode | None], nus: list[int], nthreads: int = 1) -> None:
        super().__init__(nodes, nus, nthreads)
        self.joff = np.cumsum([0] + [0 if n is None else n.iints.shape[0] for n in nodes], dtype=np.int64)
        self.iints = np.concatenate([n.iints for n in nodes if n is not None])

    def calc_diff_ranges(self, xs, us, fs, xs_at: np.ndarray, us_at: np.ndarray, fs_at: np.ndarray | None,
                         ranges: list) -> list[float]:
        ints, ioff, par, poff, iints, joff = self.ints, self.ioff, self.par, self.poff, self.iints, self.joff
        nus, nx, ndx, costs = self.nus, self.nx, self.ndx, self.costs
        gaps, gap_at = fs_at is not None, self.no_gaps if fs_at is None else fs_at

        def call(tbls, a, b):
            return horizons.invdyn_horizon_calc_diff(tbls, ints, ioff, par, poff, iints, joff, xs_at, us_at, nus, nx,
                                                     ndx, gaps, gap_at, a, b, costs)

        return self._finite(self._run(call, ranges), ranges, xs, us, fs if gaps else None, True)

    def calc_ranges(self, xs, us, xs_at: np.ndarray, us_at: np.ndarray, ranges: list) -> list[float]:
        ints, ioff, par, poff, iints, joff = self.ints, self.ioff, self.par, self.poff, self.iints, self.joff
        nus, nx, costs = self.nus, self.nx, self.costs

        def call(tbls, a, b):
            return horizons.invdyn_horizon_calc(tbls, ints, ioff, par, poff, iints, joff, xs_at, us_at, nus, nx, a, b,
                                                costs)

        return self._finite(self._run(call, ranges), ranges, xs, us, None, False)

    def rollout(self, addresses: tuple, xs_try: list, us_try: list, alpha: float, gaps: bool, gap_at: int, t0: int,
                t1: int) -> float:
        return horizons.invdyn_horizon_rollout(
            self.tbls, self.ints, self.ioff, self.par, self.poff, self.iints, self.joff, *addresses, self.nus, self.nx,
            self.ndx, alpha, gaps, gap_at, t0, t1, self.costs,
        )
