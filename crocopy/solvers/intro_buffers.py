"""What SolverIntro's compiled pass (:mod:`.intro_riccati_kernel`) reads and writes besides the DDP family's
buffers (:mod:`.horizon`): the addresses of the running datas' equality rows and one buffer for the per-node
read-outs (``YZ, Hy, ks, Ks, kz, Kz, Qz, Qzz, Qxz, Quz``).

Each node with controls and equality rows has a slot per read-out, large enough for its largest shape
(``p = max(nu, nh)``): ``YZ (nu, nu)``, ``Hy (nh, p)``, ``ks (p,)``, ``Ks (p, ndx)``, ``kz (nu,)``,
``Kz (nu, ndx)``, ``Qz (p,)``, ``Qzz (p, p)``, ``Qxz (ndx, p)``, ``Quz (nu, p)``.  The solver's lists hold
views of these slots shaped as the last pass left them (:meth:`IntroBuffers.shapes`: the nullspace shapes
follow the node's rank ``r``, the Schur ones ``nh``), rebuilt only when a rank or the method changed.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .horizon import NodeDerivatives, address
from .intro_riccati_kernel import NR, SCHUR

READOUTS = ("YZ", "Hy", "ks", "Ks", "kz", "Kz", "Qz", "Qzz", "Qxz", "Quz")
"""The solver's read-out lists, in the columns of :attr:`IntroBuffers.oaddr`."""


class EqualityRows(NodeDerivatives):
    """The addresses of the datas' own ``h, Hx, Hu`` (``dims[t] = (rows, ndx, nu)``, ``rows`` the data's
    ``max(nh, nh_T)``)."""

    names = ("h", "Hx", "Hu")

    @staticmethod
    def node_shapes(dims: Sequence[tuple[int, ...]]) -> list[list[tuple]]:
        return [[(r,), (r, n), (r, m)] for r, n, m in dims]


class IntroBuffers:
    """The compiled pass's tables for the running models ``models``.

    Attributes
    ----------
    nh : ndarray
        Rows enforced at each node (its ``nh``; 0 at a node without controls).
    rows : EqualityRows
        Where each data's ``h, Hx, Hu`` are, the terminal one's last (:meth:`row_addresses`).
    oaddr : ndarray
        ``(T, NR)``: where each read-out slot starts (0 at a node without enforced rows).
    ranks : ndarray
        ``Hu_rank`` of each node as the last pass left it.
    """

    def __init__(self, models: Sequence, terminal: object) -> None:
        self.dims = [(m.state.ndx, m.nu, m.nh if m.nu else 0) for m in models]
        self.nh = np.array([p for _, _, p in self.dims], dtype=np.int64)
        self._row_dims = [(max(m.nh, m.nh_T), m.state.ndx, m.nu) for m in (*models, terminal)]
        self.h_rows = np.array([r for r, _, _ in self._row_dims], dtype=np.int64)
        """The length of each data's ``h`` (the T running nodes, then the terminal one)."""
        self.rows = EqualityRows()
        sizes = []
        for n, m, p in self.dims:
            q = max(m, p)
            sizes.append([m * m, p * q, q, q * n, m, m * n, q, q * q, n * q, m * q] if p else [0] * NR)
        sizes = np.array(sizes, dtype=np.int64).reshape(len(self.dims), NR)
        ends = np.cumsum(sizes.ravel()).reshape(sizes.shape)
        self.buf = np.zeros(max(int(ends[-1, -1]) if ends.size else 0, 1))
        self.off = ends - sizes
        self.oaddr = np.where(sizes > 0, address(self.buf) + 8 * self.off, 0).astype(np.int64)
        self.ranks = np.zeros(len(self.dims), dtype=np.int64)
        self.constrained = [t for t, (_, _, p) in enumerate(self.dims) if p]

    def row_addresses(self, problem: object) -> np.ndarray:
        """``(T + 1, 3)``: where ``h, Hx, Hu`` of the problem's running and terminal datas are (ValueError if one does
        not have its node's shape)."""
        return self.rows.update([*problem.runningDatas, problem.terminalData], self._row_dims)

    def shapes(self, t: int, method: int) -> list[tuple]:
        """The shapes of node ``t``'s read-outs after a pass by ``method`` (rank :attr:`ranks` ``[t]``)."""
        n, m, p = self.dims[t]
        if method == SCHUR:
            return [(m, m), (p, p), (p,), (p, n), (m,), (m, n), (p,), (p, p), (n, p), (m, p)]
        r = int(self.ranks[t])
        z = m - r
        return [(m, m), (p, r), (r,), (r, n), (m,), (m, n), (z,), (z, z), (n, z), (m, z)]

    def views(self, t: int, method: int) -> list[np.ndarray]:
        """Node ``t``'s read-outs as views of :attr:`buf` (:meth:`shapes`)."""
        out = []
        for j, shape in enumerate(self.shapes(t, method)):
            start = int(self.off[t, j])
            out.append(self.buf[start : start + int(np.prod(shape))].reshape(shape))
        return out
