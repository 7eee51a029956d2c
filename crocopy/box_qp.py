"""Projected-Newton solver for box-constrained quadratic programs (Crocoddyl's ``BoxQP``).

Solves ::

    x* = argmin_x  1/2 x^T H x + q^T x   subject to   lb <= x <= ub

with ``H`` of shape ``(nx, nx)`` (symmetric; positive definite on the free subspace) and
``q, lb, ub, x`` of shape ``(nx,)``.  This is the method of Tassa, Mansard and Todorov,
*Control-Limited Differential Dynamic Programming* (ICRA 2014), Appendix I, a special case of
Bertsekas' projected Newton method with the exact Hessian:

1. start from the projection of the warm start, ``x = clamp(xinit, lb, ub)``;
2. gradient ``g = q + H x``; clamped set ``c = {j : x_j = lb_j and g_j > 0  or  x_j = ub_j and g_j < 0}``,
   free set ``f`` its complement (stop if every variable is clamped);
3. Cholesky factorization of ``H_ff + reg I``, redone only when the free set changes (each one is
   counted in :attr:`BoxQP.nfactorizations`);
4. Newton step on the free set, ``dx_f = -(H_ff + reg I)^{-1} g_f``, ``dx_c = 0``;
5. projected backtracking line search over :attr:`BoxQP.alphas` (``1, 1/2, ..., 1/512``): accept the
   first ``x_a = clamp(x + a dx)`` with ``(f(x) - f(x_a)) >= th_acceptStep * g^T (x - x_a)`` (Armijo);
   if no step length is accepted the solver stops;
6. at the new point, update the sets (step 2-3) and stop when ``||g_f|| <= th_grad`` (2-norm), else go to 4.

At least one Newton step is taken (as Crocoddyl does), so a converged warm start costs one step.
The returned :class:`BoxQPSolution` holds ``x``, the free/clamped index lists of the final point and
``Hff_inv = (H_ff + reg I)^{-1}`` for that final free set (refactorized if it changed on the last
step); the DDP solvers build their feedback gains from it.  If the warm start has the optimal
clamped set, one Newton step reaches the optimum (the paper's lemma).

Choices the paper leaves open: the step-length list (``2^-n, n = 0..9``), the 2-norm in the
gradient test, and the regularization on the free block are Crocoddyl's documented defaults.
:attr:`BoxQP.nfactorizations` and :attr:`BoxQP.iter` are crocopy extensions used by the
experiments (the paper reports factorizations per DDP iteration).
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import lapack

from .validation import as_matrix, as_vector, check_bounds

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
        Tolerance on the 2-norm of the free gradient (default 1e-9).
    reg : float
        Regularization added to the diagonal of the free Hessian block (default 1e-9).
    """

    def __init__(
        self, nx: int, maxiter: int = 100, th_acceptStep: float = 0.1, th_grad: float = 1e-9, reg: float = 1e-9
    ) -> None:
        if int(nx) < 0:
            raise ValueError(f"nx must be non-negative, got {nx}")
        self.nx = int(nx)
        self.maxiter = int(maxiter)
        self.th_acceptStep = float(th_acceptStep)
        self.th_grad = float(th_grad)
        self.reg = float(reg)
        self.alphas = [0.5**n for n in range(10)]
        self.solution = BoxQPSolution(np.zeros((0, 0)), np.zeros(self.nx), [], list(range(self.nx)))
        self.nfactorizations = 0
        self.iter = 0
        self._eye = {}

    @property
    def maxIter(self) -> int:
        """Alias of :attr:`maxiter` (Crocoddyl exposes both)."""
        return self.maxiter

    @maxIter.setter
    def maxIter(self, value: int) -> None:
        self.maxiter = int(value)

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

    def _free_set(self, H, x, g, lb, ub, mask, f_idx, Hinv):
        """Free mask (``None`` = all free), free indices and ``Hff_inv`` at ``x``; refactorizes on change."""
        at_lb = x <= lb
        at_ub = x >= ub
        new = ~((at_lb & (g > 0.0)) | (at_ub & (g < 0.0))) if (at_lb.any() or at_ub.any()) else None
        if new is not None and new.all():
            new = None
        if Hinv is not None and _same_mask(new, mask):
            return mask, f_idx, Hinv
        if new is None:
            return None, None, self._factorize(H)
        f_idx = np.flatnonzero(new)
        return new, f_idx, (self._factorize(H[np.ix_(f_idx, f_idx)]) if f_idx.size else np.zeros((0, 0)))

    def _solve(self, H: np.ndarray, q: np.ndarray, lb: np.ndarray, ub: np.ndarray, xinit: np.ndarray) -> BoxQPSolution:
        """Unchecked solve (arguments already validated); the hot path of the box solvers."""
        n = self.nx
        x = np.minimum(np.maximum(xinit, lb), ub)
        g = q + H @ x
        free_mask, f_idx, Hinv = self._free_set(H, x, g, lb, ub, None, None, None)
        self.iter = 0
        for _ in range(self.maxiter):
            if f_idx is not None and f_idx.size == 0:
                break
            if f_idx is None:
                dx = -(Hinv @ g)
            else:
                dx = np.zeros(n)
                dx[f_idx] = -(Hinv @ g[f_idx])
            fold = 0.5 * (x @ (g + q))
            accepted = False
            for a in self.alphas:
                xa = x + a * dx
                np.maximum(xa, lb, out=xa)
                np.minimum(xa, ub, out=xa)
                ga = q + H @ xa
                fnew = 0.5 * (xa @ (ga + q))
                if fold - fnew >= self.th_acceptStep * (g @ (x - xa)):
                    accepted = True
                    break
            if not accepted:
                break
            x, g = xa, ga
            self.iter += 1
            free_mask, f_idx, Hinv = self._free_set(H, x, g, lb, ub, free_mask, f_idx, Hinv)
            gf = g if f_idx is None else g[f_idx]
            if gf @ gf <= self.th_grad * self.th_grad:
                break
        sol = self.solution
        sol.x = x
        sol.Hff_inv = Hinv
        if f_idx is None:
            sol.free_idx = list(range(n))
            sol.clamped_idx = []
        else:
            sol.free_idx = f_idx.tolist()
            sol.clamped_idx = np.flatnonzero(~free_mask).tolist()
        sol._free_mask = free_mask
        return sol


def _same_mask(a: np.ndarray | None, b: np.ndarray | None) -> bool:
    """Equality of two free masks, ``None`` meaning "all free"."""
    if a is None or b is None:
        return (a is None or a.all()) and (b is None or b.all())
    return bool(np.array_equal(a, b))
