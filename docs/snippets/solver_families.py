"""One problem, every solver family: the Kinova arm reaching a point, torques bounded."""

import crocopy
from crocopy.problems import registry

spec = registry.get("arm")  # costs "goal", "state", "control"; u_lb/u_ub = the URDF torque limits


def run(name, solver, xs, us, maxiter=100):
    converged = solver.solve(xs, us, maxiter, False)
    print(f"{name:28s} converged={converged!s:5s} iterations={solver.iter:3d} cost={solver.cost:.5g}")
    return solver


# DDP and FDDP ignore the bounds; Box-DDP and Box-FDDP keep every control inside them.
for cls in (crocopy.SolverDDP, crocopy.SolverFDDP, crocopy.SolverBoxDDP, crocopy.SolverBoxFDDP):
    problem, xs, us = spec.build()
    run(cls.__name__, cls(problem), xs, us)

# The naive clamping baseline of Tassa et al. (for comparison only): not a descent method, it needs
# more iterations than Box-DDP here and can stall on harder problems.
problem, xs, us = spec.build()
run("SolverClampedDDP (backward)", crocopy.SolverClampedDDP(problem, clamping="backward"), xs, us)

# Squashing: each running model sees unbounded controls through a smooth saturation.
problem, xs, us = spec.build()
squashed = [crocopy.ActionModelSquashed(m, "smooth-sat", m.u_lb, m.u_ub) for m in problem.runningModels]
run("squashed + SolverFDDP", crocopy.SolverFDDP(crocopy.ShootingProblem(problem.x0, squashed, problem.terminalModel)),
    xs, us)

# Hierarchical DDP: reaching first, then posture and effort.
problem, xs, us = spec.build()
run("SolverHDDP", crocopy.SolverHDDP(problem, [["goal"], ["state", "control"]]), xs, us)
