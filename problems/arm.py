"""Arm reaching: a fixed-base manipulator from example-robot-data moves its end effector to a point.

Kinova Gen2 (6 DoF, 3 continuous joints: nq = 9, nv = 6, nx = 15) by default, UR5 (6 DoF) as
an alternative.  Full actuation, free forward dynamics, explicit Euler.  Starts at rest in the
robot's reference posture; the warm start is that state at every node with quasi-static
(gravity-compensating) torques.

Costs (``0.5 ||r||^2`` activations times the weight; running costs multiplied by dt):

* running ``goal``: end-effector translation error, weight 1e1;
* running ``state``: state regularisation towards the start posture at rest, weight 1e-1;
* running ``control``: ``||u||^2``, weight 1e-3;
* terminal ``goal`` weight 1e4 and terminal ``state`` weight 1e1 (stops the arm at the goal).

Control bounds for the box solvers are the URDF effort limits.
"""

from __future__ import annotations

from collections.abc import Sequence
from types import ModuleType

import numpy as np

from .common import load_model

ARMS: dict[str, tuple[str, str | None]] = {
    "kinova": ("j2s6s200_end_effector", "arm_up"),
    "ur5": ("tool0", None),
    "talos_arm": ("gripper_left_joint", "half_sitting"),
}
"""Supported arms: end-effector frame and reference configuration (``None`` = a bent posture)."""


def build_arm_reaching(
    lib: ModuleType,
    robot: str = "kinova",
    target: Sequence[float] = (0.4, 0.3, 0.6),
    horizon: float = 1.0,
    nodes: int = 100,
) -> tuple[object, list, list]:
    """Reach ``target`` (world frame, metres) with the end effector in ``horizon`` seconds.

    Returns
    -------
    problem, xs, us
        ``ShootingProblem`` (kinova: T = 100, nx = 15, nu = 6) and the quasi-static warm start.
    """
    if robot not in ARMS:
        raise KeyError(f"robot must be one of {sorted(ARMS)}, got {robot!r}")
    target = np.asarray(target, dtype=float)
    if target.shape != (3,):
        raise ValueError(f"target must have shape (3,), got {target.shape}")
    if nodes < 1 or horizon <= 0:
        raise ValueError(f"need nodes >= 1 and horizon > 0, got nodes={nodes}, horizon={horizon}")
    frame, ref = ARMS[robot]
    model = load_model(robot)
    q0 = np.array(model.referenceConfigurations[ref]) if ref else np.array([0.0, -1.0, 1.5, -0.5, 1.0, 0.0])
    x0 = np.concatenate([q0, np.zeros(model.nv)])
    state = lib.StateMultibody(model)
    actuation = lib.ActuationModelFull(state)
    nu = actuation.nu
    fid = model.getFrameId(frame)
    dt = horizon / nodes

    def node(terminal: bool) -> object:
        costs = lib.CostModelSum(state, nu)
        goal = lib.CostModelResidual(state, lib.ResidualModelFrameTranslation(state, fid, target, nu))
        xreg = lib.CostModelResidual(state, lib.ResidualModelState(state, x0, nu))
        costs.addCost("goal", goal, 1e4 if terminal else 1e1)
        costs.addCost("state", xreg, 1e1 if terminal else 1e-1)
        if not terminal:
            costs.addCost("control", lib.CostModelResidual(state, lib.ResidualModelControl(state, nu)), 1e-3)
        dam = lib.DifferentialActionModelFreeFwdDynamics(state, actuation, costs)
        iam = lib.IntegratedActionModelEuler(dam, 0.0 if terminal else dt)
        for m in (dam, iam):
            m.u_lb = -model.effortLimit.copy()
            m.u_ub = model.effortLimit.copy()
        return iam

    running = [node(False) for _ in range(nodes)]
    problem = lib.ShootingProblem(x0, running, node(True))
    xs = [x0.copy() for _ in range(nodes + 1)]
    us = list(problem.quasiStatic(xs[:-1]))
    return problem, xs, us
