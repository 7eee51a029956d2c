"""``crocopy bench --scaling``: time per iteration vs horizon, and peak memory of the hop.

Scaling.  The ANYmal trot of :func:`crocopy.problems.quadruped.build_gait` (default step: 2
support + 25 swing knots + 1 impulse per swing group, dt 10 ms) lengthened by its number of
gait cycles: ``cycles`` 1, 2, 4, 9, 18, 36 give T = 56 cycles + 2 = 58, 114, 226, 506, 1010 and
2018 nodes.  For each T, one Box-FDDP iteration is run from the builder's warm start (loads the
kernels, sets the iterate), then the work of one iteration is timed at that iterate, phase by
phase: ``problem.calc``, ``problem.calcDiff``, the backward pass (``computeDirection(False)``) and
one forward pass (``tryStep`` with the smallest line-search step: the same work as a full step,
which can diverge on the long horizons).  The iteration time is the sum of the phase medians over
``repeats`` rounds, the horizons interleaved within each round so that load drift hits them all.
The exponent ``b`` of ``log t = a + b log T`` is fitted by least squares (linear scaling: b = 1).

Memory.  A fresh Python subprocess imports crocopy, Pinocchio and the problem builders, reads its
peak resident set size, builds the 580-node hop (registry ``hop``, T = 592 with its impulse
nodes) and solves it with Box-FDDP (the registry's iteration budget), reading the peak after each
step.  Reported: the peak minus the post-import baseline after building and after solving.  The
peak is ``VmHWM`` of ``/proc/self/status`` (``resource.getrusage(RUSAGE_SELF).ru_maxrss`` where
that file does not exist): on Linux a child inherits its parent's ``ru_maxrss`` across fork and
exec, so after this process has built the long trots that figure would be the parent's.
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

from ..guards import trusted_path

__all__ = ["fit_exponent", "hop_memory", "run_scaling_bench", "time_iteration"]

CYCLES = (1, 2, 4, 9, 18, 36)
"""Trot cycles of the scaling run (T = 56 cycles + 2)."""

PHASES = ("calc", "calcDiff", "backward", "forward")

_MEMORY_SCRIPT = """
import json, resource, sys, time


def peak():
    try:
        with open("/proc/self/status") as f:
            return int(f.read().split("VmHWM:")[1].split()[0]) * 1024
    except (OSError, IndexError):
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


import crocopy, crocopy.problems.quadruped
from crocopy.problems import registry

base = peak()
spec = registry.get("hop")
problem, xs, us = spec.build()
built = peak()
solver = crocopy.SolverBoxFDDP(problem)
t0 = time.perf_counter()
converged = solver.solve(xs, us, int(sys.argv[1]) or spec.maxiter, False)
print(json.dumps({"baseline": base, "built": built, "solved": peak(), "T": problem.T, "iter": solver.iter,
                  "cost": solver.cost, "converged": converged, "seconds": time.perf_counter() - t0}))
"""


def fit_exponent(T: np.ndarray, t: np.ndarray) -> tuple[float, float]:
    """Least-squares fit of ``log t = a + b log T``; returns ``(a, b)``."""
    T, t = np.asarray(T, dtype=float), np.asarray(t, dtype=float)
    if T.shape != t.shape or T.ndim != 1 or T.size < 2:
        raise ValueError(f"T and t must be 1-D of the same length >= 2, got shapes {T.shape} and {t.shape}")
    b, a = np.polyfit(np.log(T), np.log(t), 1)
    return float(a), float(b)


def _phase_calls(solver) -> dict:
    problem, xs, us = solver.problem, solver.xs, solver.us
    return {
        "calc": lambda: problem.calc(xs, us),
        "calcDiff": lambda: problem.calcDiff(xs, us),
        "backward": lambda: solver.computeDirection(False),
        "forward": lambda: solver.tryStep(solver.alphas[-1]),
    }


def time_iteration(solver) -> dict[str, float]:
    """Seconds of each phase of one iteration at the solver's current iterate (one call each, in order)."""
    out = {}
    with trusted_path():  # timed as a solve runs them, without a user's call checks
        for name, call in _phase_calls(solver).items():
            t0 = time.perf_counter()
            call()
            out[name] = time.perf_counter() - t0
    return out


def _scaling(cycles: tuple[int, ...], repeats: int) -> list[dict]:
    import crocopy
    from crocopy.problems.quadruped import build_gait

    rows = []
    for c in cycles:
        problem, xs, us = build_gait(crocopy, "trot", cycles=c)
        solver = crocopy.SolverBoxFDDP(problem)
        solver.solve(xs, us, 1, False)
        rows.append({"cycles": c, "T": problem.T, "solver": solver, "samples": {p: [] for p in PHASES}})
    for _ in range(repeats):
        for row in rows:
            for name, seconds in time_iteration(row["solver"]).items():
                row["samples"][name].append(seconds)
    for row in rows:
        row["phases"] = {p: statistics.median(v) for p, v in row.pop("samples").items()}
        row["iteration"] = sum(row["phases"].values())
        del row["solver"]
    return rows


def hop_memory(maxiter: int = 0) -> dict:
    """Peak RSS (bytes) of building and solving the hop in a subprocess (see the module docstring)."""
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    with tempfile.TemporaryDirectory() as cwd:  # a source checkout in the cwd would shadow the installed package
        out = subprocess.run(
            [sys.executable, "-c", _MEMORY_SCRIPT, str(maxiter)],
            capture_output=True, text=True, env=env, check=False, cwd=cwd,
        )
    if out.returncode:
        raise RuntimeError(f"hop memory subprocess failed:\n{out.stderr[-2000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def run_scaling_bench(
    repeats: int = 3, cycles: tuple[int, ...] = CYCLES, memory: bool = True, maxiter: int = 0
) -> dict:
    """Print and return the scaling table, the fitted exponent and the hop's peak memory.

    Parameters
    ----------
    repeats : int
        Timing rounds per horizon (median reported).
    cycles : tuple of int
        Trot cycles (T = 56 cycles + 2).
    memory : bool
        Also run the hop memory subprocess.
    maxiter : int
        Iteration budget of the hop solve (0: the registry's).

    Returns
    -------
    dict
        ``rows`` (per horizon: ``T``, ``phases`` seconds, ``iteration`` seconds), ``exponent`` and
        per-phase ``exponents``, and ``memory`` (from :func:`hop_memory`) when requested.
    """
    if repeats < 1 or len(cycles) < 2:
        raise ValueError(f"repeats must be positive and cycles have >= 2 entries, got {repeats}, {cycles}")
    print(f"crocopy bench --scaling: ANYmal trot, Box-FDDP, one iteration (median of {repeats}) vs horizon T")
    rows = _scaling(tuple(cycles), repeats)
    print(f"  {'T':>5s} " + " ".join(f"{p + ' ms':>12s}" for p in PHASES) + f" {'iter ms':>10s} {'us/node':>8s}")
    for r in rows:
        ms = " ".join(f"{1e3 * r['phases'][p]:12.2f}" for p in PHASES)
        print(f"  {r['T']:5d} {ms} {1e3 * r['iteration']:10.2f} {1e6 * r['iteration'] / r['T']:8.1f}")
    T = np.array([r["T"] for r in rows])
    _, b = fit_exponent(T, [r["iteration"] for r in rows])
    exponents = {p: fit_exponent(T, [r["phases"][p] for r in rows])[1] for p in PHASES}
    print(
        f"  fit log t = a + b log T: b = {b:.3f} (target <= 1.1); per phase "
        + ", ".join(f"{p} {e:.3f}" for p, e in exponents.items())
    )
    out = {"rows": rows, "exponent": b, "exponents": exponents}
    if memory:
        m = hop_memory(maxiter)
        gib = 1024.0**3
        print(
            f"  hop (T = {m['T']}): peak RSS above the post-import baseline ({m['baseline'] / 2**20:.0f} MiB):"
            f" built {(m['built'] - m['baseline']) / 2**20:.0f} MiB, solved"
            f" {(m['solved'] - m['baseline']) / 2**20:.0f} MiB ({(m['solved'] - m['baseline']) / gib:.3f} GiB,"
            f" target < 1 GiB); Box-FDDP {m['iter']} iterations, cost {m['cost']:.6g},"
            f" {'converged' if m['converged'] else 'not converged'}, {m['seconds']:.1f} s"
        )
        out["memory"] = m
    return out
