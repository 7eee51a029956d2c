"""Which nodes of a shooting problem a solve evaluates as compiled nodes, and why the others are not.

:func:`compiled_coverage` asks every node for its compiled evaluator exactly as a solve of the DDP family does at
its start (the datas a changed item set made stale made again, ``problem.refresh_datas()``, then
:func:`crocopy.solvers.compiled_nodes.select`: ``model._compiled_node(data, terminal, memo)``, one ``memo`` for the
problem) and reads the reason a declined node recorded (:mod:`crocopy.not_compiled`), so the
report and the solver cannot disagree.  A model class that offers no evaluator at all is named by what it is
(``"RK4 integrator"``, ``"action ActionModelUnicycle"``,
``"user Python subclass: action MyModel"``).

What the report leaves out is the solve-wide switch (:mod:`crocopy.solvers.compiled_nodes`): compiled nodes are
used only while :func:`crocopy.kernels_enabled`, by DDP, FDDP, Box-DDP, Box-FDDP, SQP and CSQP, with crocopy's
callbacks.  A node with a constraint manager is compiled when its constraints lower
(:mod:`crocopy.models.rbd.constraint_rows`), its rows then written by the compiled call.
"""

from __future__ import annotations

from typing import NamedTuple

from ..not_compiled import REASON, class_reason, user_class
from ..shooting import ShootingProblem


class NodeCoverage(NamedTuple):
    """One node of :func:`compiled_coverage`: whether a solve evaluates it compiled, and if not, why."""

    compiled: bool
    reason: str | None
    """None for a compiled node, else a short category (see :mod:`crocopy.not_compiled`)."""


def compiled_coverage(problem) -> list[NodeCoverage]:
    """Per node of ``problem`` (the running nodes, then the terminal node), whether a solve of the DDP family evaluates
    it as one compiled call, and if not, why.

    Parameters
    ----------
    problem : ShootingProblem
        The problem, with its datas (the nodes' evaluators are made for them and kept, as a solve would).

    Returns
    -------
    list of NodeCoverage
        ``problem.T + 1`` entries ``(compiled, reason)``; ``reason`` is None for a compiled node.

    Raises
    ------
    TypeError
        If ``problem`` is not a ``ShootingProblem``.
    """
    if not isinstance(problem, ShootingProblem):
        raise TypeError(f"problem must be a ShootingProblem, got {type(problem).__name__}")
    problem.refresh_datas()
    memo: dict = {}
    nodes = [*zip(problem.runningModels, problem.runningDatas), (problem.terminalModel, problem.terminalData)]
    out = []
    for t, (model, data) in enumerate(nodes):
        make = getattr(model, "_compiled_node", None)
        if make is None:
            out.append(NodeCoverage(False, offers_none(model)))
            continue
        memo.pop(REASON, None)
        compiled = make(data, t == problem.T, memo) is not None
        out.append(NodeCoverage(compiled, None if compiled else memo.get(REASON, offers_none(model))))
    return out


def offers_none(model) -> str:
    """The reason of a node whose model offers no compiled evaluator: what the model is."""
    if user_class(model):
        return class_reason(model, "action")
    return f"action {type(model).__name__}"
