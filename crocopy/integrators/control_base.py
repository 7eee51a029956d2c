"""Control parametrizations: the differential model's control along one integration step.

An integrated action model's control ``u`` (shape ``(nu,)``, the *control parameters*) need not be
the differential model's control ``w`` (shape ``(nw,)``, the *control input*).  A parametrization
gives ``w`` as a function of the normalised time ``t ∈ [0, 1]`` over the step (0 its start, 1 its
end) and of ``u``::

    calc:      w = w(t, u)                      -> data.w      (nw,)
    calcDiff:  dw_du = ∂w/∂u (t, u)             -> data.dw_du  (nw, nu)
    params:    u such that w(t, u) = w          -> data.u      (nu,)
    convertBounds(w_lb, w_ub) -> [u_lb, u_ub]     bounds on u from bounds on w
    multiplyByJacobian(A)          = A dw_du      A (na, nw) -> (na, nu)
    multiplyJacobianTransposeBy(A) = dw_duᵀ A     A (nw, na) -> (nu, na)

The two products are what the integrators' chain rule uses (``Fu = Fw dw_du``,
``Lu = dw_duᵀ Lw``, ``Luu = dw_duᵀ Lww dw_du``, ``Lxu = Lxw dw_du``), calling them as
``multiplyByJacobian(data, A)`` (Crocoddyl's abstract signature, so a Python subclass may override
them with it); they assume ``calc`` (and, for this base class's defaults, which use ``data.dw_du``,
``calcDiff``) ran at the same ``t``.  Subclasses with a structured Jacobian override the hooks
``_multiply_by_jacobian``/``_multiply_jacobian_transpose_by`` instead.  ``op``
(:class:`~crocopy.enums.AssignmentOp`) sets, adds or subtracts the product into ``out``.
"""

from __future__ import annotations

import numbers

import numpy as np

from ..enums import AssignmentOp
from ..guards import Guard, Guarded
from ..validation import as_number, as_vector


def _time_arg(owner: object, value: object, name: str) -> float:
    return as_number(value, name)


def as_dimension(value: object, name: str) -> int:
    """``value`` as a dimension (non-negative integer, not a bool) or ``ValueError`` naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < 0:
        raise ValueError(f"{name} must be a non-negative integer, got {value!r}")
    return int(value)


class ControlParametrizationModelAbstract(Guarded):
    """Crocoddyl's ``ControlParametrizationModelAbstract(nw, nu)``.

    Parameters
    ----------
    nw : int
        Dimension of the control input ``w`` (the differential model's ``nu``).
    nu : int
        Dimension of the control parameters ``u`` (the integrated model's ``nu``).

    Notes
    -----
    A user's ``calc``/``calcDiff(data, t, u)`` and ``params(data, t, w)`` are checked: ``t`` a finite
    number, ``u (nu,)``, ``w (nw,)``, finite.
    """

    _guards = {
        "calc": Guard((("data", None), ("t", _time_arg), ("u", lambda m, v, n: as_vector(v, m.nu, n)))),
        "calcDiff": Guard((("data", None), ("t", _time_arg), ("u", lambda m, v, n: as_vector(v, m.nu, n)))),
        "params": Guard((("data", None), ("t", _time_arg), ("w", lambda m, v, n: as_vector(v, m.nw, n)))),
    }

    def __init__(self, nw: int, nu: int) -> None:
        self._nw = as_dimension(nw, "nw")
        self._nu = as_dimension(nu, "nu")

    @property
    def nw(self) -> int:
        """Dimension of the control input ``w``."""
        return self._nw

    @property
    def nu(self) -> int:
        """Dimension of the control parameters ``u``."""
        return self._nu

    def createData(self) -> "ControlParametrizationDataAbstract":
        """Allocate the data this parametrization writes into."""
        return ControlParametrizationDataAbstract(self)

    def calc(self, data: "ControlParametrizationDataAbstract", t: float, u: np.ndarray) -> None:
        """Write the control input ``w(t, u)`` into ``data.w``."""
        raise NotImplementedError(f"{type(self).__name__}.calc is not implemented")

    def calcDiff(self, data: "ControlParametrizationDataAbstract", t: float, u: np.ndarray) -> None:
        """Write the Jacobian ``∂w/∂u`` into ``data.dw_du``."""
        raise NotImplementedError(f"{type(self).__name__}.calcDiff is not implemented")

    def params(self, data: "ControlParametrizationDataAbstract", t: float, w: np.ndarray) -> None:
        """Write into ``data.u`` control parameters whose control input at ``t`` is ``w``."""
        raise NotImplementedError(f"{type(self).__name__}.params is not implemented")

    def convertBounds(
        self, w_lb: np.ndarray, w_ub: np.ndarray, u_lb: np.ndarray | None = None, u_ub: np.ndarray | None = None
    ) -> list[np.ndarray]:
        """Bounds ``[u_lb, u_ub]`` (each ``(nu,)``) on the parameters from bounds on ``w`` (each ``(nw,)``).

        Also written into ``u_lb``/``u_ub`` when given (the in-place form of Crocoddyl's concrete models).
        """
        raise NotImplementedError(f"{type(self).__name__}.convertBounds is not implemented")

    def multiplyByJacobian(
        self,
        data: "ControlParametrizationDataAbstract",
        A: np.ndarray,
        op: AssignmentOp = AssignmentOp.setto,
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """``A dw_du`` for ``A`` of shape ``(na, nw)``: shape ``(na, nu)``, written into ``out`` by ``op``."""
        self._check_operand(A, 1, "A", "(na, nw)")
        return _write_product(self._multiply_by_jacobian(data, A), op, out, "multiplyByJacobian")

    def multiplyJacobianTransposeBy(
        self,
        data: "ControlParametrizationDataAbstract",
        A: np.ndarray,
        op: AssignmentOp = AssignmentOp.setto,
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """``dw_duᵀ A`` for ``A`` of shape ``(nw, na)``: shape ``(nu, na)``, written into ``out`` by ``op``."""
        self._check_operand(A, 0, "A", "(nw, na)")
        return _write_product(self._multiply_jacobian_transpose_by(data, A), op, out, "multiplyJacobianTransposeBy")

    def _multiply_by_jacobian(self, data: "ControlParametrizationDataAbstract", A: np.ndarray) -> np.ndarray:
        """A new array ``A dw_du`` (subclasses with a structured Jacobian override this)."""
        return A @ data.dw_du

    def _multiply_jacobian_transpose_by(self, data: "ControlParametrizationDataAbstract", A: np.ndarray) -> np.ndarray:
        """A new array ``dw_duᵀ A`` (subclasses with a structured Jacobian override this)."""
        return data.dw_du.T @ A

    def _check_operand(self, A: np.ndarray, axis: int, name: str, expected: str) -> None:
        if A.ndim != 2 or A.shape[axis] != self._nw:
            raise ValueError(f"{name} has shape {A.shape}, expected {expected} with nw = {self._nw}")

    def _check_bounds_args(self, w_lb: np.ndarray, w_ub: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return (
            as_vector(w_lb, self._nw, "w_lb", allow_nonfinite=True),
            as_vector(w_ub, self._nw, "w_ub", allow_nonfinite=True),
        )

    def __repr__(self) -> str:
        return f"{type(self).__name__} {{nw={self._nw}}}"


def _write_product(value: np.ndarray, op: AssignmentOp, out: np.ndarray | None, caller: str) -> np.ndarray:
    """Return ``value`` (``out is None``, ``op`` must be ``setto``) or write it into ``out`` by ``op``."""
    if out is None:
        if op != AssignmentOp.setto:
            raise ValueError(f"{caller}: op={AssignmentOp(op).name} needs an output matrix out")
        return value
    if op == AssignmentOp.setto:
        out[:] = value
    elif op == AssignmentOp.addto:
        out += value
    else:
        out -= value
    return out


class ControlParametrizationDataAbstract:
    """Data of a control parametrization: ``w (nw,)``, ``u (nu,)`` and ``dw_du (nw, nu)``."""

    def __init__(self, model: ControlParametrizationModelAbstract) -> None:
        self.w = np.zeros(model.nw)
        self.u = np.zeros(model.nu)
        self.dw_du = np.zeros((model.nw, model.nu))
