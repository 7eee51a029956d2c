"""Oracle: mim-solvers 0.3.0's own example scripts run to their end with crocopy in its place
(issue 26's bar), and agree with mim-solvers' own runs (bench extra).

The scripts come from mim-solvers' sdist on PyPI (:mod:`crocopy.bench.mim_examples` downloads it once,
checks its sha256 and caches it); a failed download fails the test with its reason.  Each run of
:data:`~crocopy.bench.mim_examples.JOBS` is made in a subprocess with ``crocoddyl`` and ``mim_solvers``
bound to crocopy, and with Crocoddyl 3.2.1 and mim-solvers 0.3.0.  Both must end alike (the three
scripts to their end; ``humanoid_taichi-fddp`` at the script's own error, as with mim-solvers), with the
same solves: same solver and convergence, at most mim-solvers' iterations + 10 %, its final cost within
1e-6 relative and its KKT residual within 1e-3 relative (issue 26's bar for the comparison problems).
Measured: the same iterations, costs within 1e-13 and KKT within 1e-6 relative.  The eight subprocesses
take about 50 s of CPU in all (solo12 about 10 s with each library); the two of a run go side by side.
"""

from __future__ import annotations

import math
import pathlib
from concurrent.futures import ThreadPoolExecutor

import pytest

pytest.importorskip("crocoddyl")
pytest.importorskip("mim_solvers")

from crocopy.bench import mim_examples as mx  # noqa: E402

pytestmark = pytest.mark.usefixtures("bench_crocoddyl")

@pytest.fixture(scope="module")
def examples(tmp_path_factory) -> pathlib.Path:
    """The sdist's examples, extracted (downloaded first when not in the user cache)."""
    try:
        sdist = mx.fetch_sdist()
    except mx.SdistError as exc:
        pytest.fail(f"mim-solvers' examples come from its sdist on PyPI, which could not be fetched: {exc}")
    return mx.extract_examples(sdist, tmp_path_factory.mktemp("mim-examples"))


@pytest.mark.parametrize("job", list(mx.JOBS))
def test_example_ends_and_agrees_with_mim_solvers(examples, job):
    with ThreadPoolExecutor(2) as pool:  # the two subprocesses side by side (CI has two cores)
        mine, theirs = pool.map(lambda library: mx.run_job(library, job, examples, timeout=600), mx.LIBRARIES)
    assert theirs.solves, theirs
    assert mx.same_end(mine, theirs), (mine, theirs)
    if job in mx.SCRIPTS:
        assert mine.ok, mine
    assert len(mine.solves) == len(theirs.solves), (mine.solves, theirs.solves)
    for a, b in zip(mine.solves, theirs.solves):
        assert (a["solver"], a["converged"]) == (b["solver"], b["converged"]), (a, b)
        assert a["iter"] <= math.ceil(1.1 * b["iter"]), (a, b)
        assert a["cost"] == pytest.approx(b["cost"], rel=1e-6), (a, b)
        assert (a["KKT"] is None) == (b["KKT"] is None), (a, b)
        if b["KKT"] is not None:
            assert a["KKT"] == pytest.approx(b["KKT"], rel=1e-3), (a, b)
