"""Ten quadrotor solves (Box-FDDP paper Fig. 7 starts) on a Dask cluster of two worker processes."""

import time

from dask.distributed import Client, LocalCluster

import crocopy
from crocopy.experiments.box_fddp import initial_positions
from crocopy.problems import registry

if __name__ == "__main__":  # Dask starts its workers as new processes: guard the script's work
    builder = registry.get("quad-goal").build  # picklable: ProblemSpec.build(**overrides)
    params = [{"x0_position": tuple(p)} for p in initial_positions(10)]
    with LocalCluster(n_workers=2, threads_per_worker=1) as cluster, Client(cluster) as client:
        # on several machines: Client("tcp://SCHEDULER:8786"), after `dask scheduler` on one machine
        # and `dask worker tcp://SCHEDULER:8786 --nthreads 1` on each of the others
        t0 = time.perf_counter()
        results = crocopy.solve_many(builder, params, client.get_executor(), maxiter=300)
        elapsed = time.perf_counter() - t0
    best = min(results, key=lambda r: r.cost)
    print(f"{len(results)} solves in {elapsed:.1f} s; best start {best.params['x0_position']}, cost {best.cost:.4g}")
