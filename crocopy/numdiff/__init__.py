"""Numerical differentiation: of action and differential action models (:mod:`.actions`) and of a
state's ``diff``/``integrate`` (:mod:`.state`), the references every analytic derivative is tested against."""

from .actions import (
    ActionDataNumDiff,
    ActionModelNumDiff,
    DifferentialActionDataNumDiff,
    DifferentialActionModelNumDiff,
)
from .state import StateNumDiff
