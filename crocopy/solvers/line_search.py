"""The DDP family's line search in one compiled call where it can run there (:func:`compiled_trials`).

From a feasible iterate, with every running node in one compiled range and a compiled terminal node, the trials of
the step lengths ``alphas`` run one after the other in a single call (the horizon's ``line_search``,
:func:`crocopy.models.rbd.line_search_kernel.line_search`) until one passes the solver's acceptance test, as the
Python loop of ``SolverDDP._iterate`` runs them one per ``tryStep``: the same trial states, controls, costs, ``dV``
and ``dVexp``, to the bit.  It applies to the solver classes that declare ``_line_search = (negative, bounded)`` in
their own body (DDP, FDDP, Box-DDP, Box-FDDP: a subclass may override a step of the loop, so it opts in explicitly),
while the profiler is off (it times each ``tryStep``) and no step length diverged lately (such a trial runs its
range in steps, :func:`.rollout.segment_rollout`).  A trial that is not finite hands the search back to the Python
loop at that step length.

From an infeasible iterate it runs for the classes that also declare ``_gap_search = (every, grad_negative)`` (FDDP,
Box-FDDP: :func:`crocopy.models.rbd.line_search_kernel.line_search_gaps`), which sets ``d`` as the trial's
``expectedImprovement`` does.
"""

from __future__ import annotations

import numpy as np

from .rollout import horizon_addresses
from .stopwatch import profiling

NONFINITE = 2
"""The kernel's status of a trial that was not finite (:data:`crocopy.models.rbd.line_search_kernel.NONFINITE`)."""
ACCEPTED = 0
"""The kernel's status of an accepted trial."""


def compiled_trials(solver, first: int) -> tuple[int, bool]:
    """Run the trials of ``solver.alphas[first:]`` in one compiled call where the search applies (module docstring);
    returns ``(next, accepted)``: the index of the first step length not yet tried (``first`` where the search did
    not apply; a trial that was not finite is to be tried again, on the Python loop's path) and whether the trial of
    ``alphas[next - 1]`` passed the acceptance test (``stepLength``, ``dV``, ``dVexp``, ``cost_try`` and the datas'
    costs are then the trial's, as after its ``tryStep``; so they are after a search that rejected every trial)."""
    cls = type(solver)
    rule = cls.__dict__.get("_line_search")
    gap_rule = cls.__dict__.get("_gap_search")
    nodes = solver._nodes
    alphas = solver.alphas[first:]
    feasible = solver.isFeasible
    if (rule is None or nodes is None or nodes.horizon is None or (not feasible and gap_rule is None) or profiling()
            or solver._last_trial_diverged or not len(alphas) or not solver._diverged_steps.isdisjoint(alphas)):
        return first, False
    negative, bounded = rule
    problem = solver.problem
    horizon = nodes.horizon
    out = solver.__dict__.get("_search_out")
    if out is None:
        out = solver._search_out = np.zeros(6)
    lbs, ubs = (solver._lb, solver._ub) if bounded else (None, None)
    at = horizon_addresses(solver, nodes, lbs, ubs)
    thresholds = (float(solver.th_grad), float(solver.th_acceptStep), float(getattr(solver, "th_acceptNegStep", 0.0)))
    steps = np.asarray(alphas, dtype=float)
    if feasible:
        d = solver.d
        found = horizon.line_search(at, nodes.terminal, steps, float(solver.cost), (float(d[0]), float(d[1])),
                                    thresholds, negative, out)
    elif solver._Vxx_f is not solver._Vxx_f_views:  # the gaps' Vxx f are not in the horizon buffer
        return first, False
    else:
        found = horizon.line_search_gaps(at, nodes.terminal, problem.x0, solver._terminal_step(),
                                         (solver._horizon.addr, solver._horizon.dims), steps, float(solver.cost),
                                         (float(solver._dg), float(solver._dq)), thresholds, gap_rule, out)
    if found is None:
        return first, False
    i, status = found
    solver._synced = False
    if status == NONFINITE:
        return first + i, False
    solver.stepLength = alphas[i]
    solver.cost_try, solver.dV, solver.dVexp = float(out[0]), float(out[2]), float(out[3])
    if not feasible:
        solver.d[0], solver.d[1] = out[4], out[5]
    for data, cost in zip(problem.runningDatas, horizon.costs.tolist()):
        data.cost = cost
    problem.terminalData.cost = float(out[1])
    return first + i + 1, status == ACCEPTED
