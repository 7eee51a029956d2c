"""State manifolds.

A state lives on a manifold of dimension ``nx`` (its representation) whose tangent space has
dimension ``ndx``.  ``diff(x0, x1)`` returns ``x1 ⊖ x0`` (shape ``(ndx,)``) and
``integrate(x, dx)`` returns ``x ⊕ dx`` (shape ``(nx,)``).  Jacobians are ``(ndx, ndx)``:
``Jdiff`` gives ∂(x1 ⊖ x0)/∂x0 and ∂(x1 ⊖ x0)/∂x1, ``Jintegrate`` gives ∂(x ⊕ dx)/∂x and
∂(x ⊕ dx)/∂dx, all expressed in the tangent spaces.
"""

from __future__ import annotations

import numpy as np

from .enums import Jcomponent
from .guards import Guard, Guarded
from .kernels import overridden
from .validation import as_bound, as_count, point_arg, tangent_arg, warn_nonfinite_result
from .versioning import Parametrized


def _component_arg(owner: "StateAbstract", value: object, name: str) -> Jcomponent:
    try:
        return Jcomponent(value)
    except ValueError:
        raise ValueError(f"{name} must be Jcomponent.both, .first or .second, got {value!r}") from None


def _jacobian_arg(owner: "StateAbstract", value: object, name: str) -> np.ndarray:
    if not isinstance(value, np.ndarray) or value.dtype != np.float64:
        raise TypeError(f"{name} must be a float64 numpy array (it is written in place), got {type(value).__name__}")
    if value.ndim != 2 or value.shape[0] != owner.ndx:
        raise ValueError(f"{name} has shape {value.shape}, expected ({owner.ndx}, k)")
    return value


_BINARY = (("x0", point_arg), ("x1", point_arg), ("firstsecond", _component_arg))
_TANGENT = (("x", point_arg), ("dx", tangent_arg), ("firstsecond", _component_arg))


class StateAbstract(Parametrized, Guarded):
    """Abstract state manifold (Crocoddyl's ``StateAbstract``).

    ``diff``, ``integrate``, ``Jdiff``, ``Jintegrate`` and ``JintegrateTransport`` of every subclass
    check their arguments when a user calls them (:mod:`crocopy.guards`): points ``(nx,)`` and
    tangent vectors ``(ndx,)``, finite; a solve calls them unchecked.  The bounds ``lb``/``ub`` may
    be set in either order; :meth:`_set_limits` refuses NaN only.

    Parameters
    ----------
    nx : int
        Dimension of the state representation.
    ndx : int
        Dimension of the tangent space.
    """

    _read_only = frozenset({"pinocchio"})

    _guards = {
        "diff": Guard(_BINARY[:2], returns=warn_nonfinite_result),
        "integrate": Guard(_TANGENT[:2], returns=warn_nonfinite_result),
        "Jdiff": Guard(_BINARY, returns=warn_nonfinite_result),
        "Jintegrate": Guard(_TANGENT, returns=warn_nonfinite_result),
        "JintegrateTransport": Guard((*_TANGENT[:2], ("Jin", _jacobian_arg), ("firstsecond", _component_arg)),
                                     returns=warn_nonfinite_result),
    }

    def __init__(self, nx: int, ndx: int) -> None:
        self.nx = as_count(nx, "nx")
        self.ndx = as_count(ndx, "ndx")
        self.nv = self.ndx // 2
        self.nq = self.nx - self.nv
        self._lb = np.full(self.nx, -np.inf)
        self._ub = np.full(self.nx, np.inf)
        self.has_limits = False

    @property
    def lb(self) -> np.ndarray:
        """Lower state limits, shape ``(nx,)``."""
        return self._lb

    @lb.setter
    def lb(self, value: np.ndarray) -> None:
        self._set_limits(as_bound(value, self.nx, "lb", upper=False), self._ub)

    @property
    def ub(self) -> np.ndarray:
        """Upper state limits, shape ``(nx,)``."""
        return self._ub

    @ub.setter
    def ub(self, value: np.ndarray) -> None:
        self._set_limits(self._lb, as_bound(value, self.nx, "ub", upper=True))

    def _set_limits(self, lb: np.ndarray, ub: np.ndarray) -> None:
        self._lb = lb
        self._ub = ub
        self.has_limits = bool(np.any(np.isfinite(lb)) or np.any(np.isfinite(ub)))

    def zero(self) -> np.ndarray:
        raise NotImplementedError

    def rand(self) -> np.ndarray:
        raise NotImplementedError

    def diff(self, x0: np.ndarray, x1: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def integrate(self, x: np.ndarray, dx: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def Jdiff(self, x0: np.ndarray, x1: np.ndarray, firstsecond: Jcomponent = Jcomponent.both) -> list:
        raise NotImplementedError

    def Jintegrate(self, x: np.ndarray, dx: np.ndarray, firstsecond: Jcomponent = Jcomponent.both) -> list:
        raise NotImplementedError

    def JintegrateTransport(self, x: np.ndarray, dx: np.ndarray, Jin: np.ndarray, firstsecond: Jcomponent) -> None:
        """Transport ``Jin`` (rows in the tangent space at ``x ⊕ dx``) to the tangent space at ``x``, in place."""
        raise NotImplementedError

    def _integrate_into(self, x: np.ndarray, dx: np.ndarray, out: np.ndarray) -> None:
        """``out[:] = x ⊕ dx`` (states override it to skip the temporary)."""
        out[:] = self.integrate(x, dx)

    def _diff_into(self, x0: np.ndarray, x1: np.ndarray, out: np.ndarray) -> None:
        """``out[:] = x1 ⊖ x0`` (states override it to skip the temporary)."""
        out[:] = self.diff(x0, x1)

    def _Jdiff_second_into(self, x0: np.ndarray, x1: np.ndarray, out: np.ndarray) -> None:
        """``out[:] = ∂(x1 ⊖ x0)/∂x1`` (states override it to skip the temporaries)."""
        out[:] = self.Jdiff(x0, x1, Jcomponent.second)[0]

    def _integrate_chain_rule(self, x: np.ndarray, dx: np.ndarray, Fx: np.ndarray, Fu: np.ndarray) -> None:
        """Chain rule through ``x ⊕ dx``, in place: ``Fx ← ∂(x ⊕ dx)/∂x + J_dx Fx`` and ``Fu ← J_dx Fu``.

        ``Fx (ndx, ndx)`` and ``Fu (ndx, nu)`` hold ``∂dx/∂x`` and ``∂dx/∂u``; ``J_dx`` is applied by
        :meth:`JintegrateTransport`.  States override it with a cheaper form.
        """
        self.JintegrateTransport(x, dx, Fx, Jcomponent.second)
        self.JintegrateTransport(x, dx, Fu, Jcomponent.second)
        Fx += self.Jintegrate(x, dx, Jcomponent.first)[0]


class StateVector(StateAbstract):
    """Euclidean state: ``diff`` is ``x1 - x0`` and ``integrate`` is ``x + dx``.

    Parameters
    ----------
    nx : int
        Dimension of the state (``nv = nx // 2``, ``nq = nx - nv``).
    """

    def __init__(self, nx: int) -> None:
        super().__init__(nx, nx)
        self._eye = np.eye(self.nx)
        self._vector_ops = not overridden(self, StateVector, ("diff", "integrate"))

    def zero(self) -> np.ndarray:
        return np.zeros(self.nx)

    def rand(self) -> np.ndarray:
        return np.random.rand(self.nx) * 2.0 - 1.0

    def diff(self, x0: np.ndarray, x1: np.ndarray) -> np.ndarray:
        return x1 - x0

    def integrate(self, x: np.ndarray, dx: np.ndarray) -> np.ndarray:
        return x + dx

    def Jdiff(self, x0: np.ndarray, x1: np.ndarray, firstsecond: Jcomponent = Jcomponent.both) -> list:
        if firstsecond == Jcomponent.first:
            return [-self._eye.copy()]
        if firstsecond == Jcomponent.second:
            return [self._eye.copy()]
        return [-self._eye.copy(), self._eye.copy()]

    def Jintegrate(self, x: np.ndarray, dx: np.ndarray, firstsecond: Jcomponent = Jcomponent.both) -> list:
        if firstsecond == Jcomponent.both:
            return [self._eye.copy(), self._eye.copy()]
        return [self._eye.copy()]

    def JintegrateTransport(self, x: np.ndarray, dx: np.ndarray, Jin: np.ndarray, firstsecond: Jcomponent) -> None:
        return None

    def _integrate_into(self, x: np.ndarray, dx: np.ndarray, out: np.ndarray) -> None:
        if self._vector_ops:
            np.add(x, dx, out=out)
        else:
            out[:] = self.integrate(x, dx)

    def _diff_into(self, x0: np.ndarray, x1: np.ndarray, out: np.ndarray) -> None:
        if self._vector_ops:
            np.subtract(x1, x0, out=out)
        else:
            out[:] = self.diff(x0, x1)
