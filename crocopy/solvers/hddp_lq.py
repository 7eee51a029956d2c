"""Hierarchical (prioritised) LQ backward pass (Romano, Del Prete, Mansard, Nori).

Tasks ``k = 1..K`` are solved in strict priority at every node ``t = T-1..0``.  Task ``k`` has
its own cost derivatives and value function ``V⁽ᵏ⁾``; its Q terms are (Gauss-Newton)
``Qx = Lx + Aᵀ Vx``, ``Qu = Lu + Bᵀ Vx``, ``Qxx = Lxx + Aᵀ Vxx A``, ``Qxu = Lxu + Aᵀ Vxx B``,
``Quu = Luu + Bᵀ Vxx B`` (``λ⁽ᵏ⁾ c⁽ᵏ⁾ I`` is added to ``Vxx`` in ``Quu``/``Qxu`` of the gains, with
``c⁽ᵏ⁾ = maxₜ max diag Lxx⁽ᵏ⁾ₜ`` (1 if the task has no state cost): the Levenberg regularisation is
relative to the task's curvature, so that it acts alike on a task weighted by 1 or by 1e12).  The higher
tasks fix ``δu = k̄ + K̄ δx + N̄ v`` (``N̄`` the orthogonal projector on the common nullspace); task
``k`` minimises its Q-function over ``v``:

    Q̄uu = N̄ Quu N̄,   Q̄u = N̄ (Qu + Quu k̄),   Q̄ux = N̄ (Qux + Quu K̄),
    v = -Q̄uu⁺ (Q̄u + Q̄ux δx),   k̄ += -Q̄uu⁺ Q̄u,   K̄ += -Q̄uu⁺ Q̄ux,   N̄ ← N̄ - V_r V_rᵀ

with ``V_r`` the eigenvectors of the *unregularised* ``N̄ Quu N̄`` (so the nullspace never depends on
the damping) above ``th_rank · p⁽ᵏ⁾ₜ``, ``p⁽ᵏ⁾ₜ`` the largest diagonal entry of ``Quu⁽ᵏ⁾`` over the nodes
``t..T-1`` swept so far, and the damped pseudo-inverse
``Q̄uu⁺ = V_r M (M² + μ² I)⁻¹ V_rᵀ`` with ``M = V_rᵀ Q̄uu V_r`` (Maciejewski; ``μ = 0`` is the plain
pseudo-inverse).  Every task's value function is then updated for the full policy
``δu = k̄ + K̄ δx`` with its own Q terms:
``Vx = Qx + K̄ᵀ Qu + (K̄ᵀ Quu + Qxu) k̄``, ``Vxx = Qxx + K̄ᵀ Quu K̄ + Qxu K̄ + K̄ᵀ Qux``.
Sign convention: ``+k̄``, ``+K̄`` (paper D's ``-K`` is ``K̄ = -K``).  One task gives DDP.

Rank threshold.  Eigenvalues of ``N̄ Quu⁽ᵏ⁾ N̄`` at node ``t`` count as nullspace below ``th_rank``
times a scale, ``rank_scale`` choosing which:

* ``"task"`` (default): ``s⁽ᵏ⁾ = max(maxₜ|Luu⁽ᵏ⁾|, maxₜ|Lxx⁽ᵏ⁾| · maxₜ|Fu|²)``, one scale per task.  A
  small running part of a task (the arm's running reach, weight 1e1·dt against the terminal 1e4) is
  below it and is left to the lower levels.
* ``"peak"``: ``p⁽ᵏ⁾ₜ = max_{s >= t} max diag Quu⁽ᵏ⁾ₛ``, the task's largest curvature met so far in
  the sweep.  A terminal reach met by the last control (``∂q_T/∂u_{T-1} = dt² M⁻¹``) has a genuine
  last-node curvature a few ``1e-5`` of ``s⁽ᵏ⁾`` in the hierarchical-DDP experiment: ``"task"`` with
  ``th_rank = 1e-9`` cut reaching directions there (the top task stalled at 1e-4..1e-2 m² in
  2-5 % of the paper's trials), ``"peak"`` keeps them.  It keeps every genuine curvature, so a task
  with a running part, or with ``λ > 0`` (the damped last node leaves a residual ``V⁽ᵏ⁾``), takes
  directions at every node: on the Kinova arm with ``[["goal"], ["state", "control"]]`` the top level
  then drives its running reach error down with unbounded torques (the effort reaches 1e6 within
  50 iterations, the strict-priority optimum being at infinite torque) instead of converging.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np


@dataclass
class LevelDerivatives:
    """Cost derivatives of one task over the horizon (lists of length T+1 for ``x``, T for ``u``)."""

    Lx: list[np.ndarray]
    Lu: list[np.ndarray]
    Lxx: list[np.ndarray]
    Lxu: list[np.ndarray]
    Luu: list[np.ndarray]


@dataclass
class HierarchicalLQResult:
    """Output of :func:`hierarchical_backward_pass`.

    ``ff[k][t]``: feed-forward contributed by task ``k`` at node ``t``; ``K[t]``: total feedback;
    ``Vx[k][t]``, ``Vxx[k][t]``: task value functions; ``rank[k][t]``: control directions task
    ``k`` took at node ``t``; ``free[t]``: dimension of the nullspace left after all tasks.
    """

    ff: list[list[np.ndarray]]
    K: list[np.ndarray]
    Vx: list[list[np.ndarray]]
    Vxx: list[list[np.ndarray]]
    rank: list[list[int]]
    free: list[int]


def hierarchical_backward_pass(
    Fx: Sequence[np.ndarray],
    Fu: Sequence[np.ndarray],
    levels: Sequence[LevelDerivatives],
    lambdas: Sequence[float] | None = None,
    mus: Sequence[float] | None = None,
    th_rank: float = 1e-9,
    rank_scale: str = "task",
) -> HierarchicalLQResult:
    """Prioritised Riccati recursion over ``K = len(levels)`` tasks.

    Parameters
    ----------
    Fx, Fu : sequences of length T
        Dynamics Jacobians ``(ndx, ndx)``, ``(ndx, nu)``.
    levels : sequence of LevelDerivatives
        Task cost derivatives, highest priority first.
    lambdas, mus : sequences of length K, optional
        Levenberg state regularisation (relative to the task's ``max diag Lxx``) and
        pseudo-inverse damping per task (default 0).
    th_rank : float
        Eigenvalues of ``N̄ Quu⁽ᵏ⁾ N̄`` below ``th_rank`` times the scale count as nullspace.
    rank_scale : {"task", "peak"}
        The scale: per task ``s⁽ᵏ⁾`` or the running peak ``p⁽ᵏ⁾ₜ`` (see the module docstring).

    Returns
    -------
    HierarchicalLQResult
        Gains in the ``δu = Σₖ ff[k] + K δx`` convention and per-task value functions.
    """
    if rank_scale not in ("task", "peak"):
        raise ValueError(f"rank_scale: expected 'task' or 'peak', got {rank_scale!r}")
    T, nlev = len(Fx), len(levels)
    lambdas = [0.0] * nlev if lambdas is None else list(lambdas)
    mus = [0.0] * nlev if mus is None else list(mus)
    ndx = levels[0].Lx[T].shape[0]
    res = HierarchicalLQResult(
        [[None] * T for _ in range(nlev)], [None] * T,
        [[None] * T + [np.array(lv.Lx[T], dtype=float)] for lv in levels],
        [[None] * T + [np.array(lv.Lxx[T], dtype=float)] for lv in levels],
        [[0] * T for _ in range(nlev)], [0] * T,
    )
    scale = [0.0] * nlev
    if rank_scale == "task":
        bmax = max((float(np.abs(B).max()) for B in Fu if B.size), default=0.0)
        task_scale = [
            max(max((float(np.abs(m).max()) for m in lv.Luu if m.size), default=0.0),
                bmax * bmax * max(float(np.abs(m).max()) for m in lv.Lxx if m.size))
            for lv in levels
        ]
    curvature = [max((float(np.max(np.diag(m))) for m in lv.Lxx if m.size), default=0.0) or 1.0 for lv in levels]
    for t in range(T - 1, -1, -1):
        A, B = Fx[t], Fu[t]
        nu = B.shape[1]
        kbar, Kbar, Nbar = np.zeros(nu), np.zeros((nu, ndx)), np.eye(nu)
        Qs = []
        for k, lv in enumerate(levels):
            Vx, Vxx = res.Vx[k][t + 1], res.Vxx[k][t + 1]
            VxxB = Vxx @ B
            Qx, Qu = lv.Lx[t] + A.T @ Vx, lv.Lu[t] + B.T @ Vx
            Qxx = lv.Lxx[t] + A.T @ Vxx @ A
            Qxu = lv.Lxu[t] + A.T @ VxxB
            Quu = lv.Luu[t] + B.T @ VxxB
            Qs.append((Qx, Qu, Qxx, Qxu, Quu))
            if rank_scale == "task":
                scale[k] = task_scale[k]
            else:
                scale[k] = max(scale[k], float(np.max(np.diag(Quu), initial=0.0)))
            if np.trace(Nbar) < 0.5 or scale[k] == 0.0:
                continue
            w, V = np.linalg.eigh(Nbar @ Quu @ Nbar)
            Vr = V[:, w > th_rank * scale[k]]
            r = Vr.shape[1]
            res.rank[k][t] = r
            if not r:
                continue
            if lambdas[k]:
                lam = lambdas[k] * curvature[k]
                Quu_r = Quu + lam * (B.T @ B)
                Qux_r = Qxu.T + lam * (B.T @ A)
            else:
                Quu_r, Qux_r = Quu, Qxu.T
            M = Vr.T @ Quu_r @ Vr
            M = 0.5 * (M + M.T)
            rhs = Vr.T @ np.column_stack([Qu + Quu_r @ kbar, Qux_r + Quu_r @ Kbar])
            if mus[k]:
                sol = np.linalg.solve(M @ M + mus[k] ** 2 * np.eye(r), M @ rhs)
            else:
                sol = np.linalg.solve(M, rhs)
            l, L = -Vr @ sol[:, 0], -Vr @ sol[:, 1:]
            res.ff[k][t] = l
            kbar += l
            Kbar += L
            Nbar = Nbar - Vr @ Vr.T
        for k in range(nlev):
            if res.ff[k][t] is None:
                res.ff[k][t] = np.zeros(nu)
            Qx, Qu, Qxx, Qxu, Quu = Qs[k]
            KtQuu = Kbar.T @ Quu
            QxuK = Qxu @ Kbar
            res.Vx[k][t] = Qx + Kbar.T @ Qu + (KtQuu + Qxu) @ kbar
            Vxx = Qxx + KtQuu @ Kbar + QxuK + QxuK.T
            res.Vxx[k][t] = 0.5 * (Vxx + Vxx.T)
        res.K[t] = Kbar
        res.free[t] = int(round(np.trace(Nbar)))
    return res
