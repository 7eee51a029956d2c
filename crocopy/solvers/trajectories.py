"""Where a solver's trajectories are: their addresses, and the compiled copy that accepts a trial.

A DDP-family solver's trajectories (``xs``, ``us``, ``xs_try``, ``us_try``, the rollout's ``x̂ ⊖ x`` and the
gains ``k``, ``K`` and gaps ``fs``, views of the :mod:`.horizon` buffer) are arrays made once per problem shape
(:class:`~crocopy.solvers.std_vector.Trajectory`: assigning copies into them), so their addresses are read once
per allocation (:class:`TrajectoryAddresses`) and stay valid: the compiled rollout and derivatives of
:mod:`.compiled_nodes` read them by address.  Accepting a trial copies ``xs_try``/``us_try`` into ``xs``/``us``
(:func:`accept_trial`, one compiled call) instead of swapping the lists, so ``solver.xs`` stays the same arrays.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .. import kernels
from ..kernels import checked_address, compiled, vector_at


def addresses(arrays: Sequence[np.ndarray | None]) -> np.ndarray:
    """The addresses of ``arrays`` (C-contiguous float64; ``None`` entries: 0, never read), ``(len(arrays),)``."""
    return np.array([0 if a is None else checked_address(a) for a in arrays], dtype=np.int64)


class TrajectoryAddresses:
    """The addresses of a DDP-family solver's trajectories, read at construction (after an allocation)."""

    names = ("xs", "us", "xs_try", "us_try", "_dx_try", "k", "K", "fs")
    """The solver's attributes whose arrays' addresses it holds (a new list under one of these names is read again)."""

    def __init__(self, solver) -> None:
        self.xs, self.us = addresses(solver.xs), addresses(solver.us)
        self.xs_try, self.us_try = addresses(solver.xs_try), addresses(solver.us_try)
        self.dx_try = addresses(solver._dx_try)
        self.k, self.K, self.fs = addresses(solver.k), addresses(solver.K), addresses(solver.fs)
        self.nx = np.array([x.shape[0] for x in solver.xs], dtype=np.int64)
        self.nu = np.array([u.shape[0] for u in solver.us], dtype=np.int64)


def _copy_vectors(destinations, sources, sizes):
    for t in range(sizes.shape[0]):
        n = sizes[t]
        if n:
            vector_at(destinations[t], n)[:] = vector_at(sources[t], n)


copy_vectors = compiled(_copy_vectors)
"""``copy_vectors(destinations, sources, sizes)``: copy ``sizes[t]`` floats from ``sources[t]`` to
``destinations[t]`` (addresses), for every t."""


def accept_trial(solver) -> None:
    """``xs ← xs_try`` and ``us ← us_try`` (copies into the solver's arrays)."""
    if kernels.active:
        a = solver._addresses()
        copy_vectors(a.xs, a.xs_try, a.nx)
        copy_vectors(a.us, a.us_try, a.nu)
        return
    for x, x_try in zip(solver.xs, solver.xs_try):
        np.copyto(x, x_try)
    for u, u_try in zip(solver.us, solver.us_try):
        np.copyto(u, u_try)
