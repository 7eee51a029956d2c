"""A UR5 reaches for a point outside a box its end effector must stay in: a penalty (FDDP) or a hard
constraint (CSQP); and torque bounds by Box-FDDP or as constraint rows (CSQP).  ``--plot`` writes
``constrained_reach.png``."""

import example_robot_data
import numpy as np

import crocopy

robot = example_robot_data.load("ur5")
state = crocopy.StateMultibody(robot.model)
actuation = crocopy.ActuationModelFull(state)
nu, fid = actuation.nu, robot.model.getFrameId("tool0")
x0 = np.r_[0.0, -1.0, 1.5, -0.5, 1.0, 0.0, np.zeros(6)]
target = np.array([0.4, 0.4, 0.4])
box_lb, box_ub = np.array([0.3, -1.0, 0.1]), np.array([1.0, 0.25, 0.6])  # y <= 0.25 excludes the target
T, dt = 40, 0.02


def build(box="constraint", torque=None):
    """box: "constraint" (hard rows), "penalty" (quadratic barrier cost) or None; torque: bound or None."""
    def node(terminal):
        costs = crocopy.CostModelSum(state, nu)
        goal = crocopy.ResidualModelFrameTranslation(state, fid, target, nu)
        costs.addCost("goal", crocopy.CostModelResidual(state, goal), 1e3 if terminal else 1e1)
        xreg = crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, x0, nu))
        costs.addCost("state", xreg, 1e1 if terminal else 1e-1)
        if not terminal:
            costs.addCost("control", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, nu)), 1e-3)
        constraints = crocopy.ConstraintModelManager(state, nu)
        position = crocopy.ResidualModelFrameTranslation(state, fid, np.zeros(3), nu)
        if box == "constraint":
            constraints.addConstraint("box", crocopy.ConstraintModelResidual(state, position, box_lb, box_ub))
        elif box == "penalty":
            barrier = crocopy.ActivationModelQuadraticBarrier(crocopy.ActivationBounds(box_lb, box_ub))
            costs.addCost("box", crocopy.CostModelResidual(state, barrier, position), 1e4)
        if torque is not None and not terminal:
            control = crocopy.ResidualModelControl(state, nu)
            constraints.addConstraint("torque", crocopy.ConstraintModelResidual(
                state, control, -torque * np.ones(nu), torque * np.ones(nu)))
        dam = crocopy.DifferentialActionModelFreeFwdDynamics(state, actuation, costs, constraints)
        return crocopy.IntegratedActionModelEuler(dam, 0.0 if terminal else dt)

    return crocopy.ShootingProblem(x0, [node(False) for _ in range(T)], node(True))


def end_effector(problem, xs):
    """End-effector positions along ``xs`` (after ``problem.calc``)."""
    problem.calc(xs, problem.quasiStatic(xs[:-1]))
    data = robot.model.createData()
    import pinocchio

    out = []
    for x in xs:
        pinocchio.framesForwardKinematics(robot.model, data, x[: robot.model.nq])
        out.append(data.oMf[fid].translation.copy())
    return np.array(out)


def report(name, solver, problem):
    ee = end_effector(problem, list(solver.xs))
    print(f"{name:32s} iterations={solver.iter:3d} cost={solver.cost:.4f} "
          f"max y={ee[:, 1].max():.4f} max |u|={np.abs(np.array(solver.us)).max():.2f}")
    return ee


guess = ([x0] * (T + 1), [np.zeros(nu)] * T)

# 1. The box as a penalty: FDDP ignores the constraint rows; the barrier cost pushes back, softly.
penalty = build(box="penalty")
fddp = crocopy.SolverFDDP(penalty)
fddp.solve(*guess, 200)
ee_penalty = report("FDDP, box as a penalty (1e4)", fddp, penalty)

# 2. The box as a hard constraint: CSQP keeps the end effector inside (to the QP's accuracy, here
#    eps_abs = 1e-5: the default 1e-4 converges too, in more iterations).
hard = build(box="constraint")
csqp = crocopy.SolverCSQP(hard)
csqp.termination_tolerance = 1e-4
csqp.eps_abs, csqp.eps_rel = 1e-5, 0.0
csqp.solve(*guess, 200)
ee_hard = report("CSQP, box as a constraint", csqp, hard)

# 3. Torque bounds: Box-FDDP reads u_lb/u_ub; CSQP takes them as rows.  Same optimum.
bounded = build(box=None)
for m in bounded.runningModels:
    m.u_lb, m.u_ub = -50.0 * np.ones(nu), 50.0 * np.ones(nu)
box_fddp = crocopy.SolverBoxFDDP(bounded)
box_fddp.th_stop = 1e-12
box_fddp.solve(*guess, 200)
report("Box-FDDP, |u| <= 50", box_fddp, bounded)
rows = build(box=None, torque=50.0)
csqp_rows = crocopy.SolverCSQP(rows)
csqp_rows.eps_abs, csqp_rows.eps_rel = 1e-6, 0.0
csqp_rows.solve(*guess, 200)
report("CSQP, |u| <= 50 as rows", csqp_rows, rows)

if __name__ == "__main__" and "--plot" in __import__("sys").argv:
    import matplotlib.pyplot as plt

    time = dt * np.arange(T + 1)
    fig, ax = plt.subplots(figsize=(6, 3))
    ax.plot(time, ee_penalty[:, 1], label="FDDP, penalty")
    ax.plot(time, ee_hard[:, 1], label="CSQP, constraint")
    ax.axhline(box_ub[1], color="k", linestyle="--", linewidth=1, label="box: y <= 0.25")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("end effector y [m]")
    ax.legend()
    fig.tight_layout()
    fig.savefig("constrained_reach.png", dpi=110)
