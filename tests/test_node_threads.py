"""``problem.nthreads = k``: the compiled nodes' values and derivatives on k threads, bit-identical to one thread."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import crocopy
from crocopy.problems import registry
from crocopy.solvers import compiled_nodes

pytestmark = pytest.mark.skipif(not crocopy.kernels_enabled(), reason="compiled nodes need numba")


def _solve(name: str, nthreads: int, maxiter: int):
    problem, xs, us = registry.build(name)
    problem.nthreads = nthreads
    solver = crocopy.SolverFDDP(problem)
    solver.solve(xs, us, maxiter)
    return solver


@pytest.mark.parametrize(("name", "maxiter"), [("arm", 20), ("trot-short", 6), ("quad-goal", 10)])
@pytest.mark.parametrize("nthreads", [2, 3])
def test_solves_on_several_threads_are_bit_identical(name, maxiter, nthreads):
    one, several = _solve(name, 1, maxiter), _solve(name, nthreads, maxiter)
    assert several.iter == one.iter > 0
    assert several.cost == one.cost
    for a, b in zip(several.xs + several.us + several.K, one.xs + one.us + one.K, strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("nthreads", [1, 2, 4])
def test_derivatives_and_values_on_threads_equal_the_python_path(nthreads):
    problem, xs, us = registry.build("trot-short")
    problem.nthreads = nthreads
    solver = crocopy.SolverFDDP(problem)
    solver.setCandidate(xs, us, False)
    nodes = compiled_nodes.attach(solver)
    assert nodes.horizon is not None and (nodes.horizon.threads is not None) == (nthreads > 1)
    cost = nodes.calcDiff(problem, solver.xs, solver.us, False)
    compiled = [(d.cost, d.Fx.copy(), d.Fu.copy(), d.Lx.copy(), d.Luu.copy()) for d in problem.runningDatas]
    values = nodes.calc(problem, solver.xs, solver.us)
    assert values == cost
    reference = problem.calc(solver.xs, solver.us)
    problem.calcDiff(solver.xs, solver.us)
    np.testing.assert_allclose(cost, reference, rtol=1e-12)
    for (c, Fx, Fu, Lx, Luu), d in zip(compiled, problem.runningDatas, strict=True):
        np.testing.assert_allclose(c, d.cost, rtol=1e-10, atol=1e-12)
        for a, b in ((Fx, d.Fx), (Fu, d.Fu), (Lx, d.Lx), (Luu, d.Luu)):
            np.testing.assert_allclose(a, b, rtol=1e-8, atol=1e-9)


@pytest.mark.parametrize("bad", [0, -1, 1.5, "2", None])
def test_nthreads_takes_a_positive_count(bad):
    problem, _, _ = registry.build("pend")
    with pytest.raises((ValueError, TypeError), match="nthreads"):
        problem.nthreads = bad
    assert problem.nthreads == 1


def test_the_bench_reports_both_thread_counts_and_identical_solves(monkeypatch):
    from crocopy.bench import threads

    monkeypatch.setattr(threads, "_solve", lambda name, k: (3, 1.5, [np.ones(2)]))
    report = threads.run_threads_bench(("pend",), repeats=2)
    row = next(line for line in report.splitlines() if line.startswith("| pend |"))
    cells = [c.strip() for c in row.strip("|").split("|")]
    assert float(cells[1]) > 0 and float(cells[2]) > 0 and cells[3].endswith("×")
    assert cells[5] == "yes (3 iterations)"


@settings(max_examples=200, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 6), st.integers(0, 12)), min_size=1, max_size=6), st.integers(1, 4))
def test_shares_cover_every_node_once_in_order_and_evenly(gaps_and_lengths, k):
    """The threads' shares of several ranges (:func:`node_threads.shares`): every node of the ranges exactly once, in
    node order, each piece inside one range, share sizes differing by at most one."""
    from crocopy.models.rbd.node_threads import shares

    ranges, t = [], 0
    for gap, length in gaps_and_lengths:
        t += gap
        ranges.append((t, t + length))
        t += length + 1
    parts = shares(ranges, k)
    assert len(parts) == k
    nodes = [n for a, b in ranges for n in range(a, b)]
    covered = [n for part in parts for a, b in part for n in range(a, b)]
    assert covered == nodes
    assert all(any(a0 <= a and b <= b0 for a0, b0 in ranges) and a < b for part in parts for a, b in part)
    sizes = [sum(b - a for a, b in part) for part in parts]
    assert max(sizes) - min(sizes) <= 1
