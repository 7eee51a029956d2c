"""Box-FDDP against Box-DDP on the fast bundled problems, with the gap-contraction plot (Box-FDDP paper Fig. 4)."""

import crocopy
from crocopy.callbacks.plotting import plot_feasibility
from crocopy.problems import registry

for name in ("pend", "arm", "quad-goal", "trot-short"):
    spec = registry.get(name)
    loggers = {}
    for solver_name in ("SolverBoxFDDP", "SolverBoxDDP"):
        problem, xs, us = spec.build(crocopy)
        solver = getattr(crocopy, solver_name)(problem)
        logger = crocopy.CallbackLogger()
        solver.setCallbacks([logger])
        ok = solver.solve(xs, us, spec.maxiter, False)
        loggers[solver_name] = logger
        print(f"{name:10s} {solver_name:14s} solved={spec.solved(ok, solver.cost)!s:5s} "
              f"iterations={solver.iter:4d} cost={solver.cost:.6g}")
    plot_feasibility(loggers, f"{name}_gaps.png", title=name)
    print(f"  gap norms per iteration plotted in {name}_gaps.png")
