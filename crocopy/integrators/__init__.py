"""Integrators: a differential action model turned into a discrete action model (Euler, Runge-Kutta)."""

from .base import IntegratedActionModelAbstract
from .euler import IntegratedActionDataEuler, IntegratedActionModelEuler
from .rk import IntegratedActionDataRK, IntegratedActionModelRK
