"""Trend checks of ``crocopy table1`` (:mod:`crocopy.experiments.table1`) on synthetic rows."""

import pytest

from crocopy.experiments.table1 import BOXDDP_MUST_FAIL, TIE_RTOL, RowResult, format_trend, trend_checks


def _rows(**overrides):
    """Paper-like rows: Box-DDP fails on pend/jump/hop/bar, Box-FDDP solves all with a lower cost."""
    rows = {}
    for name in ("pend", "quad-goal", "quad-loop", "man", "jump", "hop", "bar"):
        rows[name] = {"boxddp": RowResult(100, 2.0, name not in BOXDDP_MUST_FAIL), "boxfddp": RowResult(50, 1.0, True)}
    rows.update(overrides)
    return rows


def test_paper_trend_holds():
    checks = trend_checks(_rows())
    assert [c.holds for c in checks] == [True, True, True]
    assert all(c.offending == () for c in checks)
    text = format_trend(checks)
    assert text.count(": yes") == 3 and "1e-06" in text


def test_each_check_names_its_offending_rows():
    rows = _rows(
        **{
            "quad-loop": {"boxddp": RowResult(250, 0.07, True), "boxfddp": RowResult(120, 0.2236, True)},
            "hop": {"boxddp": RowResult(40, 9.0, True), "boxfddp": RowResult(200, 5.0, False)},
        }
    )
    solves, fails, costs = trend_checks(rows)
    assert (solves.holds, solves.offending) == (False, ("hop",))
    assert (fails.holds, fails.offending) == (False, ("hop",))
    assert (costs.holds, costs.offending) == (False, ("quad-loop",))
    text = format_trend([solves, fails, costs])
    assert "no (hop)" in text and "no (quad-loop)" in text


@pytest.mark.parametrize(("excess", "holds"), [(0.5, True), (1.0, True), (2.0, False)])
def test_cost_tie_is_relative(excess, holds):
    ddp = 811.22359
    fddp = ddp * (1.0 + excess * TIE_RTOL)
    rows = _rows(taichi={"boxddp": RowResult(80, ddp, True), "boxfddp": RowResult(14, fddp, True)})
    assert trend_checks(rows)[2].holds is holds


def test_rows_not_run_are_reported():
    rows = {"pend": _rows()["pend"]}
    solves, fails, costs = trend_checks(rows, expected=("pend", "jump"))
    assert solves.offending == ("jump (not run)",)
    assert fails.offending == ("jump (not run)", "hop (not run)", "bar (not run)")
    assert costs.holds


def test_row_needs_both_solvers():
    with pytest.raises(KeyError, match="boxddp"):
        trend_checks({"pend": {"boxfddp": RowResult(1, 1.0, True)}})
