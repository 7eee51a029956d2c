"""Composing a problem: a Kinova arm reaching a point, built from crocopy's pieces."""

import example_robot_data
import numpy as np
import pinocchio as pin

import crocopy

robot = example_robot_data.load("kinova")
model = robot.model
frame = model.getFrameId("j2s6s200_end_effector")
target = np.array([0.4, 0.3, 0.6])
q0 = model.referenceConfigurations["arm_up"]
x0 = np.concatenate([q0, np.zeros(model.nv)])

# State and actuation: x = (q, v) on the robot's configuration manifold, all joints actuated.
state = crocopy.StateMultibody(model)
actuation = crocopy.ActuationModelFull(state)
nu = actuation.nu


def node(dt: float, terminal: bool = False) -> crocopy.IntegratedActionModelEuler:
    """One node: costs -> differential action model -> integrated action model."""
    costs = crocopy.CostModelSum(state, nu)
    reach = crocopy.CostModelResidual(state, crocopy.ResidualModelFrameTranslation(state, frame, target, nu))
    posture = crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, x0, nu))
    costs.addCost("reach", reach, 1e4 if terminal else 1e1)
    costs.addCost("posture", posture, 1e1 if terminal else 1e-1)
    if not terminal:
        effort = crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, nu))
        costs.addCost("effort", effort, 1e-3)
    dam = crocopy.DifferentialActionModelFreeFwdDynamics(state, actuation, costs)
    iam = crocopy.IntegratedActionModelEuler(dam, dt)
    iam.u_lb, iam.u_ub = -model.effortLimit, model.effortLimit  # torque limits for the box solvers
    return iam


T, dt = 100, 1e-2
problem = crocopy.ShootingProblem(x0, [node(dt) for _ in range(T)], node(0.0, terminal=True))

solver = crocopy.SolverBoxFDDP(problem)
solver.setCallbacks([crocopy.CallbackVerbose()])
xs = [x0] * (T + 1)
us = problem.quasiStatic(xs[:-1])  # gravity-compensating torques as the warm start
solver.solve(xs, us, 100, False)

data = model.createData()
pin.framesForwardKinematics(model, data, solver.xs[-1][: model.nq])
print(f"{solver.iter} iterations, cost {solver.cost:.4g}, "
      f"end effector {1e3 * np.linalg.norm(data.oMf[frame].translation - target):.1f} mm from the target")
