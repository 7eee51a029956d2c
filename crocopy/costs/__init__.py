"""Costs: an activation of a residual (:mod:`~crocopy.costs.base`), weighted sums of them
(:mod:`~crocopy.costs.sum`) and the stacked evaluation of a sum's residual costs (:mod:`~crocopy.costs.stack`)."""

from .base import CostDataAbstract, CostDataResidual, CostModelAbstract, CostModelResidual
from .sum import CostDataSum, CostItem, CostModelSum
