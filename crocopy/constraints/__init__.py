"""Constraints: residuals as inequalities or equalities (:mod:`~crocopy.constraints.base`) and their named
stack (:mod:`~crocopy.constraints.manager`)."""

from .base import ConstraintDataAbstract, ConstraintModelAbstract, ConstraintModelResidual, ConstraintType
from .manager import ConstraintDataManager, ConstraintItem, ConstraintModelManager
