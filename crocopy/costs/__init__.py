"""Costs: an activation of a residual (:mod:`.base`), weighted sums of them (:mod:`.sum`) and the
stacked evaluation of a sum's residual costs (:mod:`.stack`)."""

from .base import CostDataAbstract, CostDataResidual, CostModelAbstract, CostModelResidual
from .sum import CostDataSum, CostItem, CostModelSum
