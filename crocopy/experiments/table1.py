"""Box-FDDP paper Table I: the trend checks of ``crocopy table1``.

The paper (Mastalli et al., *Control-limited feasibility-driven DDP*, Table I) solves nine problems
with Box-DDP and Box-FDDP.  Our problems are our own designs (weights, horizons and geometry the
paper does not give), so the absolute numbers differ; the bar is the paper's *trend*:

1. Box-FDDP solves every row;
2. Box-DDP fails at least on ``pend``, ``jump``, ``hop`` and ``bar`` (:data:`BOXDDP_MUST_FAIL`);
3. Box-FDDP's final cost is at most Box-DDP's on every row, where a relative tie of
   :data:`TIE_RTOL` (``1e-6``) counts as equal: ``cost_fddp - cost_ddp <= 1e-6 * |cost_ddp|``.
   When both solvers converge to the same minimum their costs differ by round-off only (the Talos
   rows: ~1e-9 relative), which is not a trend.

A row is ``{"boxddp": RowResult, "boxfddp": RowResult}``; :func:`trend_checks` returns the three
checks with their offending rows and :func:`format_trend` renders them after the table.  A check
over rows that were not run (``crocopy table1 pend``) fails and names them "not run".
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

__all__ = ["BOXDDP_MUST_FAIL", "TIE_RTOL", "RowResult", "TrendCheck", "format_trend", "trend_checks"]

TIE_RTOL = 1e-6
"""Relative cost tie: Box-FDDP's cost may exceed Box-DDP's by this fraction of it."""

BOXDDP_MUST_FAIL = ("pend", "jump", "hop", "bar")
"""Rows where the paper's Box-DDP finds no solution."""


@dataclass(frozen=True)
class RowResult:
    """One solver's result on one row: iterations, final cost and whether it found a solution."""

    iters: int
    cost: float
    solved: bool


@dataclass(frozen=True)
class TrendCheck:
    """A trend check: its statement, whether it holds, and the rows that break it."""

    statement: str
    holds: bool
    offending: tuple[str, ...]


def _cost_ok(fddp: float, ddp: float) -> bool:
    return fddp - ddp <= TIE_RTOL * abs(ddp)


def trend_checks(
    rows: Mapping[str, Mapping[str, RowResult]], expected: tuple[str, ...] | None = None
) -> list[TrendCheck]:
    """The three trend checks of Table I on ``rows`` (name → ``{"boxddp", "boxfddp"}`` results).

    Parameters
    ----------
    rows : mapping
        Problem name → ``{"boxddp": RowResult, "boxfddp": RowResult}``.
    expected : tuple of str, optional
        Rows the first check needs (default: the rows given).  Missing ones are offending
        ("name (not run)").

    Returns
    -------
    list of TrendCheck
        Box-FDDP solves all; Box-DDP fails on :data:`BOXDDP_MUST_FAIL`; Box-FDDP cost <= Box-DDP cost.
    """
    for name, row in rows.items():
        if set(row) != {"boxddp", "boxfddp"}:
            raise KeyError(f"rows[{name!r}] must have the keys 'boxddp' and 'boxfddp', got {sorted(row)}")
    expected = tuple(rows) if expected is None else expected
    missing = tuple(f"{n} (not run)" for n in expected if n not in rows)
    solves = tuple(n for n, r in rows.items() if not r["boxfddp"].solved)
    fails = tuple(
        f"{n} (not run)" if n not in rows else n for n in BOXDDP_MUST_FAIL if n not in rows or rows[n]["boxddp"].solved
    )
    costs = tuple(n for n, r in rows.items() if not _cost_ok(r["boxfddp"].cost, r["boxddp"].cost))
    return [
        TrendCheck(f"Box-FDDP solves all {len(expected)} rows", not (solves or missing), solves + missing),
        TrendCheck(f"Box-DDP fails at least on {', '.join(BOXDDP_MUST_FAIL)}", not fails, fails),
        TrendCheck(f"Box-FDDP cost <= Box-DDP cost on every row (relative tie {TIE_RTOL:g} allowed)", not costs, costs),
    ]


def format_trend(checks: list[TrendCheck]) -> str:
    """Markdown lines ``- statement: yes`` or ``- statement: no (rows)`` under a heading."""
    lines = ["", "Trend of the paper's Table I:"]
    for c in checks:
        lines.append(f"- {c.statement}: {'yes' if c.holds else 'no (' + ', '.join(c.offending) + ')'}")
    return "\n".join(lines)
