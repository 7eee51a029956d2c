"""The oracle's Crocoddyl: 3.2.1 on the Pinocchio 4.0.0 it was compiled against (the ``bench`` extra).

A module that compares with Crocoddyl skips itself without it (``pytest.importorskip``) and uses the
``bench_crocoddyl`` fixture, which fails when the installed Crocoddyl/Pinocchio pair is not the bench
extra's (another pair computes other numbers or crashes).
"""

from __future__ import annotations

from types import ModuleType

import pytest

from crocopy.bench.side_by_side import BenchDependencyError, require_crocoddyl


@pytest.fixture(scope="session")
def bench_crocoddyl() -> ModuleType:
    """Crocoddyl of the bench extra, checked once per session."""
    try:
        return require_crocoddyl()
    except BenchDependencyError as exc:
        pytest.fail(str(exc))
