"""Discrete linear-quadratic action model.

``xnext = A x + B u + f``; cost and constraints as in :mod:`crocopy.actions.lq_terms`.
"""

from __future__ import annotations

import numpy as np

from ..action_base import ActionDataAbstract, ActionModelAbstract
from ..state import StateVector
from ..validation import as_matrix, as_vector
from .lq_terms import LQTerms, LQTermsAccess, default_input_matrix, lq_arguments, random_psd, size_arguments


class ActionModelLQR(LQTermsAccess, ActionModelAbstract):
    """Linear-quadratic regulator node (Crocoddyl's ``ActionModelLQR``).

    Constructed as ``ActionModelLQR(A, B, Q, R, N[, G, H], f, q, r[, g, h])`` or
    ``ActionModelLQR(nx, nu, driftFree=True)``.
    """

    def __init__(self, *args, **kwargs) -> None:
        if args and np.isscalar(args[0]):
            nx, nu, drift_free = size_arguments(args, kwargs)
            A, B = np.eye(nx), default_input_matrix(nx, nu)
            Q, R, N = np.eye(nx), np.eye(nu), np.zeros((nx, nu))
            f = np.zeros(nx) if drift_free else np.ones(nx)
            q, r, G, H, g, h = np.ones(nx), np.ones(nu), None, None, None, None
        else:
            vals = lq_arguments("ActionModelLQR", ("A", "B"), args, kwargs)
            A = np.atleast_2d(np.asarray(vals["A"], dtype=float))
            nx = A.shape[0]
            B = np.asarray(vals["B"], dtype=float).reshape(nx, -1)
            nu = B.shape[1]
            Q, R, N = vals["Q"], vals["R"], vals["N"]
            f, q, r = vals.get("f", np.zeros(nx)), vals.get("q", np.zeros(nx)), vals.get("r", np.zeros(nu))
            G, H, g, h = vals.get("G"), vals.get("H"), vals.get("g"), vals.get("h")
        state = StateVector(nx)
        self._lq = LQTerms(nx, nu, Q, R, N, q, r, G, H, g, h)
        ng, nh = self._lq.G.shape[0], self._lq.H.shape[0]
        super().__init__(state, nu, 0, ng, nh, ng, nh)
        self.A = as_matrix(A, (nx, nx), "A")
        self.B = as_matrix(B, (nx, nu), "B")
        self.f = as_vector(f, nx, "f")
        lq = self._lq
        self._AB = np.hstack([self.A, self.B])
        self._H = np.block([[lq.Q, lq.N], [lq.N.T, lq.R]])
        self._h = np.concatenate([lq.q, lq.r])

    @staticmethod
    def Random(nx: int, nu: int, ng: int = 0, nh: int = 0) -> "ActionModelLQR":
        """A random LQR model with stable-ish dynamics and positive-definite weights."""
        rng = np.random.default_rng()
        A = np.eye(nx) + 0.1 * rng.standard_normal((nx, nx))
        B = rng.standard_normal((nx, nu))
        Q, R = random_psd(nx, rng), random_psd(nu, rng)
        N = 0.1 * rng.standard_normal((nx, nu))
        G, H = rng.standard_normal((ng, nx + nu)), rng.standard_normal((nh, nx + nu))
        return ActionModelLQR(
            A, B, Q, R, N, G, H, rng.standard_normal(nx), rng.standard_normal(nx), rng.standard_normal(nu),
            rng.standard_normal(ng), rng.standard_normal(nh),
        )

    def createData(self) -> "ActionDataLQR":
        return ActionDataLQR(self)

    def calc(self, data: "ActionDataLQR", x: np.ndarray, u: np.ndarray | None = None) -> None:
        if u is None:
            data.xnext[:] = x
            data.cost = self._lq.cost(x, None)
        else:
            z, Hz = data.z, data.Hz
            nx = z.size - u.size
            z[:nx] = x
            z[nx:] = u
            np.dot(self._AB, z, out=data.xnext)
            data.xnext += self.f
            np.dot(self._H, z, out=Hz)
            data.cost = 0.5 * float(z @ Hz) + float(self._h @ z)
        if data.g.size or data.h.size:
            self._lq.fill_constraints(data, x, u, diff=False)

    def calcDiff(self, data: "ActionDataLQR", x: np.ndarray, u: np.ndarray | None = None) -> None:
        """Gradients only: ``Fx, Fu, Lxx, Lxu, Luu`` are constant and set in :meth:`createData`."""
        if u is None:
            self._lq.fill_cost_derivatives(data, x, None)
        else:
            z, grad = data.z, data.Hz
            nx = z.size - u.size
            z[:nx] = x
            z[nx:] = u
            np.dot(self._H, z, out=grad)
            grad += self._h
            data.Lx[:] = grad[:nx]
            data.Lu[:] = grad[nx:]
        if data.g.size or data.h.size:
            self._lq.fill_constraints(data, x, u, diff=True)


class ActionDataLQR(ActionDataAbstract):
    """Data of :class:`ActionModelLQR`, with the constant derivatives filled once and a ``z = (x, u)`` buffer."""

    def __init__(self, model: ActionModelLQR) -> None:
        super().__init__(model)
        self.Fx[:] = model.A
        self.Fu[:] = model.B
        self.Lxx[:] = model.Q
        self.Lxu[:] = model.N
        self.Luu[:] = model.R
        self.z = np.zeros(model.state.nx + model.nu)
        self.Hz = np.zeros(model.state.nx + model.nu)
