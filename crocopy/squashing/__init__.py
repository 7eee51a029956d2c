"""Squashing: bounded controls through a smooth saturation ``u = s(w)`` (the squashing-DDP baseline)."""

from .action import ActionModelSquashed
from .smooth_sat import ActuationSquashingModel, SquashingDataAbstract, SquashingModelAbstract, SquashingModelSmoothSat
