"""Equality-constrained LQ backward pass by nullspace projection (Giftthaler & Buchli).

At node ``t`` the equality rows ``h + Hx δx + Hu δu = 0`` are split (by an SVD of ``Hu``) into
state-input rows ``Er δu + Dr δx = er`` with ``Er`` of full row rank and pure-state rows
``C δx = d``.  Pure-state rows of node ``t+1`` (the terminal rows at ``t = T-1``) are previewed one
step through the dynamics ``δx' = A δx + B δu + f'``: ``M = C B``, ``N = C A``, which requires
relative degree one (``M`` of full row rank).  With ``𝓔 = [Er; M]``, ``𝓓 = [Dr; N]`` and
``rhs = [er; d - C f']`` the control is parametrised as

    δu = ε + U δx + Z v,   ε = 𝓔⁺ rhs,   U = -𝓔⁺ 𝓓,   Z a basis of 𝒩(𝓔),

and ``v`` minimises the Q-function: ``v = l + L δx`` with ``Hz = Zᵀ(Quu + preg I)Z``,
``l = -Hz⁻¹ Zᵀ(Qu + Quu ε)``, ``L = -Hz⁻¹ Zᵀ(Qux + Quu U)``.  The policy
``δu = (ε + Z l) + (U + Z L) δx`` is returned in Crocoddyl's sign (``k = -uff``, ``K = -Kfb``) and
the value function is updated for that policy:
``Vx = Qx + Kfbᵀ Qu + (Kfbᵀ Quu + Qxu) uff``, ``Vxx = Qxx + Kfbᵀ Quu Kfb + Qxu Kfb + Kfbᵀ Qux``.
Without constraints this is the DDP backward pass.  Cost: one SVD of at most ``nu`` rows per node.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg


class ConstraintRankError(ValueError):
    """The linearised equality constraints cannot be projected at some node.

    Attributes
    ----------
    node : int
        Node index where the problem was found.
    kind : str
        ``"rank-deficient"`` (dependent but consistent rows of ``[Hx Hu]``), ``"infeasible"``
        (dependent rows whose values contradict each other, or pure-state rows violated at ``x0``),
        ``"relative-degree"`` (a previewed state constraint does not see the control one step
        later) or ``"over-constrained"`` (more independent rows than controls, or state-input and
        previewed rows conflict).
    """

    def __init__(self, node: int, kind: str, message: str) -> None:
        super().__init__(f"node {node}: {kind} equality constraints: {message}")
        self.node = node
        self.kind = kind


@dataclass
class ProjectionLQResult:
    """Output of :func:`projected_backward_pass` (lists indexed by node).

    ``C0 δx₀ = d0`` are node 0's pure-state rows, which no control can correct.
    """

    k: list[np.ndarray]
    K: list[np.ndarray]
    Vx: list[np.ndarray]
    Vxx: list[np.ndarray]
    Qu: list[np.ndarray]
    Quu: list[np.ndarray]
    nullity: list[int] = field(default_factory=list)
    C0: np.ndarray | None = None
    d0: np.ndarray | None = None


def _rank(s: np.ndarray, rtol: float) -> int:
    if s.size == 0:
        return 0
    return int(np.sum(s > rtol * max(s[0], 1.0)))


def split_equality(
    Hx: np.ndarray, Hu: np.ndarray | None, h: np.ndarray, node: int, rtol: float = 1e-9
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Split ``h + Hx δx + Hu δu = 0`` into state-input and pure-state rows.

    Returns
    -------
    Dr, Er, er, C, d
        State-input rows ``Er δu + Dr δx = er`` (``Er`` full row rank) and pure-state rows
        ``C δx = d``.  ``Hu=None`` means a terminal node (all rows pure-state).

    Raises
    ------
    ConstraintRankError
        If ``[Hx Hu]`` does not have full row rank: ``"infeasible"`` when the dependent rows
        contradict each other, ``"rank-deficient"`` when they are redundant.
    """
    nh, ndx = Hx.shape
    J = Hx if Hu is None else np.hstack([Hx, Hu])
    if nh:
        W, s, _ = np.linalg.svd(J)
        r = _rank(s, rtol)
        if r < nh:
            conflict = float(np.linalg.norm(W[:, r:].T @ h))
            if conflict > rtol * max(1.0, float(np.linalg.norm(h))):
                raise ConstraintRankError(
                    node, "infeasible",
                    f"the {nh} rows of [Hx Hu] are linearly dependent and contradict each other (their values "
                    f"disagree by {conflict:.3g} along the dependent combination): no step satisfies them",
                )
            raise ConstraintRankError(
                node, "rank-deficient", f"the {nh} rows of [Hx Hu] are linearly dependent (rank {r}); remove the "
                "redundant rows",
            )
    if Hu is None or Hu.shape[1] == 0 or not np.any(Hu):
        nu = 0 if Hu is None else Hu.shape[1]
        return np.zeros((0, ndx)), np.zeros((0, nu)), np.zeros(0), Hx, -h
    Us, s, _ = np.linalg.svd(Hu)
    r = _rank(s, rtol)
    Ur, W = Us[:, :r], Us[:, r:]
    return Ur.T @ Hx, Ur.T @ Hu, -(Ur.T @ h), W.T @ Hx, -(W.T @ h)


def projected_backward_pass(
    Fx: Sequence[np.ndarray],
    Fu: Sequence[np.ndarray],
    Lx: Sequence[np.ndarray],
    Lu: Sequence[np.ndarray],
    Lxx: Sequence[np.ndarray],
    Lxu: Sequence[np.ndarray],
    Luu: Sequence[np.ndarray],
    Hx: Sequence[np.ndarray],
    Hu: Sequence[np.ndarray],
    h: Sequence[np.ndarray],
    fs: Sequence[np.ndarray] | None = None,
    preg: float = 0.0,
    xreg: float = 0.0,
    rtol: float = 1e-9,
) -> ProjectionLQResult:
    """Riccati recursion of the equality-constrained LQ problem around a nominal trajectory.

    Parameters
    ----------
    Fx, Fu : sequences of length T
        Dynamics Jacobians ``(ndx, ndx)``, ``(ndx, nu)``.
    Lx, Lxx : sequences of length T+1
        Cost gradient/Hessian in ``x`` (the last entry is the terminal cost).
    Lu, Lxu, Luu : sequences of length T
        Remaining cost derivatives of the running nodes.
    Hx, h : sequences of length T+1; Hu : sequence of length T
        Equality rows of each node (``(nh_t, ndx)``, ``(nh_t,)``, ``(nh_t, nu)``); terminal rows
        depend on ``x`` only.
    fs : sequence of length T+1, optional
        Gaps ``f(x_t, u_t) ⊖ x_{t+1}`` (zeros for a feasible nominal trajectory).
    preg, xreg : float
        Regularisation added to ``Quu`` (in the nullspace) and to ``Vxx``.
    rtol : float
        Relative singular-value threshold of the rank tests.

    Returns
    -------
    ProjectionLQResult
        Gains in Crocoddyl's sign (``δu = -k - K δx``) and the value function.

    Raises
    ------
    ConstraintRankError
        On rank-deficient rows, relative degree above one or an over-constrained node.
    numpy.linalg.LinAlgError
        If the reduced Hessian ``Zᵀ Quu Z`` is not positive definite (raise ``preg``).
    """
    T = len(Fx)
    ndx = Lx[T].shape[0]
    res = ProjectionLQResult([None] * T, [None] * T, [None] * (T + 1), [None] * (T + 1),
                             [None] * T, [None] * T, [0] * T)
    Vx = np.array(Lx[T], dtype=float)
    Vxx = np.array(Lxx[T], dtype=float)
    if xreg:
        Vxx += xreg * np.eye(ndx)
    res.Vx[T], res.Vxx[T] = Vx, Vxx
    _, _, _, C, d = split_equality(Hx[T], None, h[T], T, rtol)
    for t in range(T - 1, -1, -1):
        A, B = Fx[t], Fu[t]
        nu = B.shape[1]
        Vx_n = Vx if fs is None else Vx + Vxx @ fs[t + 1]
        VxxB = Vxx @ B
        Qx = Lx[t] + A.T @ Vx_n
        Qu = Lu[t] + B.T @ Vx_n
        Qxx = Lxx[t] + A.T @ Vxx @ A
        Qxu = Lxu[t] + A.T @ VxxB
        Quu = Luu[t] + B.T @ VxxB
        if preg:
            Quu = Quu + preg * np.eye(nu)
        Dr, Er, er, Cs, ds = split_equality(Hx[t], Hu[t], h[t], t, rtol)
        if C.shape[0]:
            M = C @ B
            if _rank(np.linalg.svd(M, compute_uv=False), rtol) < C.shape[0]:
                raise ConstraintRankError(
                    t + 1, "relative-degree",
                    f"{C.shape[0]} pure-state rows are not controllable one step ahead (rank of C_(t+1) B_t "
                    "below their number); relative degree above one (e.g. a position constraint under explicit "
                    "Euler) is not supported",
                )
            rhs_prev = d - C @ fs[t + 1] if fs is not None else d
            Ecal, Dcal, rhs = np.vstack([Er, M]), np.vstack([Dr, C @ A]), np.concatenate([er, rhs_prev])
        else:
            Ecal, Dcal, rhs = Er, Dr, er
        m = Ecal.shape[0]
        if m:
            Ue, se, Vt = np.linalg.svd(Ecal)
            if m > nu or _rank(se, rtol) < m:
                raise ConstraintRankError(
                    t, "over-constrained",
                    f"{Er.shape[0]} state-input and {m - Er.shape[0]} previewed state rows are dependent or "
                    f"exceed nu={nu}",
                )
            pinv = (Vt[:m].T / se) @ Ue.T
            eps = pinv @ rhs
            U = -pinv @ Dcal
            Z = Vt[m:].T
            Qu_e = Qu + Quu @ eps
            Qux_e = Qxu.T + Quu @ U
            Hz = Z.T @ Quu @ Z
            gz, Gz = Z.T @ Qu_e, Z.T @ Qux_e
        else:
            eps, U, Z = np.zeros(nu), np.zeros((nu, ndx)), None
            Hz, gz, Gz = Quu, Qu, Qxu.T
        res.nullity[t] = nu - m
        if Hz.shape[0]:
            factor = scipy.linalg.cho_factor(Hz, lower=True, check_finite=False)
            sol = scipy.linalg.cho_solve(factor, np.column_stack([gz, Gz]), check_finite=False)
            l, L = -sol[:, 0], -sol[:, 1:]
        else:
            l, L = np.zeros(0), np.zeros((0, ndx))
        if Z is None:
            uff, Kfb = l, L
        else:
            uff, Kfb = eps + Z @ l, U + Z @ L
        KtQuu = Kfb.T @ Quu
        QxuK = Qxu @ Kfb
        Vx = Qx + Kfb.T @ Qu + (KtQuu + Qxu) @ uff
        Vxx = Qxx + KtQuu @ Kfb + QxuK + QxuK.T
        Vxx = 0.5 * (Vxx + Vxx.T)
        if xreg:
            Vxx += xreg * np.eye(ndx)
        res.k[t], res.K[t] = -uff, -Kfb
        res.Vx[t], res.Vxx[t] = Vx, Vxx
        res.Qu[t], res.Quu[t] = Qu, Quu
        C, d = Cs, ds
    res.C0, res.d0 = C, d
    return res


def linear_rollout_model_change(
    Fx: Sequence[np.ndarray],
    Fu: Sequence[np.ndarray],
    Lx: Sequence[np.ndarray],
    Lu: Sequence[np.ndarray],
    Lxx: Sequence[np.ndarray],
    Lxu: Sequence[np.ndarray],
    Luu: Sequence[np.ndarray],
    k: Sequence[np.ndarray],
    K: Sequence[np.ndarray],
    fs: Sequence[np.ndarray] | None = None,
) -> tuple[float, float]:
    """First- and second-order terms of the LQ model's cost change along the policy.

    Rolls out ``δx_{t+1} = A δx + B δu + f_{t+1}``, ``δu = -k - K δx`` from ``δx_0 = f_0`` and returns
    ``(d1, d2)`` with the model's cost change ``d1 + ½ d2`` for the full step (exact for a feasible
    nominal trajectory, where the change at step ``α`` is ``α d1 + ½ α² d2``).
    """
    T = len(Fx)
    dx = np.zeros(Lx[T].shape[0]) if fs is None else np.array(fs[0], dtype=float)
    d1 = d2 = 0.0
    for t in range(T):
        du = -k[t] - K[t] @ dx
        d1 += Lx[t] @ dx + Lu[t] @ du
        d2 += dx @ Lxx[t] @ dx + 2.0 * dx @ Lxu[t] @ du + du @ Luu[t] @ du
        dx = Fx[t] @ dx + Fu[t] @ du + (0.0 if fs is None else fs[t + 1])
    d1 += Lx[T] @ dx
    d2 += dx @ Lxx[T] @ dx
    return float(d1), float(d2)
