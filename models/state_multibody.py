"""Multibody state ``x = (q, v)`` on Pinocchio's configuration Lie group.

``nq``/``nv`` come from the Pinocchio model, ``nx = nq + nv`` and ``ndx = 2 nv``.
``diff(x0, x1) = (q1 ⊖ q0, v1 - v0)`` and ``integrate(x, dx) = (q ⊕ dq, v + dv)`` use
``pinocchio.difference``/``pinocchio.integrate``, except on continuous joints (``q = [cos θ, sin θ]``), whose
difference is ``atan2(c0 s1 - s0 c1, c0 c1 + s0 s1)`` computed here: Pinocchio returns exactly 0 when
``c0 c1 + s0 s1`` rounds above 1, i.e. for some angles below about 1e-8 (the compiled
:func:`~crocopy.models.rbd.configuration_kernel.difference` uses the same formula).  The Jacobians are block diagonal:

    Jdiff   = (diag(∂(q1 ⊖ q0)/∂q0, -I), diag(∂(q1 ⊖ q0)/∂q1, I))
    Jintegrate = (diag(∂(q ⊕ dq)/∂q, I), diag(∂(q ⊕ dq)/∂dq, I))

with the configuration blocks from ``pinocchio.dDifference``/``pinocchio.dIntegrate``.

The solvers and models call in-place forms (``_diff_into``, ``_integrate_into``,
``_Jdiff_second_into`` and the Euler chain rule ``_integrate_chain_rule``, whose last step is the
compiled :func:`~crocopy.integrators.euler_kernel.add_integrate_jacobian`) that call Pinocchio
directly.  A subclass that overrides ``diff``, ``integrate``, ``Jdiff``, ``Jintegrate`` or
``JintegrateTransport`` is honoured: the in-place forms built on the overridden operation then go
through it (the generic :class:`~crocopy.state.StateAbstract` forms), logged once per class and
operation at DEBUG level on the ``"crocopy"`` logger.
"""

from __future__ import annotations

import copyreg
import math
import threading

import numpy as np
import pinocchio as pin

import crocopy.kernels as kernels
from crocopy.enums import Jcomponent
from crocopy.integrators.euler_kernel import add_integrate_jacobian, add_integrate_jacobian_numpy
from crocopy.kernels import log_fallback, overridden
from crocopy.state import StateAbstract

from .pinocchio_pickle import remember_model

_HUGE = 1e300  # URDF "no limit" values (numeric_limits::max) are mapped to inf


_IN_PLACE = {
    "_diff_into": ("the in-place diff", ("diff",)),
    "_integrate_into": ("the in-place integrate", ("integrate",)),
    "_Jdiff_second_into": ("the in-place Jdiff", ("Jdiff",)),
    "_integrate_chain_rule": ("the compiled Euler chain rule", ("Jintegrate", "JintegrateTransport")),
}
"""In-place form → (what it is, the public operations it must agree with)."""

_ARG0, _ARG1 = pin.ARG0, pin.ARG1
_SCRATCH = threading.local()
"""Per thread: ``rows``, the ``[Fx[:nv] Fu[:nv]]`` matrices of the Euler chain rule by shape (filled and
read within one call)."""


def _scratch_rows(shape: tuple[int, int]) -> np.ndarray:
    if not hasattr(_SCRATCH, "rows"):
        _SCRATCH.rows = {}
    rows = _SCRATCH.rows[shape] = np.empty(shape)
    return rows


_CONTINUOUS = ("JointModelRUBX", "JointModelRUBY", "JointModelRUBZ", "JointModelRevoluteUnboundedUnaligned")
"""Pinocchio's continuous (unbounded revolute) joints, ``q = [cos θ, sin θ]``."""

_MODEL_VECTORS = ("lowerPositionLimit", "upperPositionLimit", "velocityLimit", "effortLimit", "armature")


def _restore_model(model: pin.Model, fixes: dict) -> pin.Model:
    """Unpickle a model saved by :func:`_reduce_model`: put back the name and non-finite vectors."""
    for attr, value in fixes.items():
        setattr(model, attr, value)
    return model


def _reduce_model(model: pin.Model) -> tuple:
    """Pickle a ``pinocchio.Model`` with Pinocchio's own text archive, which cannot read back an
    empty name or non-finite limits (Talos legs has both): those are pickled beside a cleaned copy."""
    fixes = {} if model.name else {"name": ""}
    for attr in _MODEL_VECTORS:
        value = np.asarray(getattr(model, attr))
        if not np.all(np.isfinite(value)):
            fixes[attr] = value.copy()
    if not fixes:
        return model.__reduce__()
    clean = pin.Model(model)
    clean.name = model.name or "unnamed"
    for attr in fixes.keys() - {"name"}:
        setattr(clean, attr, np.nan_to_num(fixes[attr], posinf=0.0, neginf=0.0))
    return _restore_model, (clean, fixes)


copyreg.pickle(pin.Model, _reduce_model)


def _finite_or_inf(values: np.ndarray, sign: float) -> np.ndarray:
    out = np.array(values, dtype=float)
    out[~np.isfinite(out) | (np.abs(out) >= _HUGE)] = sign * np.inf
    return out


class StateMultibody(StateAbstract):
    """Crocoddyl's ``StateMultibody(pinocchio_model)``.

    Parameters
    ----------
    model : pinocchio.Model
        Multibody model; stored as ``pinocchio``.

    Notes
    -----
    ``lb``/``ub`` hold the position limits followed by ``∓velocityLimit``; entries are ``∓inf`` on
    joints whose configuration is not a vector (``joint.nq != joint.nv``: free flyer, spherical,
    planar, unbounded revolute) and where the URDF gives "unlimited" values.
    """

    def __init__(self, model: pin.Model) -> None:
        if not isinstance(model, pin.Model):
            raise ValueError(f"model must be a pinocchio.Model, got {type(model).__name__}")
        super().__init__(model.nq + model.nv, 2 * model.nv)
        self.pinocchio = model
        remember_model(model)
        self.nq, self.nv = model.nq, model.nv
        lq = _finite_or_inf(model.lowerPositionLimit, -1.0)
        uq = _finite_or_inf(model.upperPositionLimit, 1.0)
        for joint in model.joints[1:]:
            if joint.nq != joint.nv:
                lq[joint.idx_q:joint.idx_q + joint.nq] = -np.inf
                uq[joint.idx_q:joint.idx_q + joint.nq] = np.inf
        vlim = _finite_or_inf(model.velocityLimit, 1.0)
        self._set_limits(np.concatenate([lq, -vlim]), np.concatenate([uq, vlim]))
        self._q0 = pin.neutral(model)
        self._continuous = tuple((j.idx_q, j.idx_v) for j in model.joints[1:] if j.shortname() in _CONTINUOUS)
        self._rand_lo = np.where(np.isfinite(lq), lq, -1.0)
        self._rand_hi = np.where(np.isfinite(uq), uq, 1.0)
        nv, ndx = self.nv, self.ndx
        self._Jpos = np.zeros((ndx, ndx))  # templates with ±I in the velocity block
        self._Jpos[nv:, nv:] = np.eye(nv)
        self._Jneg = -self._Jpos
        generic = []
        for form, (what, operations) in _IN_PLACE.items():
            steps = overridden(self, StateMultibody, operations)
            if steps:
                generic.append(form)
                log_fallback(type(self), steps, what)
        self._generic = tuple(generic)  # in-place forms that go through the overridden operations

    def zero(self) -> np.ndarray:
        """Neutral configuration and zero velocity."""
        return np.concatenate([self._q0, np.zeros(self.nv)])

    def rand(self) -> np.ndarray:
        """Random configuration within the finite position limits (``[-1, 1]`` elsewhere, then normalized
        onto the joint manifolds), random velocity in ``[-1, 1]``; drawn from NumPy's global generator."""
        q = self._rand_lo + np.random.rand(self.nq) * (self._rand_hi - self._rand_lo)
        q = pin.normalize(self.pinocchio, q)
        return np.concatenate([q, np.random.rand(self.nv) * 2.0 - 1.0])

    def diff(self, x0: np.ndarray, x1: np.ndarray) -> np.ndarray:
        nq = self.nq
        dq = pin.difference(self.pinocchio, x0[:nq], x1[:nq])
        if self._continuous:
            self._continuous_difference(x0, x1, dq)
        return np.concatenate([dq, x1[nq:] - x0[nq:]])

    def _continuous_difference(self, x0: np.ndarray, x1: np.ndarray, out: np.ndarray) -> None:
        """Where Pinocchio's difference ``out`` of a continuous joint is exactly 0, write ``atan2(c0 s1 - s0 c1,
        c0 c1 + s0 s1)`` (elsewhere Pinocchio's value is that formula already, bit for bit, as in the kernel)."""
        for a, k in self._continuous:
            if out[k] == 0.0:
                c0, s0, c1, s1 = x0[a], x0[a + 1], x1[a], x1[a + 1]
                out[k] = math.atan2(c0 * s1 - s0 * c1, c0 * c1 + s0 * s1)

    def integrate(self, x: np.ndarray, dx: np.ndarray) -> np.ndarray:
        nq, nv = self.nq, self.nv
        return np.concatenate([pin.integrate(self.pinocchio, x[:nq], dx[:nv]), x[nq:] + dx[nv:]])

    def _block(self, Jq: np.ndarray, sign: float) -> np.ndarray:
        """``[[Jq, 0], [0, ±I]]``."""
        J = (self._Jpos if sign > 0.0 else self._Jneg).copy()
        J[: self.nv, : self.nv] = Jq
        return J

    def Jdiff(self, x0: np.ndarray, x1: np.ndarray, firstsecond: Jcomponent = Jcomponent.both) -> list:
        """Jacobians of ``x1 ⊖ x0`` w.r.t. ``x0`` and/or ``x1``, each ``(ndx, ndx)``."""
        nq, model = self.nq, self.pinocchio
        q0, q1 = x0[:nq], x1[:nq]
        out = []
        if firstsecond in (Jcomponent.first, Jcomponent.both):
            out.append(self._block(pin.dDifference(model, q0, q1, pin.ARG0), -1.0))
        if firstsecond in (Jcomponent.second, Jcomponent.both):
            out.append(self._block(pin.dDifference(model, q0, q1, pin.ARG1), 1.0))
        return out

    def Jintegrate(self, x: np.ndarray, dx: np.ndarray, firstsecond: Jcomponent = Jcomponent.both) -> list:
        """Jacobians of ``x ⊕ dx`` w.r.t. ``x`` and/or ``dx``, each ``(ndx, ndx)``."""
        q, dq, model = x[: self.nq], dx[: self.nv], self.pinocchio
        out = []
        if firstsecond in (Jcomponent.first, Jcomponent.both):
            out.append(self._block(pin.dIntegrate(model, q, dq, pin.ARG0), 1.0))
        if firstsecond in (Jcomponent.second, Jcomponent.both):
            out.append(self._block(pin.dIntegrate(model, q, dq, pin.ARG1), 1.0))
        return out

    def JintegrateTransport(self, x: np.ndarray, dx: np.ndarray, Jin: np.ndarray, firstsecond: Jcomponent) -> None:
        """Parallel-transport the first ``nv`` rows of ``Jin`` from ``x ⊕ dx`` to ``x``, in place."""
        if firstsecond == Jcomponent.both:
            raise ValueError("firstsecond must be Jcomponent.first or Jcomponent.second")
        arg = pin.ARG0 if firstsecond == Jcomponent.first else pin.ARG1
        nv = self.nv
        if Jin.shape[-1] == 0:
            return
        rows = Jin[:nv]
        rows[...] = np.reshape(pin.dIntegrateTransport(self.pinocchio, x[: self.nq], dx[:nv], rows, arg), rows.shape)

    def _integrate_into(self, x: np.ndarray, dx: np.ndarray, out: np.ndarray) -> None:
        if self._generic and "_integrate_into" in self._generic:
            super()._integrate_into(x, dx, out)
            return
        nq, nv = self.nq, self.nv
        out[:nq] = pin.integrate(self.pinocchio, x[:nq], dx[:nv])
        np.add(x[nq:], dx[nv:], out=out[nq:])

    def _diff_into(self, x0: np.ndarray, x1: np.ndarray, out: np.ndarray) -> None:
        if self._generic and "_diff_into" in self._generic:
            super()._diff_into(x0, x1, out)
            return
        nq, nv = self.nq, self.nv
        out[:nv] = pin.difference(self.pinocchio, x0[:nq], x1[:nq])
        if self._continuous:
            self._continuous_difference(x0, x1, out)
        np.subtract(x1[nq:], x0[nq:], out=out[nv:])

    def _Jdiff_second_into(self, x0: np.ndarray, x1: np.ndarray, out: np.ndarray) -> None:
        """``out = [[∂(x1 ⊖ x0)/∂q1, 0], [0, I]]``."""
        if self._generic and "_Jdiff_second_into" in self._generic:
            super()._Jdiff_second_into(x0, x1, out)
            return
        nq, nv = self.nq, self.nv
        out[:] = self._Jpos
        out[:nv, :nv] = pin.dDifference(self.pinocchio, x0[:nq], x1[:nq], _ARG1)

    def _integrate_chain_rule(self, x: np.ndarray, dx: np.ndarray, Fx: np.ndarray, Fu: np.ndarray) -> None:
        """Chain rule through ``x ⊕ dx`` (see :meth:`StateAbstract._integrate_chain_rule`): Pinocchio's
        ``dIntegrateTransport`` on the configuration rows of ``[Fx Fu]`` (one call, copied into a per-thread
        scratch matrix), ``dIntegrate`` on the configuration block and the identity on the velocity block."""
        if "_integrate_chain_rule" in self._generic:
            super()._integrate_chain_rule(x, dx, Fx, Fu)
            return
        model, nv, ndx = self.pinocchio, self.nv, self.ndx
        q, dq = x[: self.nq], dx[:nv]
        shape = (nv, ndx + Fu.shape[1])
        try:
            rows = _SCRATCH.rows[shape]
        except (AttributeError, KeyError):
            rows = _scratch_rows(shape)
        rows[:, :ndx] = Fx[:nv]
        rows[:, ndx:] = Fu[:nv]
        rows = pin.dIntegrateTransport(model, q, dq, rows, _ARG1)
        add = add_integrate_jacobian if kernels.active else add_integrate_jacobian_numpy
        add(rows if rows.ndim == 2 else np.reshape(rows, shape), pin.dIntegrate(model, q, dq, _ARG0), Fx, Fu)

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        remember_model(self.pinocchio)

    def __repr__(self) -> str:
        return f"StateMultibody(nq={self.nq}, nv={self.nv})"
