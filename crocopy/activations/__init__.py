"""Activation functions a(r): scalar of a residual r (shape ``(nr,)``), gradient ``Ar`` and Hessian ``Arr``."""

from .barrier import ActivationBounds, ActivationModelQuadraticBarrier, ActivationModelWeightedQuadraticBarrier
from .base import ActivationDataAbstract, ActivationModelAbstract
from .flat import ActivationModelQuadFlatExp, ActivationModelQuadFlatLog
from .norms import ActivationModel2NormBarrier, ActivationModelSmooth1Norm, ActivationModelSmooth2Norm
from .quad import ActivationModelQuad, ActivationModelWeightedQuad

__all__ = [
    "ActivationBounds",
    "ActivationDataAbstract",
    "ActivationModel2NormBarrier",
    "ActivationModelAbstract",
    "ActivationModelQuad",
    "ActivationModelQuadFlatExp",
    "ActivationModelQuadFlatLog",
    "ActivationModelQuadraticBarrier",
    "ActivationModelSmooth1Norm",
    "ActivationModelSmooth2Norm",
    "ActivationModelWeightedQuad",
    "ActivationModelWeightedQuadraticBarrier",
]
