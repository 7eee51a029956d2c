"""Step and chain rule of :class:`~crocopy.integrators.euler.IntegratedActionModelEuler`: numba kernels and numpy twins.

``euler_step(a, x, dt, dx)`` writes the symplectic Euler step ``dx = ((v + a dt) dt, a dt)``.

With ``nv`` velocity rows, ``ndx = 2 nv`` and the differential model's ``(Fx, Fu)`` of shapes
``(nv, ndx)``/``(nv, nu)``, one call writes (``e`` = 1 for a Euclidean state, else 0)::

    Fx[nv:] = dt Fx_d + e [0 I],   Fx[:nv] = dt² Fx_d + dt [0 I] + e [I 0],
    Fu[nv:] = dt Fu_d,           Fu[:nv] = dt² Fu_d,
    (Lx, Lu, Lxx, Lxu, Luu) = dt (Lx_d, Lu_d, Lxx_d, Lxu_d, Luu_d)

i.e. the Euler Jacobians of a Euclidean state, and for a Lie-group state the blocks that are then
carried through ``Jintegrate`` (transport of the rows, plus ``∂(x ⊕ dx)/∂x``).  For a multibody state,
``add_integrate_jacobian(rows, Jq, Fx, Fu)`` finishes that step from the transported configuration rows
``rows = [Fx[:nv] Fu[:nv]]`` (one Pinocchio call) and ``Jq = ∂(q ⊕ dq)/∂q``::

    Fx[:nv] = rows[:, :ndx] + [Jq 0],   Fx[nv:, nv:] += I,   Fu[:nv] = rows[:, ndx:]

Each kernel has a numpy twin (``*_numpy``) giving the same numbers (tested); :mod:`crocopy.kernels`
chooses.  The kernels keep no reference counts (:func:`crocopy.kernels.uncounted`).
"""

from __future__ import annotations

import numpy as np

from ..kernels import uncounted


def euler_step_numpy(a, x, dt, dx) -> None:
    """Numpy twin of :func:`euler_step`."""
    nv = a.shape[0]
    np.multiply(a, dt, out=dx[nv:])
    np.add(x[-nv:], dx[nv:], out=dx[:nv])
    dx[:nv] *= dt


def _euler_step(a, x, dt, dx):
    nv, nx = a.shape[0], x.shape[0]
    for i in range(nv):
        dv = a[i] * dt
        dx[nv + i] = dv
        dx[i] = (x[nx - nv + i] + dv) * dt


def euler_chain_numpy(dFx, dFu, dLx, dLu, dLxx, dLxu, dLuu, dt, euclidean, Fx, Fu, Lx, Lu, Lxx, Lxu, Luu) -> None:
    """Numpy twin of :func:`euler_chain` (see the module docstring)."""
    nv = dFx.shape[0]
    ndx = Fx.shape[0]
    np.multiply(dFx, dt, out=Fx[nv:])
    np.multiply(Fx[nv:], dt, out=Fx[:nv])
    diagonal = Fx.reshape(-1)
    diagonal[nv : nv + nv * (ndx + 1) : ndx + 1] += dt
    if euclidean:
        diagonal[:: ndx + 1] += 1.0
    np.multiply(dFu, dt, out=Fu[nv:])
    np.multiply(Fu[nv:], dt, out=Fu[:nv])
    np.multiply(dLx, dt, out=Lx)
    np.multiply(dLu, dt, out=Lu)
    np.multiply(dLxx, dt, out=Lxx)
    np.multiply(dLxu, dt, out=Lxu)
    np.multiply(dLuu, dt, out=Luu)


def _euler_chain(dFx, dFu, dLx, dLu, dLxx, dLxu, dLuu, dt, euclidean, Fx, Fu, Lx, Lu, Lxx, Lxu, Luu):
    nv, ndx = dFx.shape
    nu = dFu.shape[1]
    dt2 = dt * dt
    for i in range(nv):
        for j in range(ndx):
            a = dFx[i, j]
            Fx[nv + i, j] = dt * a
            Fx[i, j] = dt2 * a
        Fx[i, nv + i] += dt
        if euclidean:
            Fx[i, i] += 1.0
            Fx[nv + i, nv + i] += 1.0
        for j in range(nu):
            b = dFu[i, j]
            Fu[nv + i, j] = dt * b
            Fu[i, j] = dt2 * b
    for i in range(ndx):
        Lx[i] = dt * dLx[i]
        for j in range(ndx):
            Lxx[i, j] = dt * dLxx[i, j]
        for j in range(nu):
            Lxu[i, j] = dt * dLxu[i, j]
    for i in range(nu):
        Lu[i] = dt * dLu[i]
        for j in range(nu):
            Luu[i, j] = dt * dLuu[i, j]


euler_step = uncounted(_euler_step)
euler_chain = uncounted(_euler_chain)


def add_integrate_jacobian_numpy(rows, Jq, Fx, Fu) -> None:
    """Numpy twin of :func:`add_integrate_jacobian`."""
    nv, ndx = Jq.shape[0], Fx.shape[1]
    Fx[:nv] = rows[:, :ndx]
    Fx[:nv, :nv] += Jq
    Fx.reshape(-1)[nv * (ndx + 1) :: ndx + 1] += 1.0
    Fu[:nv] = rows[:, ndx:]


def _add_integrate_jacobian(rows, Jq, Fx, Fu):
    nv = Jq.shape[0]
    ndx, nu = Fx.shape[1], Fu.shape[1]
    for i in range(nv):
        for j in range(ndx):
            Fx[i, j] = rows[i, j]
        for j in range(nv):
            Fx[i, j] += Jq[i, j]
        for j in range(nu):
            Fu[i, j] = rows[i, ndx + j]
        Fx[nv + i, nv + i] += 1.0


add_integrate_jacobian = uncounted(_add_integrate_jacobian)
