"""``setCandidate`` copies a checked warm start into the solver's own arrays, whichever path checks it (the stacked
fast path for finite float64 vectors of the right sizes, one by one otherwise): same values, same errors, nothing
written when one of ``xs``/``us`` is refused, and a warm start made of the solver's own arrays (shifted) is copied
as it was given."""

from __future__ import annotations

import numpy as np
import pytest

import crocopy
from crocopy.problems import arm


@pytest.fixture()
def solver():
    problem, xs, us = arm.build_arm_reaching(crocopy, nodes=6)
    s = crocopy.SolverFDDP(problem)
    rng = np.random.default_rng(0)
    s.setCandidate([x + 0.01 * rng.normal(size=x.shape) for x in xs], [u + rng.normal(size=u.shape) for u in us])
    return s


@pytest.mark.parametrize("shift", [1, -1], ids=["left", "right"])
def test_shifted_own_arrays_are_copied_as_given(solver, shift):
    xs, us = [x.copy() for x in solver.xs], [u.copy() for u in solver.us]

    def shifted(a):
        return a[1:] + [a[-1]] if shift == 1 else [a[0]] + a[:-1]

    solver.setCandidate(shifted(list(solver.xs)), shifted(list(solver.us)))
    for got, want in zip([*solver.xs, *solver.us], [*shifted(xs), *shifted(us)]):
        np.testing.assert_array_equal(got, want)


def test_column_vectors_and_lists_give_the_same_candidate(solver):
    xs, us = [x.copy() for x in solver.xs], [u.copy() for u in solver.us]
    solver.setCandidate([x.reshape(-1, 1) for x in xs], [list(u) for u in us])
    for got, want in zip([*solver.xs, *solver.us], [*xs, *us]):
        np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize("where", ["xs", "us"])
@pytest.mark.parametrize("bad", ["nan", "inf", "shape", "length"])
def test_refused_candidate_writes_nothing(solver, where, bad):
    before = [a.copy() for a in [*solver.xs, *solver.us]]
    xs, us = [x.copy() + 1.0 for x in solver.xs], [u.copy() + 1.0 for u in solver.us]
    given = xs if where == "xs" else us
    if bad == "nan":
        given[2][0] = np.nan
    elif bad == "inf":
        given[2][0] = np.inf
    elif bad == "shape":
        given[2] = np.zeros(given[2].shape[0] + 1)
    else:
        given.pop()
    with pytest.raises(ValueError, match=f"init_{where}"):
        solver.setCandidate(xs, us)
    for got, want in zip([*solver.xs, *solver.us], before):
        np.testing.assert_array_equal(got, want)
