"""The compiled Euler nodes of a problem's running horizon (:class:`EulerHorizon`): a range of nodes in one compiled
call (:mod:`.horizon_kernel`), on ``problem.nthreads`` threads (:mod:`.node_threads`)."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from . import horizon_kernel as horizons
from . import line_search_kernel, trial_kernel
from .node_threads import ThreadTables

if TYPE_CHECKING:
    from .euler_node import EulerNode


class EulerHorizon:
    """The rollout of the DDP family over the running Euler nodes (:func:`.horizon_kernel.horizon_rollout`) and
    their derivatives with the gaps (:func:`.horizon_kernel.horizon_calc_diff`), a range ``t0 <= t < t1`` of
    compiled nodes per call; the other nodes' entries are never read.

    ``rollout(addresses, xs_try, us_try, alpha, gaps, gap_at, t0, t1)`` (``addresses``: of ``xs, us, xs_try, us_try,
    dxs, ks, Ks, fs, lbs, ubs``, :func:`crocopy.solvers.rollout.horizon_addresses`) and ``calc_diff(xs, us, fs, xs_at,
    us_at, fs_at, t0, t1)`` (with the addresses of ``xs``, ``us`` and of the gaps ``fs`` it writes, or None) return
    the total cost of the range, each node's in :attr:`costs`.  A node whose acceleration is not finite (a contact
    set singular at that state) is evaluated again on its Python path by ``calc``/``calc_diff``; a rollout stops
    there (its cost NaN) and the caller goes on node by node (:func:`crocopy.solvers.rollout.trial_rollout`)."""

    def __init__(self, nodes: list[EulerNode | None], nus: list[int], nthreads: int = 1) -> None:
        first = next(n for n in nodes if n is not None)
        empty = np.zeros_like(first.tbl)
        self.tbls = np.stack([empty if n is None else n.tbl for n in nodes])
        self.ioff = np.cumsum([0] + [0 if n is None else n.ints.shape[0] for n in nodes], dtype=np.int64)
        self.poff = np.cumsum([0] + [0 if n is None else n.par.shape[0] for n in nodes], dtype=np.int64)
        self.ints = np.concatenate([n.ints for n in nodes if n is not None])
        self.par = np.concatenate([n.par for n in nodes if n is not None])
        for t, n in enumerate(nodes):
            if n is not None:  # the node's parameters are now the horizon's: re-read in place, both see them
                n.par = self.par[self.poff[t]:self.poff[t + 1]]
        self.nus = np.array(nus, dtype=np.int64)
        self.nx, self.ndx = first.model.state.nx, first.model.state.ndx
        self.costs = np.zeros(len(nodes))
        self.python = [(t, n) for t, n in enumerate(nodes) if n is not None and n.python.items]
        """The nodes with Python residuals (:mod:`.python_residuals`): their rows are evaluated before a compiled
        ``calc_diff`` and their costs again after a compiled rollout."""
        self._python_ranges: dict[tuple[int, int], list] = {}
        self._python_indices: dict[tuple[int, int], np.ndarray] = {}
        self.no_gaps = np.zeros(len(nodes) + 1, dtype=np.int64)
        self.nodes = nodes
        self._searches = type(self) is EulerHorizon and not self.python and all(n is not None for n in nodes)
        """Whether :meth:`line_search` may run: every running node of this class, none with Python residuals."""
        self.threads = ThreadTables(nodes, self.tbls, nthreads) if nthreads > 1 else None
        """The extra threads' tables (:mod:`.node_threads`), or None on one thread."""

    def calc_diff(self, xs, us, fs, xs_at: np.ndarray, us_at: np.ndarray, fs_at: np.ndarray | None, t0: int,
                  t1: int) -> float:
        """Values and derivatives of the nodes ``t0 <= t < t1`` (and their gaps ``fs[t+1]`` when ``fs_at``, the
        addresses of the list ``fs``)."""
        return self.calc_diff_ranges(xs, us, fs, xs_at, us_at, fs_at, [(t0, t1)])[0]

    def calc_diff_ranges(self, xs, us, fs, xs_at: np.ndarray, us_at: np.ndarray, fs_at: np.ndarray | None,
                         ranges: list) -> list[float]:
        """:meth:`calc_diff` of each range ``(t0, t1)`` of ``ranges``; returns their totals.  On several threads the
        nodes of all the ranges are shared out at once (one dispatch, :meth:`.node_threads.ThreadTables.run`)."""
        self._python_rows(xs, us, ranges, True)
        head, nus, costs, kernel = self._head(), self.nus, self.costs, self.calc_diff_kernel
        nx, ndx, gaps, gap_at = self.nx, self.ndx, fs_at is not None, self.no_gaps if fs_at is None else fs_at

        def call(tbls, a, b):
            return kernel(tbls, *head, xs_at, us_at, nus, nx, ndx, gaps, gap_at, a, b, costs)

        return self._finite(self._run(call, ranges), ranges, xs, us, fs if gaps else None, True)

    def calc_diff_all(self, xs_at: np.ndarray, us_at: np.ndarray, fs_at: np.ndarray | None, terminal,
                      out: np.ndarray) -> float | None:
        """:meth:`calc_diff` of every running node and the ``terminal`` evaluator's ``calcDiff`` in one call
        (:func:`.horizon_kernel.calc_diff_all`, the terminal cost into ``out[0]``); returns the running nodes' total,
        or None where it does not apply (as :meth:`line_search`; several threads): the caller takes the node by node
        path, as it does after a total that is not finite."""
        if not self._whole(terminal):
            return None
        gaps, gap_at = fs_at is not None, self.no_gaps if fs_at is None else fs_at
        return horizons.calc_diff_all(self.tbls, *self._head(), xs_at, us_at, self.nus, self.nx, self.ndx, gaps,
                                      gap_at, len(self.nodes), self.costs, terminal.tbl, terminal.ints, terminal.par,
                                      terminal.no_control, out)

    def trial_all(self, addresses: tuple, x0: np.ndarray, dx: np.ndarray, du: np.ndarray, alpha: float,
                  fs: np.ndarray, step: np.ndarray, terminal, out: np.ndarray) -> float | None:
        """The terminal state ``x̂_T``, :attr:`trial` of every running node and the ``terminal`` evaluator's ``calc`` at
        ``x̂_T`` in one call (:func:`.trial_kernel.trial_all`, the terminal cost into ``out[0]``); returns the running
        nodes' total, or None where it does not apply (as :meth:`calc_diff_all`; a horizon without ``fused_trial``)."""
        if not self.fused_trial or not self._whole(terminal):
            return None
        xs, us, xs_try, us_try = addresses
        return trial_kernel.trial_all(self.tbls, *self._head(), x0, xs, us, xs_try, us_try, self.nus, self.nx,
                                      self.ndx, dx, du, alpha, fs, step, len(self.nodes), self.costs, terminal.tbl,
                                      terminal.ints, terminal.par, terminal.no_control, out)

    def first_gap(self, x: np.ndarray, x0: np.ndarray, f: np.ndarray) -> bool:
        """``f = x0 ⊖ x`` by node 0's compiled state difference (:meth:`.EulerNode.diff`, as the trial point's ``f̂₀``);
        False (nothing written) where node 0 is not a compiled Euler node."""
        if type(self) is not EulerHorizon or self.nodes[0] is None:
            return False
        self.nodes[0].diff(x, x0, f)
        return True

    def first_state(self, x0: np.ndarray, step: np.ndarray, x: np.ndarray) -> bool:
        """``x = x0 ⊕ step`` by node 0's compiled state integration (:meth:`.EulerNode.integrate`, as the compiled line
        search's ``x̂₀``); False (nothing written) where node 0 is not a compiled Euler node."""
        if type(self) is not EulerHorizon or self.nodes[0] is None:
            return False
        self.nodes[0].integrate(x0, step, x)
        return True

    def _searches_with(self, terminal) -> bool:
        """Whether the line searches apply with the ``terminal`` evaluator: every running node in this horizon's one
        range without Python residuals, and a compiled Euler terminal node without them either."""
        return self._searches and type(terminal) is type(self.nodes[0]) and not terminal.python.items

    def _whole(self, terminal) -> bool:
        """Whether one call may run every running node and the ``terminal`` evaluator: the conditions of
        :meth:`line_search`, on one thread."""
        return self.threads is None and self._searches_with(terminal)

    def calc(self, xs, us, xs_at: np.ndarray, us_at: np.ndarray, t0: int, t1: int) -> float:
        """Values of the nodes ``t0 <= t < t1``."""
        return self.calc_ranges(xs, us, xs_at, us_at, [(t0, t1)])[0]

    def calc_ranges(self, xs, us, xs_at: np.ndarray, us_at: np.ndarray, ranges: list) -> list[float]:
        """:meth:`calc` of each range of ``ranges`` (shared out at once on several threads); returns their totals."""
        self._python_rows(xs, us, ranges, False)
        head, nus, nx, costs, kernel = self._head(), self.nus, self.nx, self.costs, self.calc_kernel

        def call(tbls, a, b):
            return kernel(tbls, *head, xs_at, us_at, nus, nx, a, b, costs)

        return self._finite(self._run(call, ranges), ranges, xs, us, None, False)

    def _python_rows(self, xs, us, ranges: list, derivatives: bool) -> None:
        """The rows of the Python residuals of the nodes in ``ranges`` (before the compiled calls), and their
        Jacobians with ``derivatives`` (:meth:`EulerNode.python_derivatives`)."""
        if not self.python:
            return
        for t0, t1 in ranges:
            for t, evaluate, derive in self._python_nodes(t0, t1):
                if derivatives:
                    derive(xs[t], us[t])
                else:
                    evaluate(xs[t], us[t])

    def fold(self, t0: int, t1: int) -> float:
        """The sum of :attr:`costs` ``[t0:t1]`` in node order."""
        return horizons.fold(self.costs, t0, t1)

    def _finite(self, totals: list[float], ranges: list, xs, us, fs, derivatives: bool) -> list[float]:
        """The ranges' ``totals``, each that is not finite replaced by :meth:`_python_path`'s."""
        return [total if math.isfinite(total) else self._python_path(xs, us, fs, t0, t1, derivatives)
                for (t0, t1), total in zip(ranges, totals)]

    def _python_path(self, xs, us, fs, t0: int, t1: int, derivatives: bool) -> float:
        """After a range whose total is not finite: the nodes whose cost is not finite again on their Python path
        (:meth:`EulerNode.python_path`), with their gaps when ``fs``; returns the range's total."""
        for t in range(t0, t1):
            if not math.isfinite(self.costs[t]):
                node = self.nodes[t]
                self.costs[t] = node.python_path(xs[t], us[t], derivatives)
                if fs is not None:
                    node.model.state._diff_into(xs[t + 1], node._data().xnext, fs[t + 1])
        return horizons.fold(self.costs, t0, t1)

    def _run(self, call: Callable, ranges: list) -> list[float]:
        """``call(tbls, a, b)`` over each range ``[a, b)``, on the extra threads too (then each range's costs added in
        node order, as one call adds them); the ranges' totals."""
        if self.threads is None or sum(b - a for a, b in ranges) < 2:
            return [call(self.tbls, a, b) for a, b in ranges]
        self.threads.run(call, self.tbls, ranges)
        return [horizons.fold(self.costs, a, b) for a, b in ranges]

    def rollout(self, addresses: tuple, xs_try: list, us_try: list, alpha: float, gaps: bool, gap_at: int, t0: int,
                t1: int) -> float:
        """The rollout steps of the nodes ``t0 <= t < t1`` (the Python residuals' rows and costs after them)."""
        total = self.rollout_kernel(self.tbls, *self._head(), *addresses, self.nus, self.nx, self.ndx, alpha, gaps,
                                    gap_at, t0, t1, self.costs)
        if self.python:
            for t, evaluate, _ in self._python_nodes(t0, t1):
                evaluate(xs_try[t], us_try[t])
            total += horizons.horizon_recost(self.tbls, self.ints, self.ioff, self.par, self.poff,
                                           self._python_in(t0, t1), self.costs)
        return total

    def line_search(self, addresses: tuple, terminal, alphas: np.ndarray, cost: float, d: tuple[float, float],
                    thresholds: tuple[float, float, float], negative: bool, out: np.ndarray) -> tuple[int, int] | None:
        """The DDP family's line search from a feasible iterate in one call (:func:`.line_search_kernel.line_search`,
        ``addresses`` as for :meth:`rollout`, ``d = (d₀, d₁)``, ``thresholds = (th_grad, th_accept, th_negative)``);
        returns ``(i, status)``, or None where it does not apply: a range short of the whole horizon, Python residuals,
        another horizon class, or a ``terminal`` evaluator that is not a compiled Euler node without Python
        residuals.  Node ``t``'s cost stays in :attr:`costs`, the terminal node's in ``out[1]``."""
        if not self._searches_with(terminal):
            return None
        return line_search_kernel.line_search(self.tbls, *self._head(), *addresses, self.nus, self.nx, self.ndx,
                                              len(self.nodes), self.costs, terminal.tbl, terminal.ints, terminal.par,
                                              terminal.no_control, alphas, cost, *d, *thresholds, negative, out)

    def line_search_gaps(self, addresses: tuple, terminal, x0: np.ndarray, scratch: tuple[np.ndarray, np.ndarray],
                         buffer: tuple[np.ndarray, np.ndarray], alphas: np.ndarray, cost: float,
                         d: tuple[float, float], thresholds: tuple[float, float, float], rule: tuple[bool, bool],
                         out: np.ndarray) -> tuple[int, int] | None:
        """The line search of FDDP and Box-FDDP from an infeasible iterate in one call
        (:func:`.line_search_kernel.line_search_gaps`; ``d = (dg, dq)``, ``scratch`` two tangent vectors, ``buffer``
        the solver's horizon buffer ``(addr, dims)``, ``rule = (every, grad_negative)``); None where
        :meth:`line_search` does not apply."""
        if not self._searches_with(terminal):
            return None
        return line_search_kernel.line_search_gaps(
            self.tbls, *self._head(), *addresses, self.nus, self.nx, self.ndx, len(self.nodes), self.costs,
            terminal.tbl, terminal.ints, terminal.par, terminal.no_control, x0, *scratch, *buffer, alphas, cost, *d,
            *thresholds, *rule, out)

    calc_diff_kernel = staticmethod(horizons.horizon_calc_diff)
    calc_kernel = staticmethod(horizons.horizon_calc)
    rollout_kernel = staticmethod(horizons.horizon_rollout)
    """The compiled loops over a range of nodes (:mod:`.horizon_kernel`); a subclass names its own, which take the
    arguments after the tables that :meth:`_head` gives."""

    def _head(self) -> tuple:
        """The kernels' arguments after the stacked tables: the nodes' integers and parameters with their offsets."""
        return self.ints, self.ioff, self.par, self.poff

    fused_trial = True
    """Whether :attr:`trial` may run a range as one compiled call (:func:`.trial_kernel.horizon_trial`)."""

    trial = trial_kernel.trial
    """SolverSQP/SolverCSQP's trial point of the nodes ``t0 <= t < t1`` (:func:`.trial_kernel.trial`)."""

    def _python_nodes(self, t0: int, t1: int) -> list:
        """The nodes ``t0 <= t < t1`` with Python residuals, as ``(t, evaluate, derive)``: their rows'
        :meth:`.python_residuals.PythonResiduals.evaluate` and :meth:`EulerNode.python_derivatives` (made once per
        range)."""
        key = (t0, t1)
        if key not in self._python_ranges:
            self._python_ranges[key] = [(t, node.python.evaluate, node.python_derivatives) for t, node in self.python
                                        if t0 <= t < t1]
        return self._python_ranges[key]

    def _python_in(self, t0: int, t1: int) -> np.ndarray:
        """The indices of :meth:`_python_nodes` (made once per range)."""
        key = (t0, t1)
        if key not in self._python_indices:
            self._python_indices[key] = np.array([t for t, _, _ in self._python_nodes(t0, t1)], dtype=np.int64)
        return self._python_indices[key]
