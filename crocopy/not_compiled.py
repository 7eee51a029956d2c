"""Why a node gets no compiled evaluator: the reason recorded where its offer is declined.

A node's compiled evaluator is offered by ``model._compiled_node(data, terminal, memo)``
(:mod:`crocopy.solvers.compiled_nodes`), which returns None when the node does not qualify.  Every such return
goes through :func:`decline`, which writes a short reason (``"constraint residual ResidualModelControlGrav"``,
``"contact ContactModel1D"``, ``"residual ResidualModelContactForce"``, ``"user Python subclass: actuation
MyActuation"``, ...) into the solve's
``memo`` under :data:`REASON`: :func:`crocopy.solvers.coverage.compiled_coverage` reads it there, so the coverage
it reports is the very decision a solve makes, never a second copy of the rules.
"""

from __future__ import annotations

REASON = "why not compiled"
"""The ``memo`` key of the last declined node's reason."""

USER = "user Python subclass"
"""The reason of a node that holds a user's class (a subclass of the user's that may override a step)."""

USER_PACKAGES = ("crocopy.problems", "crocopy.bench", "crocopy.experiments")
"""crocopy's packages that build problems as a user does (their classes count as a user's)."""


def decline(memo: dict, reason: str) -> None:
    """Record in ``memo`` why the node being offered has no compiled evaluator; returns None (no evaluator)."""
    memo[REASON] = reason


def user_class(obj: object) -> bool:
    """Whether ``obj``'s class is a user's (defined outside crocopy's library modules)."""
    module = type(obj).__module__
    return not module.startswith("crocopy.") or module.startswith(USER_PACKAGES)


def class_reason(obj: object, role: str) -> str:
    """``"<role> <class name>"``: a library class the compiled nodes do not evaluate in that role, or, prefixed by
    :data:`USER` and a colon, a user's class."""
    reason = f"{role} {type(obj).__name__}"
    return f"{USER}: {reason}" if user_class(obj) else reason
