"""Projected-Newton solver for box-constrained quadratic programs (Crocoddyl's ``BoxQP``).

Solves ::

    x* = argmin_x  f(x) = 1/2 x^T (H + reg I) x + q^T x   subject to   lb <= x <= ub

with ``H`` of shape ``(nx, nx)`` (symmetric; positive definite on the free subspace) and
``q, lb, ub, x`` of shape ``(nx,)``.  This is the method of Tassa, Mansard and Todorov,
*Control-Limited Differential Dynamic Programming* (ICRA 2014), Appendix I, a special case of
Bertsekas' projected Newton method with the exact Hessian.  From ``x = clamp(xinit, lb, ub)``, each
iteration:

1. gradient ``g = q + (H + reg I) x``; clamped set ``c = {j : x_j <= lb_j and g_j > 0  or
   x_j >= ub_j and g_j < 0}``, free set ``f`` its complement (stop if every variable is clamped);
2. Cholesky factorization of ``H_ff + reg I``, redone only when the free set changes (each one is
   counted in :attr:`BoxQP.nfactorizations`);
3. Newton step on the free set, ``dx_f = -(H_ff + reg I)^{-1} g_f``, ``dx_c = 0``;
4. projected backtracking line search over :attr:`BoxQP.alphas` (``1, 1/2, ..., 1/512``): accept
   the first ``x_a = clamp(x + a dx)`` with ``f(x) - f(x_a) >= th_acceptStep g^T (x - x_a)`` (the
   paper's Armijo rule, eq. 20); if none is accepted the solver stops;
5. ``x <- x_a``; stop when the free gradient of step 3 was small, ``||g_f||_inf <= th_grad``.

Choices the paper leaves open follow Crocoddyl 3.2's ``BoxQP`` (measured as a black box on random
QPs): step lengths ``2^-n, n = 0..9``; the infinity norm in the gradient test; the test made after
the step computed from that gradient, so a converged warm start still takes one (vanishing) Newton
step and the reported sets, ``Hff_inv = (H_ff + reg I)^{-1}``, are those the last step was computed
on.  If the warm start has the optimal clamped set, the first Newton step reaches the optimum (the
paper's lemma).

Two departures of Crocoddyl 3.2 from the paper are reproduced only with ``compat_crocoddyl = True``
(used by ``crocopy bench --box-parity``): (a) its line search accepts when
``f(x) - f(x_a) >= -th_acceptStep g^T (x - x_a)``, a flipped sign that admits a cost *increase*
(on some random QPs it then cycles and returns a point far from the optimum after ``maxiter``
iterations, where the paper's rule converges in three); (b) its clamped set and line-search objective
use ``H`` without ``reg`` while the Newton step and the gradient test use ``H + reg I``, so for
``reg > 0`` its answer solves neither QP exactly.  Both coincide with the paper when the line search
takes full unprojected steps and ``reg = 0`` (as in the DDP solvers).  :attr:`BoxQP.nfactorizations`,
:attr:`BoxQP.iter` (Newton steps of the last solve) and :attr:`BoxQP.compat_crocoddyl` are crocopy
extensions.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import lapack

from ..validation import as_count, as_matrix, as_number, as_vector, check_bounds

__all__ = ["BoxQP", "BoxQPSolution", "BoxQPError"]


class BoxQPError(np.linalg.LinAlgError):
    """The free block of the Hessian is not positive definite."""


class BoxQPSolution:
    """Solution of a box QP (Crocoddyl's ``BoxQPSolution``).

    Parameters
    ----------
    Hff_inv : numpy.ndarray
        Inverse of the (regularized) free block of the Hessian, shape ``(nf, nf)``.
    x : numpy.ndarray
        Solution, shape ``(nx,)``.
    free_idx, clamped_idx : list of int
        Indices of the free and clamped variables at ``x``.
    """

    def __init__(
        self,
        Hff_inv: np.ndarray | None = None,
        x: np.ndarray | None = None,
        free_idx: list[int] | None = None,
        clamped_idx: list[int] | None = None,
    ) -> None:
        self.Hff_inv = np.zeros((0, 0)) if Hff_inv is None else np.asarray(Hff_inv, dtype=float)
        self.x = np.zeros(0) if x is None else np.asarray(x, dtype=float)
        self.free_idx = [] if free_idx is None else [int(i) for i in free_idx]
        self.clamped_idx = [] if clamped_idx is None else [int(i) for i in clamped_idx]

    def copy(self) -> "BoxQPSolution":
        """Deep copy."""
        return BoxQPSolution(self.Hff_inv.copy(), self.x.copy(), list(self.free_idx), list(self.clamped_idx))

    def __repr__(self) -> str:
        return f"BoxQPSolution(x={self.x}, free_idx={self.free_idx}, clamped_idx={self.clamped_idx})"


class BoxQP:
    """Projected-Newton QP for bound constraints (Crocoddyl's ``BoxQP``).

    Parameters
    ----------
    nx : int
        Dimension of the decision vector.
    maxiter : int
        Maximum number of Newton iterations (default 100).
    th_acceptStep : float
        Armijo acceptance ratio of the projected line search (default 0.1).
    th_grad : float
        Tolerance on the infinity norm of the free gradient (default 1e-9).
    reg : float
        Regularization added to the diagonal of the free Hessian block (default 1e-9).
    """

    def __init__(
        self, nx: int, maxiter: int = 100, th_acceptStep: float = 0.1, th_grad: float = 1e-9, reg: float = 1e-9
    ) -> None:
        self.nx = as_count(nx, "nx")
        self.maxiter = as_count(maxiter, "maxiter")
        self.th_acceptStep = as_number(th_acceptStep, "th_acceptStep", 0.0)
        self.th_grad = as_number(th_grad, "th_grad", 0.0)
        self.reg = as_number(reg, "reg", 0.0)
        self.alphas = [0.5**n for n in range(10)]
        self.solution = BoxQPSolution(np.zeros((0, 0)), np.zeros(self.nx), [], list(range(self.nx)))
        self.nfactorizations = 0
        self.iter = 0
        self.compat_crocoddyl = False
        self._eye = {}

    @property
    def maxIter(self) -> int:
        """Alias of :attr:`maxiter` (Crocoddyl exposes both)."""
        return self.maxiter

    @maxIter.setter
    def maxIter(self, value: int) -> None:
        self.maxiter = as_count(value, "maxIter")

    def solve(self, H: np.ndarray, q: np.ndarray, lb: np.ndarray, ub: np.ndarray, xinit: np.ndarray) -> BoxQPSolution:
        """Solve the box QP from the warm start ``xinit``.

        Parameters
        ----------
        H : numpy.ndarray
            Hessian, shape ``(nx, nx)``.
        q : numpy.ndarray
            Gradient, shape ``(nx,)``.
        lb, ub : numpy.ndarray
            Lower and upper bounds, shape ``(nx,)`` (``-inf``/``inf`` allowed, NaN not, ``lb <= ub``).
        xinit : numpy.ndarray
            Warm start, shape ``(nx,)``; projected onto the box first.

        Returns
        -------
        BoxQPSolution
            Also stored in :attr:`solution`.

        Raises
        ------
        ValueError
            Bad shapes, NaN entries or ``lb > ub``.
        BoxQPError
            The free Hessian block is not positive definite.
        """
        n = self.nx
        H = as_matrix(H, (n, n), "H")
        q = as_vector(q, n, "q")
        lb = as_vector(lb, n, "lb", allow_nonfinite=True)
        ub = as_vector(ub, n, "ub", allow_nonfinite=True)
        check_bounds(lb, ub, "lb", "ub")
        xinit = as_vector(xinit, n, "xinit")
        return self._solve(H, q, lb, ub, xinit)

    def _objective(self, H: np.ndarray, q: np.ndarray, x: np.ndarray, compat: bool) -> float:
        """``1/2 x^T H x + q^T x``, plus ``reg/2 |x|^2`` unless in Crocoddyl-compatible mode."""
        f = 0.5 * (x @ (H @ x)) + q @ x
        return f if compat or not self.reg else f + 0.5 * self.reg * (x @ x)

    def _factorize(self, Hff: np.ndarray) -> np.ndarray:
        """Inverse of ``Hff + reg I`` through its Cholesky factor; raises :class:`BoxQPError`."""
        nf = Hff.shape[0]
        eye = self._eye.get(nf)
        if eye is None:
            eye = self._eye[nf] = np.eye(nf)
        if self.reg != 0.0:
            Hff = Hff + self.reg * eye
        self.nfactorizations += 1
        c, info = lapack.dpotrf(Hff, lower=0, clean=0)
        if info != 0:
            raise BoxQPError("BoxQP: the free block of the Hessian is not positive definite")
        inv, info = lapack.dpotrs(c, eye)
        if info != 0 or not np.all(np.isfinite(inv)):
            raise BoxQPError("BoxQP: the free block of the Hessian is singular")
        return inv

    def _solve(self, H: np.ndarray, q: np.ndarray, lb: np.ndarray, ub: np.ndarray, xinit: np.ndarray) -> BoxQPSolution:
        """Unchecked solve (arguments already validated); the hot path of the box solvers."""
        n = self.nx
        reg = self.reg
        compat = self.compat_crocoddyl
        th_acc = -self.th_acceptStep if compat else self.th_acceptStep
        x = np.minimum(np.maximum(xinit, lb), ub)
        free_mask = f_idx = Hinv = None
        self.iter = 0
        for _ in range(self.maxiter):
            g = q + H @ x
            gr = g + reg * x if reg else g
            gs = g if compat else gr
            new = ~(((x <= lb) & (gs > 0.0)) | ((x >= ub) & (gs < 0.0)))
            if not new.any():
                free_mask, f_idx, Hinv = new, np.zeros(0, dtype=int), np.zeros((0, 0))
                break
            if Hinv is None or not np.array_equal(new, free_mask):
                free_mask, f_idx = new, np.flatnonzero(new)
                Hinv = self._factorize(H if f_idx.size == n else H[np.ix_(f_idx, f_idx)])
            grf = gr[f_idx]
            dx = np.zeros(n)
            dx[f_idx] = -(Hinv @ grf)
            fold = self._objective(H, q, x, compat)
            for a in self.alphas:
                xa = x + a * dx
                np.maximum(xa, lb, out=xa)
                np.minimum(xa, ub, out=xa)
                if fold - self._objective(H, q, xa, compat) >= th_acc * (gr @ (x - xa)):
                    break
            else:
                break
            x = xa
            self.iter += 1
            if np.abs(grf).max() <= self.th_grad:
                break
        if free_mask is None:  # maxiter = 0
            g = q + H @ x + self.reg * x
            free_mask = ~(((x <= lb) & (g > 0.0)) | ((x >= ub) & (g < 0.0)))
            f_idx = np.flatnonzero(free_mask)
            Hinv = self._factorize(H[np.ix_(f_idx, f_idx)]) if f_idx.size else np.zeros((0, 0))
        sol = self.solution
        sol.x = x
        sol.Hff_inv = Hinv
        sol.free_idx = f_idx.tolist()
        sol.clamped_idx = np.flatnonzero(~free_mask).tolist()
        sol._free_mask = free_mask
        return sol
