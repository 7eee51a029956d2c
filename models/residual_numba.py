"""A user's residual written as numba-compilable functions of arrays: it runs inside compiled nodes.

A subclass of :class:`ResidualModelNumba` gives two static functions of arrays and a parameter vector::

    compute_residual(r, x, u, p, kin)          # writes r (nr,)
    compute_jacobians(Rx, Ru, x, u, p, kin)    # writes Rx (nr, ndx) and Ru (nr, nu); both arrive zeroed

``x (nx,)`` and ``u (nu,)`` are the node's state and control (``u`` empty at a terminal node), ``p`` is
:meth:`ResidualModelNumba.parameters` (read again at every solve and every Python evaluation) and ``kin`` the
node's kinematics (:data:`NodeKinematics`) at ``x``, as the constructor's ``kinematics`` asked:

* ``kin.R (3, 3)`` and ``kin.p (3,)``: the world placement of frame ``frame`` (``"placement"``);
* ``kin.J (6, nv)``: its Jacobian in ``frame_reference`` (``pinocchio.LOCAL``, ``WORLD`` or
  ``LOCAL_WORLD_ALIGNED``), linear rows first (``"jacobian"``; filled for ``compute_jacobians`` only);
* ``kin.com (3,)`` and ``kin.Jcom (3, nv)``: the centre of mass and its Jacobian (``"com"``; ``Jcom`` filled for
  ``compute_jacobians`` only).

Inside a solve a compiled node (:mod:`.rbd.euler_node`) calls them through C callbacks with its own kinematics
(:func:`crocopy.kernels.call_address`), so the node stays one compiled call.  Called directly, ``calc``/``calcDiff``
read the same kinematics from the node's Pinocchio data and call the same functions (compiled while
:func:`crocopy.kernels_enabled`, plain Python otherwise): one answer on every path.
:func:`check_residual_derivatives` compares ``compute_jacobians`` with finite differences of ``compute_residual``
and names the first wrong entry.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np
import pinocchio as pin

from crocopy import kernels
from crocopy.data_collector import DataCollectorAbstract
from crocopy.residuals.base import ResidualDataAbstract, ResidualModelAbstract

from .data_collectors import DataCollectorMultibody
from .force_base import frame_id
from .residuals_frame import frame_jacobian, shared_pinocchio
from .state_multibody import StateMultibody

NodeKinematics = namedtuple("NodeKinematics", "R p com J Jcom")
"""The kinematics a :class:`ResidualModelNumba`'s functions read: ``R (3, 3)``, ``p (3,)``, ``com (3,)``,
``J (6, nv)``, ``Jcom (3, nv)`` (views of one buffer, :func:`kinematics_size`)."""

PLACEMENT, JACOBIAN, COM, U_DEPENDENT = 1, 2, 4, 8
"""Flags of a lowered residual: the kinematics it reads, and whether it depends on ``u``."""
KINEMATICS = {"placement": PLACEMENT, "jacobian": PLACEMENT | JACOBIAN, "com": COM}
REFERENCES = {pin.WORLD: 0, pin.LOCAL: 1, pin.LOCAL_WORLD_ALIGNED: 2}


def kinematics_size(nv: int) -> int:
    """Length of the kinematics buffer: ``R`` (9), ``p`` (3), ``com`` (3), ``J`` (6 nv), ``Jcom`` (3 nv)."""
    return 15 + 9 * nv


def _unpack(buffer: np.ndarray, nv: int) -> NodeKinematics:
    """The views of a kinematics buffer (Python path)."""
    return NodeKinematics(buffer[:9].reshape((3, 3)), buffer[9:12], buffer[12:15],
                          buffer[15:15 + 6 * nv].reshape((6, nv)), buffer[15 + 6 * nv:].reshape((3, nv)))


def _kinematics_at(address, nv):
    """The views of the kinematics buffer at ``address`` (in a callback: no reshape, 8 bytes per float)."""
    matrix_at, vector_at = kernels.matrix_at, kernels.vector_at
    return NodeKinematics(matrix_at(address, 3, 3), vector_at(address + 72, 3), vector_at(address + 96, 3),
                          matrix_at(address + 120, 6, nv), matrix_at(address + 120 + 48 * nv, 3, nv))


kinematics_at = kernels.jit(_kinematics_at)


class ResidualModelNumba(ResidualModelAbstract):
    """Base class of a residual given as numba-compilable functions (see the module docstring).

    Parameters
    ----------
    state : StateMultibody
        The robot's state.
    nr : int
        Residual dimension.
    nu : int, optional
        Control dimension (default ``state.nv``).
    frame : int or str, optional
        The frame whose placement and Jacobian ``kin`` holds (default 0).
    frame_reference : pinocchio.ReferenceFrame, optional
        The frame in which ``kin.J`` is expressed (default ``LOCAL_WORLD_ALIGNED``).
    kinematics : sequence of str, optional
        What ``kin`` must hold: any of ``"placement"``, ``"jacobian"``, ``"com"`` (default none).
    q_dependent, v_dependent, u_dependent : bool, optional
        Which arguments the residual depends on (default True, True, False).
    """

    def __init__(self, state: StateMultibody, nr: int, nu: int | None = None, frame: int | str = 0,
                 frame_reference: pin.ReferenceFrame = pin.LOCAL_WORLD_ALIGNED, kinematics: tuple = (),
                 q_dependent: bool = True, v_dependent: bool = True, u_dependent: bool = False) -> None:
        if not isinstance(state, StateMultibody):
            raise TypeError(f"state must be a StateMultibody, got {type(state).__name__}")
        super().__init__(state, nr, nu, q_dependent, v_dependent, u_dependent)
        for name in ("compute_residual", "compute_jacobians"):
            if not callable(getattr(type(self), name, None)):
                raise TypeError(f"{type(self).__name__} must define the static function {name}")
        if frame_reference not in REFERENCES:
            raise ValueError(f"frame_reference must be a pinocchio.ReferenceFrame, got {frame_reference!r}")
        unknown = [k for k in kinematics if k not in KINEMATICS]
        if isinstance(kinematics, str) or unknown:
            raise ValueError(f"kinematics must be a sequence of {sorted(KINEMATICS)}, got {kinematics!r}")
        self._frame = frame_id(state, frame)
        self._frame_reference = frame_reference
        flags = U_DEPENDENT if u_dependent else 0
        for k in kinematics:
            flags |= KINEMATICS[k]
        self._flags = flags

    @property
    def frame(self) -> int:
        """The frame of ``kin.R``, ``kin.p`` and ``kin.J``."""
        return self._frame

    @property
    def frame_reference(self) -> pin.ReferenceFrame:
        """The frame in which ``kin.J`` is expressed."""
        return self._frame_reference

    @property
    def flags(self) -> int:
        """The kinematics the functions read and the ``u`` dependence (:data:`PLACEMENT`, ...)."""
        return self._flags

    def parameters(self) -> np.ndarray:
        """The parameter vector ``p`` handed to the functions (default empty); read at every solve and call."""
        return np.zeros(0)

    def checked_parameters(self) -> np.ndarray:
        """:meth:`parameters` as a finite float vector (ValueError naming the class otherwise)."""
        p = np.ascontiguousarray(self.parameters(), dtype=float).reshape(-1)
        if not np.isfinite(p).all():
            raise ValueError(f"{type(self).__name__}.parameters() returned a non-finite value: {p}")
        return p

    def functions(self) -> tuple:
        """``(compute_residual, compute_jacobians)``: compiled while :func:`crocopy.kernels_enabled`, else the plain
        Python functions (compiled once per class)."""
        if not kernels.active:
            return type(self).compute_residual, type(self).compute_jacobians
        cls = type(self)
        if "_compiled_functions" not in cls.__dict__:
            cls._compiled_functions = (kernels.jit(cls.compute_residual), kernels.jit(cls.compute_jacobians))
        return cls._compiled_functions

    def callbacks(self) -> tuple[int, int]:
        """Addresses of the C callbacks of the two functions, for compiled nodes (built once per class)."""
        cls = type(self)
        if "_callbacks" not in cls.__dict__:
            cls._callbacks = c_callbacks(*self.functions())
        return cls._callbacks[0], cls._callbacks[1]

    def createData(self, data: DataCollectorAbstract | None = None) -> ResidualDataNumba:
        return ResidualDataNumba(self, data)

    def calc(self, data: ResidualDataNumba, x: np.ndarray, u: np.ndarray | None = None) -> None:
        compute_residual = self.functions()[0]
        compute_residual(data.r, x, data.no_control if u is None else u, self.checked_parameters(),
                         data.read_kinematics(self, False))

    def calcDiff(self, data: ResidualDataNumba, x: np.ndarray, u: np.ndarray | None = None) -> None:
        compute_jacobians = self.functions()[1]
        data.Rx[:] = 0.0
        data.Ru[:] = 0.0
        compute_jacobians(data.Rx, data.Ru, x, data.no_control if u is None else u, self.checked_parameters(),
                          data.read_kinematics(self, True))


class ResidualDataNumba(ResidualDataAbstract):
    """Data of a :class:`ResidualModelNumba`: ``pinocchio`` (the collector's) and the kinematics buffer."""

    def __init__(self, model: ResidualModelNumba, data: DataCollectorAbstract | None) -> None:
        super().__init__(model, data)
        self.pinocchio = shared_pinocchio(data, model.state, type(model).__name__)
        self.buffer = np.zeros(kinematics_size(model.state.nv))
        self.kinematics = _unpack(self.buffer, model.state.nv)
        self.no_control = np.zeros(0)

    def read_kinematics(self, model: ResidualModelNumba, derivatives: bool) -> NodeKinematics:
        """Fill the kinematics buffer from the Pinocchio data (after the dynamics model's evaluation)."""
        pmodel, pd, kin, flags = model.state.pinocchio, self.pinocchio, self.kinematics, model.flags
        if flags & PLACEMENT:
            oMf = pin.updateFramePlacement(pmodel, pd, model.frame)
            kin.R[:] = oMf.rotation
            kin.p[:] = oMf.translation
            if derivatives and flags & JACOBIAN:
                kin.J[:] = frame_jacobian(pmodel, pd, model.frame, model.frame_reference)
        if flags & COM:
            kin.com[:] = pin.centerOfMass(pmodel, pd, pin.POSITION, False)
            if derivatives:
                kin.Jcom[:] = pin.jacobianCenterOfMass(pmodel, pd, False)
        return kin


def c_callbacks(compute_residual, compute_jacobians) -> tuple:
    """``(residual address, jacobians address, keep)``: the two functions behind the uniform C signature of
    :func:`crocopy.kernels.call_address`: ``(dims, p, x, u, kin, out, out_u)`` with ``dims = (nq, nv, nu, nr,
    npar)`` (int64), ``out`` the residual (or ``Rx``) and ``out_u`` ``Ru``."""
    vector_at, matrix_at, int64_pointer, carray = (kernels.vector_at, kernels.matrix_at, kernels.int64_pointer,
                                                   kernels.carray)

    def residual(dims, p, x, u, kin, out, out_u):
        d = carray(int64_pointer(dims), (5,))
        nq, nv, nu, nr, npar = d[0], d[1], d[2], d[3], d[4]
        compute_residual(vector_at(out, nr), vector_at(x, nq + nv), vector_at(u, nu), vector_at(p, npar),
                         kinematics_at(kin, nv))

    def jacobians(dims, p, x, u, kin, out, out_u):
        d = carray(int64_pointer(dims), (5,))
        nq, nv, nu, nr, npar = d[0], d[1], d[2], d[3], d[4]
        compute_jacobians(matrix_at(out, nr, 2 * nv), matrix_at(out_u, nr, nu), vector_at(x, nq + nv),
                          vector_at(u, nu), vector_at(p, npar), kinematics_at(kin, nv))

    r_address, r_keep = kernels.c_callback(residual)
    j_address, j_keep = kernels.c_callback(jacobians)
    return r_address, j_address, (r_keep, j_keep)


def check_residual_derivatives(residual: ResidualModelNumba, x: np.ndarray | None = None,
                               u: np.ndarray | None = None, h: float = 1e-6, rtol: float = 1e-4,
                               atol: float = 1e-6) -> None:
    """Compare ``compute_jacobians`` with central differences of ``compute_residual`` (through a free-dynamics
    node's Pinocchio data, at ``x`` and ``u``, random by default); raises AssertionError naming the first entry
    ``Rx[i, j]`` or ``Ru[i, j]`` outside ``rtol``/``atol``."""
    state = residual.state
    x = state.rand() if x is None else np.asarray(x, dtype=float)
    u = np.random.default_rng(0).standard_normal(residual.nu) if u is None else np.asarray(u, dtype=float)
    pmodel = state.pinocchio
    pdata = pmodel.createData()
    data = residual.createData(DataCollectorMultibody(pdata))
    nq = state.nq

    def evaluate(xx: np.ndarray, uu: np.ndarray, derivatives: bool) -> None:
        pin.forwardKinematics(pmodel, pdata, xx[:nq], xx[nq:])
        pin.computeJointJacobians(pmodel, pdata, xx[:nq])
        pin.updateFramePlacements(pmodel, pdata)
        residual.calc(data, xx, uu)
        if derivatives:
            residual.calcDiff(data, xx, uu)

    evaluate(x, u, True)
    Rx, Ru = data.Rx.copy(), data.Ru.copy()
    ndx = state.ndx
    for j in range(ndx + residual.nu):
        e = np.zeros(ndx + residual.nu)
        e[j] = h
        evaluate(state.integrate(x, e[:ndx]), u + e[ndx:], False)
        plus = data.r.copy()
        evaluate(state.integrate(x, -e[:ndx]), u - e[ndx:], False)
        column = (plus - data.r) / (2 * h)
        analytic = Rx[:, j] if j < ndx else Ru[:, j - ndx]
        name, col = ("Rx", j) if j < ndx else ("Ru", j - ndx)
        for i in range(residual.nr):
            if abs(column[i] - analytic[i]) > atol + rtol * abs(column[i]):
                raise AssertionError(
                    f"{type(residual).__name__}: {name}[{i}, {col}] = {analytic[i]:.6g}, finite differences give "
                    f"{column[i]:.6g}"
                )
