"""The running nodes' values and derivatives on several threads (``problem.nthreads``).

A horizon of compiled nodes (:class:`.euler_horizon.EulerHorizon`) evaluates the nodes ``t0 <= t < t1`` of a range in
one compiled call, which releases the GIL (:func:`.horizon_kernel.horizon_calc_diff`, ``horizon_calc``).  With
``k`` threads the nodes of a solve's ranges (those of one call of the solver, all at once) are cut into ``k``
contiguous shares of nearly equal length; the calling thread runs the first
and a pool of ``k - 1`` threads the others, at once.  The nodes of one Pinocchio model share a workspace and a
scratch (:meth:`.lowered_model.Lowered.scratch`), so each extra thread ``c`` reads tables of its own
(:class:`ThreadTables`): every node's table with the addresses of the workspace and scratch replaced by those of
thread ``c``'s copies (:meth:`.lowered_model.Lowered.thread_entries`), except the node's own arrays
(:data:`.node_table.OWN`: one thread evaluates a node at a time).  A node's result does not depend on which thread
evaluated it (a kernel call reads nothing a previous call left in the scratch), each writes only its own arrays and
``costs[t]``, and the total is then added in node order (:func:`.horizon_kernel.fold`): the results are
bit-identical to one thread's.  Rollouts stay on one thread (each node starts where the previous one ended).
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from . import node_table as table

_POOLS: dict[int, ThreadPoolExecutor] = {}


def pool(workers: int) -> ThreadPoolExecutor:
    """A pool of ``workers`` threads, made once per size and kept for the process."""
    if workers not in _POOLS:
        _POOLS[workers] = ThreadPoolExecutor(max_workers=workers, thread_name_prefix="crocopy-nodes")
    return _POOLS[workers]


class ThreadTables:
    """The node tables of the extra threads ``1 .. k-1`` (``tables[c - 1]``, shape of ``tbls``) for the running
    ``nodes`` (None where a node is not compiled) whose own tables are ``tbls`` (thread 0's)."""

    def __init__(self, nodes: list, tbls: np.ndarray, k: int) -> None:
        n_rb, start = table.N_RB, table.NODE + len(table.NODE_ARRAYS)
        minv = table.ENTRIES["Minv"]
        self.tables = []
        for c in range(1, k):
            tbls_c = tbls.copy()
            for t, node in enumerate(nodes):
                if node is None:
                    continue
                workspace, scratch = node._lowered.thread_entries(c, node.model.nu, node.contacts.nc)
                tbls_c[t, n_rb:table.NODE] = workspace
                tbls_c[t, start:] = scratch[:-1]
                if node.shared_minv:
                    tbls_c[t, minv] = scratch[-1]
                tbls_c[t, table.OWN] = tbls[t, table.OWN]
            self.tables.append(tbls_c)

    def run(self, call: Callable, tbls: np.ndarray, ranges: list) -> None:
        """``call(tables, a, b)`` over the nodes of ``ranges`` (``(t0, t1)`` pairs, in order), cut into one contiguous
        share per thread (:func:`shares`): the first here with ``tbls``, the others at once on the pool with the extra
        threads' tables; returns when all are done (re-raising their errors)."""
        parts = shares(ranges, len(self.tables) + 1)
        futures = [pool(len(self.tables)).submit(_each, call, tables, part)
                   for tables, part in zip(self.tables, parts[1:])]
        try:
            _each(call, tbls, parts[0])
        finally:
            for f in futures:
                f.result()


def _each(call: Callable, tables: np.ndarray, part: list) -> None:
    for a, b in part:
        call(tables, a, b)


def shares(ranges: list, k: int) -> list[list[tuple[int, int]]]:
    """The nodes of ``ranges`` cut into ``k`` shares whose sizes differ by at most one, each a list of pieces of the
    ranges (in node order)."""
    total = sum(b - a for a, b in ranges)
    edges = [total * c // k for c in range(k + 1)]
    parts: list[list[tuple[int, int]]] = [[] for _ in range(k)]
    seen = 0
    for a, b in ranges:
        for c in range(k):
            lo, hi = max(a, a + edges[c] - seen), min(b, a + edges[c + 1] - seen)
            if hi > lo:
                parts[c].append((lo, hi))
        seen += b - a
    return parts
