"""Under-actuated double-pendulum swing-up (Box-FDDP paper §IV-A1, "pend").

The double pendulum of example-robot-data (two revolute joints about x, 0.6 kg) starts hanging
down at rest, ``x0 = (pi, 0, 0, 0)``, and must reach the upright equilibrium ``(0, 0, 0, 0)``.
Only one joint is actuated (the elbow by default, an acrobot) and its torque is bounded to ±5 N m.
Horizon 1 s with 100 nodes (dt = 10 ms, explicit Euler).  The warm start is cold: the hanging
state at every node and zero torque.

Costs (``0.5 ||r||^2`` activations times the weight, running costs multiplied by dt):

* running ``state``: weighted state error to upright, weights ``(1, 1, 0.1, 0.1)``, weight 1e-2;
* running ``control``: ``||u||^2``, weight 1e-3;
* terminal ``state``: same residual, weight 1e3.

The actuation ``tau = (0, u)`` (elbow) is crocopy's ``ActuationModelLinear``, which its compiled nodes
take; Crocoddyl has no built-in equivalent, so its problem gets a Python subclass of
``ActuationModelAbstract``, as in Crocoddyl's own double-pendulum example (``python_actuation=True``
gives crocopy that class too).
"""

from __future__ import annotations

import functools
import importlib
from types import ModuleType

import numpy as np

from .common import load_model


@functools.cache
def _actuation_class(lib: ModuleType) -> type:
    """One-joint actuation ``tau = S u`` written in Python on ``lib.ActuationModelAbstract`` (one class per lib),
    as Crocoddyl's own double-pendulum example does: Crocoddyl has no built-in actuation for it."""

    class ActuationModelSingleJoint(lib.ActuationModelAbstract):
        """Actuation of joint ``joint`` only: ``tau = e_joint u`` (nu = 1)."""

        def __init__(self, state: object, joint: int) -> None:
            lib.ActuationModelAbstract.__init__(self, state, 1)
            self.joint = joint
            self._S = np.zeros((state.nv, 1))
            self._S[joint, 0] = 1.0

        def __reduce__(self) -> tuple:
            return _single_joint_actuation, (lib.__name__, self.state, self.joint)

        def calc(self, data: object, x: np.ndarray, u: np.ndarray | None = None) -> None:
            data.tau[:] = 0.0
            if u is not None:
                data.tau[self.joint] = u[0]

        def calcDiff(self, data: object, x: np.ndarray, u: np.ndarray | None = None) -> None:
            dtau_du = data.dtau_du
            dtau_du[...] = self._S.reshape(dtau_du.shape)

        def commands(self, data: object, x: np.ndarray, tau: np.ndarray) -> None:
            data.u[:] = tau[self.joint]

        def torqueTransform(self, data: object, x: np.ndarray, u: np.ndarray) -> None:
            Mtau = data.Mtau
            Mtau[...] = self._S.T.reshape(Mtau.shape)

    return ActuationModelSingleJoint


def _single_joint_actuation(lib_name: str, state: object, joint: int) -> object:
    """Rebuild a pickled single-joint actuation (its class is local to :func:`_actuation_class`)."""
    return _actuation_class(importlib.import_module(lib_name))(state, joint)


def single_joint_actuation(lib: ModuleType, state: object, joint: int, python: bool = False) -> object:
    """Actuation of joint ``joint`` only (``nu = 1``): ``lib.ActuationModelLinear`` where ``lib`` has it
    (crocopy), else, or when ``python``, the Python class of :func:`_actuation_class` (Crocoddyl)."""
    if python or not hasattr(lib, "ActuationModelLinear"):
        return _actuation_class(lib)(state, joint)
    selection = np.zeros((state.nv, 1))
    selection[joint, 0] = 1.0
    return lib.ActuationModelLinear(state, selection)


def build_pendulum(
    lib: ModuleType,
    actuated_joint: int = 1,
    torque_limit: float = 5.0,
    horizon: float = 1.0,
    nodes: int = 100,
    weights: tuple[float, float, float] = (1e-2, 1e-3, 1e3),
    python_actuation: bool = False,
) -> tuple[object, list, list]:
    """Double-pendulum swing-up with one actuated joint and ±``torque_limit`` N m.

    Parameters
    ----------
    lib : module
        ``crocopy`` or ``crocoddyl``.
    actuated_joint : int
        0 (shoulder, "pendubot") or 1 (elbow, "acrobot").
    torque_limit : float
        Symmetric control bound seen by the box solvers.
    horizon, nodes : float, int
        Duration (s) and number of running nodes (dt = horizon / nodes).
    weights : tuple of float
        Running state, running control and terminal state weights.
    python_actuation : bool
        Use the Python actuation class (as Crocoddyl's example does) even where ``lib`` has
        ``ActuationModelLinear``; crocopy then keeps these nodes on its Python path.

    Returns
    -------
    problem, xs, us
        ``ShootingProblem`` (T = ``nodes``, nx = 4, nu = 1) and a cold start.
    """
    if actuated_joint not in (0, 1):
        raise ValueError(f"actuated_joint must be 0 or 1, got {actuated_joint}")
    if nodes < 1 or horizon <= 0:
        raise ValueError(f"need nodes >= 1 and horizon > 0, got nodes={nodes}, horizon={horizon}")
    model = load_model("double_pendulum")
    state = lib.StateMultibody(model)
    actuation = single_joint_actuation(lib, state, actuated_joint, python_actuation)
    x0 = np.array([np.pi, 0.0, 0.0, 0.0])
    x_up = np.zeros(4)
    w_state, w_control, w_terminal = weights
    act = lib.ActivationModelWeightedQuad(np.array([1.0, 1.0, 0.1, 0.1]))
    dt = horizon / nodes

    def node(terminal: bool) -> object:
        costs = lib.CostModelSum(state, 1)
        x_cost = lib.CostModelResidual(state, act, lib.ResidualModelState(state, x_up, 1))
        costs.addCost("state", x_cost, w_terminal if terminal else w_state)
        if not terminal:
            costs.addCost("control", lib.CostModelResidual(state, lib.ResidualModelControl(state, 1)), w_control)
        dam = lib.DifferentialActionModelFreeFwdDynamics(state, actuation, costs)
        iam = lib.IntegratedActionModelEuler(dam, 0.0 if terminal else dt)
        for m in (dam, iam):
            m.u_lb = np.array([-torque_limit])
            m.u_ub = np.array([torque_limit])
        return iam

    running = [node(False) for _ in range(nodes)]
    problem = lib.ShootingProblem(x0, running, node(True))
    xs = [x0.copy() for _ in range(nodes + 1)]
    us = [np.zeros(1) for _ in range(nodes)]
    return problem, xs, us
