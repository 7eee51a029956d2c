"""``crocopy.solve_many`` on a real distributed engine: a Dask ``LocalCluster`` of 2 worker processes.

The same quadrotor goal solves (Box-FDDP paper Fig. 7 starts, few iterations) run through a Dask
client's executor and through the default local process pool; the results must be the same
numbers.  Needs the ``distributed`` extra (``pip install ".[distributed]"``): skipped without it,
failed in CI (see ``conftest.py``).
"""

from __future__ import annotations

import os

import numpy as np
import pytest
from optional_requirements import require_module, skip_without_module

import crocopy
from crocopy.experiments.box_fddp import initial_positions
from crocopy.problems import registry

pytestmark = skip_without_module("distributed", "distributed")
STARTS = 4
MAXITER = 15


@pytest.fixture(scope="module")
def dask_client():
    """A client of a 2-process ``LocalCluster``, one thread per worker."""
    distributed = require_module("distributed", "distributed")
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    with cluster, distributed.Client(cluster) as client:
        yield client


def test_solve_many_on_a_dask_cluster_equals_the_local_process_pool(dask_client):
    workers = dask_client.scheduler_info()["workers"]
    assert len(workers) == 2 and all(w["nthreads"] == 1 for w in workers.values())
    builder = registry.get("quad-goal").build
    params = [{"x0_position": tuple(p)} for p in initial_positions(STARTS)]
    on_dask = crocopy.solve_many(builder, params, dask_client.get_executor(), maxiter=MAXITER)
    local = crocopy.solve_many(builder, params, maxiter=MAXITER, max_workers=2)
    assert len(on_dask) == len(local) == STARTS
    for d, p, start in zip(on_dask, local, params, strict=True):
        assert d.params == p.params == start
        assert (d.iter, d.converged, d.reason) == (p.iter, p.converged, p.reason)
        assert d.cost == p.cost
        np.testing.assert_array_equal(np.array(d.xs), np.array(p.xs))
        np.testing.assert_array_equal(np.array(d.us), np.array(p.us))
    assert len({round(r.cost, 12) for r in on_dask}) == STARTS  # the starts differ, so do the solutions
    pids = dask_client.run(os.getpid)
    assert len(set(pids.values())) == 2 and os.getpid() not in pids.values()  # two worker processes


def test_a_failing_task_on_dask_names_its_params(dask_client):
    builder = registry.get("quad-goal").build
    params = [{"x0_position": (0.0, 0.0, 0.0)}, {"no_such_argument": 1}]
    with pytest.raises(crocopy.SolveManyError, match="solve 1 with params {'no_such_argument': 1}"):
        crocopy.solve_many(builder, params, dask_client.get_executor(), maxiter=2)
