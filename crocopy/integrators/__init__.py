"""Integrators: a differential action model turned into a discrete action model (Euler, Runge-Kutta),
with a control parametrization over the step (constant, linear, quadratic)."""

from .base import IntegratedActionModelAbstract
from .control_base import ControlParametrizationDataAbstract, ControlParametrizationModelAbstract
from .control_poly import (
    ControlParametrizationDataPolyOne,
    ControlParametrizationDataPolyTwoRK,
    ControlParametrizationModelPolyOne,
    ControlParametrizationModelPolyTwoRK,
    ControlParametrizationModelPolyZero,
)
from .euler import IntegratedActionDataEuler, IntegratedActionModelEuler
from .rk import IntegratedActionDataRK, IntegratedActionModelRK
