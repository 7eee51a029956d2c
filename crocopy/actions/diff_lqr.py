"""Differential linear-quadratic model: ``a = Aq q + Av v + B u + f`` with the LQ cost."""

from __future__ import annotations

import numpy as np

from ..diff_action_base import DifferentialActionDataAbstract, DifferentialActionModelAbstract
from ..state import StateVector
from ..validation import as_matrix, as_vector
from .lq_terms import LQTerms, LQTermsAccess, default_input_matrix, lq_arguments, random_psd, size_arguments


class DifferentialActionModelLQR(LQTermsAccess, DifferentialActionModelAbstract):
    """Crocoddyl's ``DifferentialActionModelLQR``.

    Constructed as ``DifferentialActionModelLQR(Aq, Av, B, Q, R, N[, G, H], f, q, r[, g, h])`` or
    ``DifferentialActionModelLQR(nq, nu, driftFree=True)``.
    """

    def __init__(self, *args, **kwargs) -> None:
        if args and np.isscalar(args[0]):
            nq, nu, drift_free = size_arguments(args, kwargs)
            Aq, Av, B = np.eye(nq), np.eye(nq), default_input_matrix(nq, nu)
            Q, R, N = np.eye(2 * nq), np.eye(nu), np.zeros((2 * nq, nu))
            f = np.zeros(nq) if drift_free else np.ones(nq)
            q, r, G, H, g, h = np.ones(2 * nq), np.ones(nu), None, None, None, None
        else:
            vals = lq_arguments("DifferentialActionModelLQR", ("Aq", "Av", "B"), args, kwargs)
            Aq = np.atleast_2d(np.asarray(vals["Aq"], dtype=float))
            nq = Aq.shape[0]
            Av = vals["Av"]
            B = np.asarray(vals["B"], dtype=float).reshape(nq, -1)
            nu = B.shape[1]
            Q, R, N = vals["Q"], vals["R"], vals["N"]
            f = vals.get("f", np.zeros(nq))
            q, r = vals.get("q", np.zeros(2 * nq)), vals.get("r", np.zeros(nu))
            G, H, g, h = vals.get("G"), vals.get("H"), vals.get("g"), vals.get("h")
        self._lq = LQTerms(2 * nq, nu, Q, R, N, q, r, G, H, g, h)
        ng, nh = self._lq.G.shape[0], self._lq.H.shape[0]
        super().__init__(StateVector(2 * nq), nu, 0, ng, nh, ng, nh)
        self.Aq = as_matrix(Aq, (nq, nq), "Aq")
        self.Av = as_matrix(Av, (nq, nq), "Av")
        self.B = as_matrix(B, (nq, nu), "B")
        self.f = as_vector(f, nq, "f")
        self._Fx = np.hstack([self.Aq, self.Av])

    @staticmethod
    def Random(nq: int, nu: int, ng: int = 0, nh: int = 0) -> "DifferentialActionModelLQR":
        """A random differential LQR model with positive-definite weights."""
        rng = np.random.default_rng()
        nx = 2 * nq
        return DifferentialActionModelLQR(
            -np.eye(nq) + 0.1 * rng.standard_normal((nq, nq)), -np.eye(nq) + 0.1 * rng.standard_normal((nq, nq)),
            rng.standard_normal((nq, nu)), random_psd(nx, rng), random_psd(nu, rng),
            0.1 * rng.standard_normal((nx, nu)),
            rng.standard_normal((ng, nx + nu)), rng.standard_normal((nh, nx + nu)), rng.standard_normal(nq),
            rng.standard_normal(nx), rng.standard_normal(nu), rng.standard_normal(ng), rng.standard_normal(nh),
        )

    def calc(self, data: DifferentialActionDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        nq = self.Aq.shape[0]
        if u is None:
            data.xout[:] = 0.0
        else:
            data.xout[:] = self.Aq @ x[:nq] + self.Av @ x[nq:] + self.B @ u + self.f
        data.cost = self._lq.cost(x, u)
        self._lq.fill_constraints(data, x, u, diff=False)

    def calcDiff(self, data: DifferentialActionDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        if u is not None:
            data.Fx[:] = self._Fx
            data.Fu[:] = self.B
        self._lq.fill_cost_derivatives(data, x, u)
        self._lq.fill_constraints(data, x, u, diff=True)
