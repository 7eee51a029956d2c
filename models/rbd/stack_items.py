"""The items of a cost stack a compiled node (Euler, impulse, inverse dynamics) evaluates, and why a stack keeps its
node on the Python path: an activation the stack does not fuse, a cost sum's generic item, a cost that is not a
``CostModelResidual`` (:mod:`crocopy.costs.stack`, :mod:`crocopy.not_compiled`)."""

from __future__ import annotations

from collections.abc import Iterator

from crocopy.costs.base import CostModelResidual
from crocopy.not_compiled import class_reason


def generic_reason(cost) -> str:
    """Why a cost the cost stack does not hold (a cost sum's ``generic`` item, :mod:`crocopy.costs.sum`) keeps its
    node off the compiled path."""
    if not isinstance(cost, CostModelResidual):
        return class_reason(cost, "cost")
    if not cost.activation.diagonal:
        return class_reason(cost.activation, "activation")
    return class_reason(cost.residual, "residual with no rows")


def compiled_items(stack, costs_data, costs, item_forms: bool = False) -> Iterator:
    """The items of a cost stack a compiled node evaluates: ``(residual, cdata, rows)`` of each active, non-zero
    ``CostModelResidual`` in order; or, as the last entry, why the node cannot compile (a str: an activation the
    stack does not fuse, or with ``item_forms`` (a node whose kernel evaluates them) one without an item form either,
    a generic cost, another cost class)."""
    unfused = stack.uncompiled if item_forms else [a for a, _, _ in stack.unfused]
    if unfused:
        yield class_reason(unfused[0], "activation")
        return
    if costs_data.generic:
        yield generic_reason(costs.costs[costs_data.generic[0]].cost)
        return
    for (_, item, cdata), rows in zip(stack.items, stack.slices):
        if type(item.cost) is not CostModelResidual:
            yield class_reason(item.cost, "cost")
            return
        if item.active and not cdata.zero:
            yield item.cost.residual, cdata, rows
