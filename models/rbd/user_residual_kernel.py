"""The node kernel's ``USER`` residual items (:class:`~crocopy.models.residual_numba.ResidualModelNumba`): the
kinematics buffer filled from the node's workspace, and the calls of the residual's two C callbacks
(:func:`crocopy.kernels.call_address`) on its rows of the cost stack."""

from __future__ import annotations

from crocopy.kernels import address, call_address, uncounted

from .com_kernel import center_of_mass
from .dynamics_kernel import frame_jacobian, frame_placement
from .node_table import (
    E_COM,
    E_J6,
    E_JCOM,
    E_JU,
    E_KIN,
    E_USER_DIMS,
    E_USER_RU,
    FLAGS,
    JACOBIANS_ADDRESS,
    N_PARAMETERS,
    NQ,
    NV,
    TERMINAL,
    U_START,
    ivec,
    mat,
    vec,
)


@uncounted
def user_kinematics(tbl, ints, rb, ws, fid, ref, flags, derivatives):
    """The kinematics buffer of a ``USER`` item (:mod:`crocopy.models.residual_numba`): placement (flag 1), frame
    Jacobian in ``ref`` (flag 2, ``derivatives``), centre of mass (flag 4) and its Jacobian (``derivatives``)."""
    nv = ints[NV]
    kin = vec(tbl, ints, E_KIN)
    if flags & 1:
        if derivatives and flags & 2:
            J6 = mat(tbl, ints, E_J6)
            frame_jacobian(rb, ws, fid, ref, J6)  # leaves the frame's placement in ws.Rf, ws.pf
            for i in range(6):
                for j in range(nv):
                    kin[15 + nv * i + j] = J6[i, j]
        else:
            frame_placement(rb, ws, fid, ws.Rf, ws.pf)
        for i in range(3):
            for j in range(3):
                kin[3 * i + j] = ws.Rf[i, j]
            kin[9 + i] = ws.pf[i]
    if flags & 4:
        com, Jcom = vec(tbl, ints, E_COM), mat(tbl, ints, E_JCOM)
        center_of_mass(rb, ws, com, Jcom)
        for i in range(3):
            kin[12 + i] = com[i]
        if derivatives:
            for i in range(3):
                for j in range(nv):
                    kin[15 + 6 * nv + nv * i + j] = Jcom[i, j]


@uncounted
def user_call(tbl, ints, par, b, x, u, function, out, out_u):
    """Call a ``USER`` item's C callback ``function`` (:func:`crocopy.kernels.call_address`) on ``out``/``out_u``."""
    dims = ivec(tbl, ints, E_USER_DIMS)
    o, npar = ints[b + 5], ints[b + N_PARAMETERS]
    dims[0], dims[1], dims[2], dims[3], dims[4] = ints[NQ], ints[NV], u.shape[0], ints[b + 2], npar
    call_address(function, address(dims), address(par[o: o + npar]), address(x), address(u),
                 address(vec(tbl, ints, E_KIN)), address(out), address(out_u))


@uncounted
def user_jacobians(tbl, ints, par, rb, ws, b, x, u, rows):
    """A ``USER`` item's rows of ``Jx`` and, when it depends on ``u`` at a running node, of ``Ju`` (zeroed, then
    written by its callback)."""
    start, nr, flags = ints[b + 1], ints[b + 2], ints[b + FLAGS]
    for i in range(nr):
        for j in range(rows.shape[1]):
            rows[i, j] = 0.0
    if flags & 8 and not ints[TERMINAL]:
        Ju, u0 = mat(tbl, ints, E_JU), start - ints[U_START]
        out_u = Ju[u0: u0 + nr]
    else:
        out_u = mat(tbl, ints, E_USER_RU)[:nr]
    for i in range(out_u.shape[0]):
        for j in range(out_u.shape[1]):
            out_u[i, j] = 0.0
    user_kinematics(tbl, ints, rb, ws, ints[b + 3], ints[b + 4], flags, True)
    user_call(tbl, ints, par, b, x, u, ints[b + JACOBIANS_ADDRESS], rows, out_u)
