"""Which models and residuals compiled nodes evaluate, by class (:mod:`.euler_node`, :mod:`.impulse_node`,
:mod:`.invdyn_node`).

An actuation joins when it declares its constant ``S = ∂τ/∂u`` (``compiled_matrix()``); a residual class when it
declares a ``compiled_kind`` of its own (the kind's code in :data:`.node_table.KIND`), a user's
:class:`~crocopy.models.residual_numba.ResidualModelNumba` as ``USER``.  A subclass inherits neither (it may override
``calc``); a user's Python residual may run beside a compiled free-dynamics node (:mod:`.python_residuals`).
"""

from __future__ import annotations

from crocopy.kernels import overridden
from crocopy.residuals.base import ResidualModelAbstract

from ..actuations import ActuationModelAbstract
from ..residual_numba import ResidualModelNumba
from . import node_table as table
from .lowering import declaring

ACTUATIONS = declaring(ActuationModelAbstract, "compiled_matrix")
"""The actuations compiled nodes take: those that declare their constant ``S = ∂τ/∂u`` (``compiled_matrix()``)."""


def compiled_residual_classes() -> dict[type, str]:
    """Every residual class that declares a ``compiled_kind`` of its own (beside its maths, with its
    ``compiled_parameters()``), with that kind: the registry of the kinds compiled nodes evaluate (a subclass
    inherits none: it may override ``calc``)."""
    return {cls: cls.__dict__["compiled_kind"] for cls in declaring(ResidualModelAbstract, "compiled_kind")}


def residual_kind(residual) -> int | None:
    """The kernel's kind of ``residual`` (its class's own ``compiled_kind``, or ``USER`` for a
    :class:`ResidualModelNumba` that keeps
    the base class's ``calc``/``calcDiff``), or None when compiled nodes cannot evaluate it."""
    name = type(residual).__dict__.get("compiled_kind")
    if name is not None:
        return table.KIND[name]
    if isinstance(residual, ResidualModelNumba) and not overridden(residual, ResidualModelNumba, ("calc", "calcDiff")):
        return table.USER
    return None


def python_residual(residual) -> bool:
    """Whether ``residual`` may run in Python inside a compiled free-dynamics node (:mod:`.python_residuals`): a
    residual class of the user's, not one of the library's models (some of which read the actuation's or the
    contacts' data)."""
    return isinstance(residual, ResidualModelAbstract) and not type(residual).__module__.startswith(
        ("crocopy.models.", "crocopy.residuals.")
    )
