"""Equality-constrained test problems for SolverIntro/SolverKKT, built through Crocoddyl's public API.

Each builder takes the library module (``crocopy`` or ``crocoddyl``) so that the oracle tests build
the same problem in both.
"""

from __future__ import annotations

import numpy as np


def lq_equality_problem(lib, T: int = 8, nx: int = 4, nu: int = 3, nh: int = 2, seed: int = 0):
    """LQR nodes with ``nh`` state-control equality rows ``H [x; u] + h = 0`` on every running node."""
    r = np.random.RandomState(seed)
    A = np.eye(nx) + 0.1 * r.randn(nx, nx)
    B = r.randn(nx, nu)
    Q, R, N = np.eye(nx), 0.1 * np.eye(nu), np.zeros((nx, nu))
    f, q, rr = r.randn(nx), r.randn(nx), r.randn(nu)
    G, g = np.zeros((0, nx + nu)), np.zeros(0)
    H, h = r.randn(nh, nx + nu), r.randn(nh)
    running = lib.ActionModelLQR(A, B, Q, R, N, G, H, f, q, rr, g, h)
    terminal = lib.ActionModelLQR(A, B, Q, R, N, f, q, rr)
    return lib.ShootingProblem(r.randn(nx), [running] * T, terminal)


def nonlinear_equality_model(lib):
    """Class of a node with nonlinear dynamics ``x' = A x + B u + a sin(x)`` and rows
    ``h = C x + D u + e + b Σ sin(u) + ½ b x₀²`` (analytic derivatives), written as a Crocoddyl user would."""

    class NonlinearEquality(lib.ActionModelAbstract):
        def __init__(self, nx: int, nu: int, nh: int, seed: int, a: float, b: float) -> None:
            lib.ActionModelAbstract.__init__(self, lib.StateVector(nx), nu, 0, 0, nh, 0, 0)
            r = np.random.RandomState(seed)
            self.A = np.eye(nx) + 0.1 * r.randn(nx, nx)
            self.B = r.randn(nx, nu)
            self.q, self.rr = r.randn(nx), r.randn(nu)
            self.C, self.D, self.e = r.randn(nh, nx), r.randn(nh, nu), r.randn(nh)
            self.a, self.b = a, b

        def calc(self, data, x, u=None):
            if u is None:
                data.cost = 0.5 * x @ x + self.q @ x
                return
            data.xnext[:] = self.A @ x + self.B @ u + self.a * np.sin(x)
            data.cost = 0.5 * x @ x + self.q @ x + 0.05 * u @ u + self.rr @ u
            data.h[:] = self.C @ x + self.D @ u + self.e + self.b * np.sin(u).sum() + 0.5 * self.b * x[0] ** 2

        def calcDiff(self, data, x, u=None):
            data.Lx[:] = x + self.q
            data.Lxx[:] = np.eye(x.size)
            if u is None:
                return
            data.Fx[:] = self.A + self.a * np.diag(np.cos(x))
            data.Fu[:] = self.B
            data.Lu[:] = 0.1 * u + self.rr
            data.Luu[:] = 0.1 * np.eye(u.size)
            data.Lxu[:] = 0.0
            Hx = self.C.copy()
            Hx[:, 0] += self.b * x[0]
            data.Hx[:] = Hx
            data.Hu[:] = self.D + self.b * np.cos(u)[None, :]

    return NonlinearEquality


def nonlinear_equality_problem(lib, T: int = 10, seed: int = 1, a: float = 0.8, b: float = 0.05):
    """``T`` nonlinear constrained nodes (4 states, 3 controls, 2 rows) and the warm start used with it."""
    cls = nonlinear_equality_model(lib)
    running = [cls(4, 3, 2, seed, a, b) for _ in range(T)]
    terminal = cls(4, 3, 2, seed, a, b)
    r = np.random.RandomState(seed + 100)
    problem = lib.ShootingProblem(r.randn(4), running, terminal)
    r = np.random.RandomState(seed + 7)
    return problem, [r.randn(4) for _ in range(T + 1)], [r.randn(3) for _ in range(T)]



def arm_problem(lib, T: int = 20, dt: float = 1e-2, aref=(0.5, -0.3, 0.2, 0.4, -0.1, 0.3, 0.2)):
    """Talos' arm (free forward dynamics, Euler): joint accelerations held at ``aref`` by equality rows
    (``ConstraintModelResidual(state, ResidualModelJointAcceleration)``, ``Hu = M⁻¹``) on every running
    node, state and control regularisation and a gripper target as costs."""
    import example_robot_data

    model = example_robot_data.load("talos_arm").model
    state = lib.StateMultibody(model)
    actuation = lib.ActuationModelFull(state)
    frame = model.getFrameId("gripper_left_joint")
    x0 = np.concatenate([np.array([0.17, -0.16, 0.0, -0.7, 0.0, 0.3, 0.0]), np.zeros(model.nv)])

    def dam(constrained: bool, terminal: bool):
        costs = lib.CostModelSum(state, actuation.nu)
        costs.addCost("x", lib.CostModelResidual(state, lib.ResidualModelState(state, x0, actuation.nu)), 1e-2)
        costs.addCost("u", lib.CostModelResidual(state, lib.ResidualModelControl(state, actuation.nu)), 1e-3)
        track = lib.ResidualModelFrameTranslation(state, frame, np.array([0.4, 0.2, 0.4]), actuation.nu)
        costs.addCost("track", lib.CostModelResidual(state, track), 1e2 if terminal else 1.0)
        constraints = lib.ConstraintModelManager(state, actuation.nu)
        if constrained:
            accel = lib.ResidualModelJointAcceleration(state, np.array(aref), actuation.nu)
            constraints.addConstraint("accel", lib.ConstraintModelResidual(state, accel))
        return lib.DifferentialActionModelFreeFwdDynamics(state, actuation, costs, constraints)

    running = [lib.IntegratedActionModelEuler(dam(True, False), dt) for _ in range(T)]
    terminal = lib.IntegratedActionModelEuler(dam(False, True), 0.0)
    return lib.ShootingProblem(x0, running, terminal)
