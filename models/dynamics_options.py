"""Options shared by the multibody dynamics models.

* ``armature`` (shape ``(nv,)``): added to the diagonal of the mass matrix; ``_with_armature``
  tells the models whether it is non-zero.
* ``JMinvJt_damping`` (≥ 0): damping of the contact-space inertia ``Jc M⁻¹ Jcᵀ`` in the KKT solves of
  the contact and impulse dynamics (Crocoddyl's ``inv_damping``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from crocopy.validation import as_vector


class ArmatureMixin:
    """The ``armature`` property of a multibody dynamics model."""

    state: Any

    @property
    def armature(self) -> np.ndarray:
        """Armature added to the diagonal of the mass matrix, shape ``(nv,)``."""
        return self._armature

    @armature.setter
    def armature(self, value: np.ndarray) -> None:
        arm = as_vector(value, self.state.nv, "armature").copy()
        self._armature = arm
        self._with_armature = bool(np.any(arm != 0.0))


class KKTDampingMixin:
    """The ``JMinvJt_damping`` property of contact and impulse dynamics."""

    @property
    def JMinvJt_damping(self) -> float:
        """Damping factor of ``Jc M⁻¹ Jcᵀ`` (non-negative)."""
        return self._damping

    @JMinvJt_damping.setter
    def JMinvJt_damping(self, value: float) -> None:
        value = float(value)
        if not value >= 0.0:
            raise ValueError(f"inv_damping must be non-negative, got {value}")
        self._damping = value
