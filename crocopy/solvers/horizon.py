"""The DDP family's backward pass in one compiled call: stacked solver buffers and the nodes' derivatives.

One compiled call per backward pass (:func:`~crocopy.solvers.riccati_kernel.riccati_pass`,
:func:`~crocopy.solvers.box_kernel.box_pass`) instead of one per node: numba's dispatch of some
twenty arrays per node cost several µs, more than the node's arithmetic on small problems.  The call
receives two integer tables of *addresses* (and the per-node dimensions :attr:`Horizon.dims`); the
kernel views the memory there as arrays (``numba.carray``, :func:`crocopy.kernels.float64_pointer`),
which costs nothing per node, where a numba typed list cost ~45 ns per item and a reshaped slice
~40 ns.  The arrays are kept alive by the objects that list them.

* **The solver's own arrays** (``Vxx, Vx`` of the T+1 nodes; ``Qxx, Qxu, Quu, Qx, Qu, K, k`` and
  Box-DDP's ``Quu_inv`` of the T running nodes; FDDP's ``Vxx fs``; the gaps ``fs``): one flat float64
  buffer :attr:`Horizon.buf` with per-node offsets :attr:`Horizon.off` (``(T+1, NQ)``, columns
  :data:`VXX` ... :data:`FS`) and addresses :attr:`Horizon.addr`.  The solver's lists (Crocoddyl's
  API) hold C-contiguous reshaped views of their slices, so what the kernel writes is what
  ``solver.K[t]`` shows.  The solvers write these arrays in place and never rebind an entry; assigning
  ``solver.fs`` copies into them (:class:`~crocopy.solvers.std_vector.Trajectory`).
* **The nodes' derivatives** (``Fx, Fu, Lxx, Lxu, Luu, Lx, Lu`` of ``problem.runningDatas``):
  :attr:`NodeDerivatives.addr` ``(T, 7)`` lists where the datas' *own* arrays are.  They are not
  moved into a stack owned by the problem or the solver: a model's ``calcDiff`` keeps writing where
  it always did, so every writer (integrators, action models, a cost sum sharing its memory with the
  data, squashing, control parametrizations, a user's Python model) stays correct without relying on
  an audit of all of them.  Assigning one (``data.Fx = M``) copies into the data's array
  (:mod:`crocopy.stored`, Crocoddyl's semantics), so the addresses taken once per list of datas stay valid.
  A data class that makes one of these a property or a slot of its own has its node compared at
  every pass; an array the kernel cannot read in place (not float64 or not C-contiguous) is copied
  into a staging array at every pass; shapes are checked when an array is taken (a wrong size raises
  ValueError): the compiled pass trusts them.
* A changed list of datas (``problem.updateModel``, ``circularAppend``) makes the solver follow the
  problem first (``_sync_problem``: re-allocation when a node's dimensions changed).

Nodes of different sizes share the buffers: each node has its own ``(ndx, nu)`` (an impulse node
has ``nu = 0``: its ``Qu``, ``K``, ``k`` ... are empty and the kernel skips the gains).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..stored import Stored

VXX, VX, QXX, QXU, QUU, QX, QU, KM, KV, QUU_INV, VXX_F, FS = range(12)
"""Columns of :attr:`Horizon.off`: where each per-node array of the solver starts in :attr:`Horizon.buf`."""
NQ = 12

NAMES = ("Fx", "Fu", "Lxx", "Lxu", "Luu", "Lx", "Lu")
"""The derivatives of a running data the compiled pass reads, in the columns of :attr:`NodeDerivatives.addr`."""


class Horizon:
    """The solver's per-node arrays as views of one buffer.

    Parameters
    ----------
    ndx : sequence of int
        Tangent dimension of the T+1 nodes.
    nu : sequence of int
        Control dimension of the T running nodes.
    """

    def __init__(self, ndx: Sequence[int], nu: Sequence[int]) -> None:
        T = len(nu)
        self.T = T
        self.off = np.zeros((T + 1, NQ), dtype=np.int64)
        self.dims = np.array([(int(ndx[t]), int(nu[t]) if t < T else 0) for t in range(T + 1)], dtype=np.int64)
        shapes: list[list[tuple]] = []
        pos = 0
        for t in range(T + 1):
            n, m = int(ndx[t]), int(nu[t]) if t < T else 0
            node = [(n, n), (n,), (n, n), (n, m), (m, m), (n,), (m,), (m, n), (m,), (m, m), (n,), (n,)]
            for j, shape in enumerate(node):
                self.off[t, j] = pos
                pos += int(np.prod(shape))
            shapes.append(node)
        self.buf = np.zeros(pos)
        self.addr = address(self.buf) + 8 * self.off
        """Where each array starts in memory (the kernels read them by address)."""
        self._views = [[self._view(t, j, shapes[t][j]) for t in range(T + 1)] for j in range(NQ)]

    def __getstate__(self) -> dict:
        return {"dims": self.dims, "buf": self.buf}

    def __setstate__(self, state: dict) -> None:
        dims = state["dims"]
        self.__init__(dims[:, 0], dims[:-1, 1])
        self.buf[:] = state["buf"]

    def _view(self, t: int, j: int, shape: tuple) -> np.ndarray:
        start = self.off[t, j]
        return self.buf[start:start + int(np.prod(shape))].reshape(shape)

    def views(self, j: int, running: bool = False) -> list[np.ndarray]:
        """A new list of the views of column ``j`` (the T running nodes only if ``running``)."""
        return list(self._views[j][: self.T if running else self.T + 1])


def address(a: np.ndarray) -> int:
    """Where the first element of ``a`` is in memory."""
    return a.__array_interface__["data"][0]


class NodeDerivatives:
    """The addresses of the running datas' own derivative arrays, taken at the first :meth:`update` (a solver makes
    a new one when the problem's nodes change: ``updateModel``, ``circularAppend``, datas rebuilt).

    :attr:`addr` ``(T, 7)``: row t holds where ``Fx, Fu, Lxx, Lxu, Luu, Lx, Lu`` (:data:`NAMES`) of
    ``datas[t]`` are.  The arrays are referenced here as long as their address is listed.  A subclass lists
    other fields (:attr:`names`, shaped by :meth:`node_shapes`).
    """

    names: tuple[str, ...] = NAMES
    """The data fields listed, in the columns of :attr:`addr`."""

    @staticmethod
    def node_shapes(dims: Sequence[tuple[int, ...]]) -> list[list[tuple]]:
        """The shape of each field of :attr:`names` at each node (``dims[t] = (ndx, nu)``)."""
        return [[(n, n), (n, m), (n, n), (n, m), (m, m), (n,), (m,)] for n, m in dims]

    def __init__(self) -> None:
        self._seen: list[list] = []
        self._shapes: list[list[tuple]] = []
        self._stale: list[int] = []
        self._staged: list[tuple[int, str, np.ndarray]] = []
        self.addr = np.zeros((0, len(self.names)), dtype=np.int64)
        self._kept: list[list] = []

    def __reduce__(self) -> tuple:
        """A copy lists nothing yet (addresses are not valid in another process or object)."""
        return type(self), ()

    def update(self, datas: list, dims: Sequence[tuple[int, int]]) -> np.ndarray:
        """:attr:`addr` for the current arrays of ``datas`` (``dims[t] = (ndx, nu)`` of node t).

        Raises
        ------
        ValueError
            If a derivative array does not have the size of its node's ``(ndx, nu)``.
        """
        if len(self.addr) != len(datas):
            self._sync(datas, dims)
        elif self._stale:
            self._refresh(self._stale, datas)
        for t, name, stage in self._staged:
            np.copyto(stage, np.reshape(getattr(datas[t], name), stage.shape))
        return self.addr

    def _sync(self, datas: list, dims: Sequence[tuple[int, int]]) -> None:
        names = self.names
        shapes = self.node_shapes(dims)
        if len(self.addr) != len(datas) or shapes != self._shapes:
            self._shapes = shapes
            self._seen = [[None] * len(names) for _ in datas]
            self._kept = [[None] * len(names) for _ in datas]
            self.addr = np.zeros((len(datas), len(names)), dtype=np.int64)
        self._stale = [t for t, d in enumerate(datas) if not all(stores(type(d), name) for name in names)]
        self._refresh(range(len(datas)), datas)

    def _refresh(self, nodes, datas: list) -> None:
        """Take the arrays of ``nodes`` that are not the ones taken before."""
        for t in nodes:
            d, seen = datas[t], self._seen[t]
            for i, name in enumerate(self.names):
                a = getattr(d, name)
                if a is seen[i]:
                    continue
                self._staged = [s for s in self._staged if s[:2] != (t, name)]
                seen[i] = a
                shape = self._shapes[t][i]
                if _readable(a, shape):
                    entry = a
                else:
                    entry = np.zeros(shape)
                    np.copyto(entry, np.reshape(a, shape))
                    self._staged.append((t, name, entry))
                self._kept[t][i] = entry
                self.addr[t, i] = address(entry)


def stores(cls: type, name: str) -> bool:
    """True when ``cls.name`` is a :class:`~crocopy.stored.Stored` field (a subclass may replace it, e.g. by a
    property)."""
    for klass in cls.__mro__:
        if name in klass.__dict__:
            return isinstance(klass.__dict__[name], Stored)
    return False


def _readable(a: object, shape: tuple) -> bool:
    """True when a kernel can read ``a`` in place as a C-contiguous float64 array of ``shape``."""
    return isinstance(a, np.ndarray) and a.dtype == np.float64 and a.shape == shape and a.flags.c_contiguous
