"""Constraints: residuals as inequalities or equalities (:mod:`.base`) and their named stack (:mod:`.manager`)."""

from .base import ConstraintDataAbstract, ConstraintModelAbstract, ConstraintModelResidual, ConstraintType
from .manager import ConstraintDataManager, ConstraintItem, ConstraintModelManager
