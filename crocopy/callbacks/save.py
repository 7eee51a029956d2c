"""Crocoddyl's ``saveOCSolution``, ``saveConvergence`` and ``saveLogfile``: pickle files of results.

Each writes one ``pickle`` of a dict (read back with ``pickle.load``); trajectories are stored as
plain lists of numpy arrays, so a file loads without crocopy installed.

* ``saveOCSolution(filename, xs, us, ks=None, Ks=None)``: keys ``xs, us, ks, Ks`` (states,
  controls, feed-forward terms and feedback gains; ``None`` when not given).
* ``saveConvergence(filename, costs, muLM, muV, gamma, theta, alpha)``: one key per argument.
* ``saveLogfile(filename, log)``: a :class:`~crocopy.callbacks.base.CallbackLogger`'s record under
  Crocoddyl's keys ``xs, us, fs, steps, iters, costs, primal-reg, dual-reg, stops, grads``.
"""

from __future__ import annotations

import os
import pickle
from collections.abc import Sequence
from typing import Any

import numpy as np


def _arrays(values: Sequence | None) -> list[np.ndarray] | None:
    return None if values is None else [np.array(v, dtype=float) for v in values]


def _dump(filename: str | os.PathLike, content: dict) -> None:
    with open(filename, "wb") as f:
        pickle.dump(content, f)


def saveOCSolution(
    filename: str | os.PathLike,
    xs: Sequence[np.ndarray],
    us: Sequence[np.ndarray],
    ks: Sequence[np.ndarray] | None = None,
    Ks: Sequence[np.ndarray] | None = None,
) -> None:
    """Pickle ``{"xs", "us", "ks", "Ks"}`` to ``filename``."""
    _dump(filename, {"xs": _arrays(xs), "us": _arrays(us), "ks": _arrays(ks), "Ks": _arrays(Ks)})


def saveConvergence(
    filename: str | os.PathLike,
    costs: Sequence[float],
    muLM: Sequence[float],
    muV: Sequence[float],
    gamma: Sequence[float],
    theta: Sequence[float],
    alpha: Sequence[float],
) -> None:
    """Pickle the convergence figures ``{"costs", "muLM", "muV", "gamma", "theta", "alpha"}``."""
    _dump(
        filename,
        {"costs": costs, "muLM": muLM, "muV": muV, "gamma": gamma, "theta": theta, "alpha": alpha},
    )


def saveLogfile(filename: str | os.PathLike, log: Any) -> None:
    """Pickle a ``CallbackLogger``'s record (see the module docstring for the keys)."""
    _dump(
        filename,
        {
            "xs": _arrays(log.xs),
            "us": _arrays(log.us),
            "fs": [_arrays(fs) for fs in log.fs],
            "steps": list(log.steps),
            "iters": list(log.iters),
            "costs": list(log.costs),
            "primal-reg": list(log.pregs),
            "dual-reg": list(log.dregs),
            "stops": list(log.stops),
            "grads": list(log.grads),
        },
    )
