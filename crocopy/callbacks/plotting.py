"""Matplotlib plots of solutions and solver convergence (Crocoddyl-compatible names).

* :func:`plotOCSolution` — state and control trajectories, controls against their limits;
* :func:`plotConvergence` — cost, regularisation, gradient, stopping criterion and step length
  per iteration (the lists a ``CallbackLogger`` records);
* :func:`plotFeasibility` — dynamic (gap) and equality feasibility per iteration;
* :func:`plot_convergence_from_logger`, :func:`plot_feasibility` — one-call variants that save a
  PNG: the latter compares gap norms of several runs (Box-FDDP paper, Fig. 4).

Every function returns the :class:`matplotlib.figure.Figure`, saves it when ``path`` is given and
calls ``plt.show()`` only when ``show`` is true, so it works with the non-interactive ``Agg``
backend. Matplotlib is imported on first use, not with crocopy.

Every figure has a title (``figTitle`` / ``title``, or a default naming the plot) and every panel
its own. Quantities that span decades over a solve are drawn on logarithmic axes: cost,
regularisation, gradient, stopping criterion, step length and feasibility. A series with a
negative value (a cost can be negative) is drawn on a symmetric-log axis instead, and exact zeros
(closed gaps, zero regularisation) at :data:`_ZERO_FLOOR`.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

__all__ = [
    "plotOCSolution",
    "plotConvergence",
    "plotFeasibility",
    "plot_convergence_from_logger",
    "plot_feasibility",
    "gap_norms",
]

_ZERO_FLOOR = 1e-14  # exact zeros (closed gaps) are drawn here on logarithmic axes


def _pyplot() -> Any:
    import matplotlib.pyplot as plt

    return plt


def _figure(figIndex: int, size: tuple[float, float], nrows: int, ncols: int, **kwargs: Any) -> tuple[Any, Any]:
    """Figure number ``figIndex`` (reused and cleared if it exists) with a grid of axes."""
    fig = _pyplot().figure(figIndex)
    fig.clear()
    fig.set_size_inches(*size)
    return fig, fig.subplots(nrows, ncols, **kwargs)


def _finish(fig: Any, figTitle: str, default_title: str, path: str | os.PathLike | None, show: bool) -> Any:
    fig.suptitle(figTitle or default_title)
    fig.tight_layout()
    if path is not None:
        fig.savefig(os.fspath(path), dpi=100)
    if show:
        _pyplot().show()
    return fig


def _series(name: str, values: Sequence[float] | np.ndarray) -> np.ndarray:
    arr = np.asarray(values, dtype=float)
    if arr.ndim != 1:
        raise ValueError(f"{name} must be a 1-D sequence (one value per iteration), got shape {arr.shape}")
    return arr


def _stack(name: str, vectors: Sequence[np.ndarray]) -> np.ndarray:
    rows = [np.asarray(v, dtype=float).reshape(-1) for v in vectors]
    if not rows:
        raise ValueError(f"{name} must contain at least one vector")
    if len({r.shape[0] for r in rows}) != 1:
        raise ValueError(f"{name} must hold vectors of one size, got sizes {sorted({r.shape[0] for r in rows})}")
    return np.vstack(rows)


def _bound(name: str, bound: Any, n: int) -> np.ndarray | None:
    if bound is None:
        return None
    b = np.asarray(bound, dtype=float).reshape(-1)
    if b.shape != (n,):
        raise ValueError(f"{name} must have shape ({n},), got {b.shape}")
    return b


def _positive(values: np.ndarray) -> np.ndarray:
    return np.where(values > 0, values, _ZERO_FLOOR)


def _log_panel(ax: Any, title: str, ylabel: str, values: np.ndarray, style: str = ".-", **kwargs: Any) -> None:
    """Draw ``values`` per iteration on a log axis (symmetric-log if any is negative), titled."""
    it = np.arange(values.shape[0])
    if np.any(values < 0):
        ax.plot(it, values, style, **kwargs)
        ax.set_yscale("symlog", linthresh=max(float(np.min(np.abs(values[values != 0]), initial=1.0)), _ZERO_FLOOR))
    else:
        ax.semilogy(it, _positive(values), style, **kwargs)
    ax.set_title(title, fontsize=10)
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)


def plotOCSolution(
    xs: Sequence[np.ndarray] | None = None,
    us: Sequence[np.ndarray] | None = None,
    figIndex: int = 1,
    show: bool = True,
    figTitle: str = "",
    u_lb: np.ndarray | None = None,
    u_ub: np.ndarray | None = None,
    dts: Sequence[float] | None = None,
    path: str | os.PathLike | None = None,
) -> Any:
    """Plot state and control trajectories; controls are drawn against their box limits.

    Parameters
    ----------
    xs : list of ndarray (nx,), optional
        States, one per node (T + 1).
    us : list of ndarray (nu,), optional
        Controls, one per running node (T).
    figIndex, show, figTitle
        As in Crocoddyl: figure number, call ``plt.show()``, figure title.
    u_lb, u_ub : ndarray (nu,), optional
        Control limits, drawn dashed in each control's colour (infinite entries are skipped).
    dts : list of float, optional
        Node durations; the abscissa is time in seconds instead of the node index.
    path : str, optional
        Save the figure there (PNG from the extension).
    """
    if xs is None and us is None:
        raise ValueError("plotOCSolution needs xs or us")
    plt = _pyplot()
    panels = [p for p in (("state", xs), ("control", us)) if p[1] is not None]
    fig, axes = _figure(figIndex, (8, 3.2 * len(panels)), len(panels), 1, squeeze=False)
    time = None if dts is None else np.concatenate([[0.0], np.cumsum(_series("dts", dts))])
    for ax, (kind, traj) in zip(axes[:, 0], panels, strict=True):
        data = _stack("xs" if kind == "state" else "us", traj)
        t = np.arange(data.shape[0]) if time is None else time[: data.shape[0]]
        if t.shape[0] != data.shape[0]:
            raise ValueError(f"dts must have at least {data.shape[0] - 1} entries, got {len(time) - 1}")
        colors = plt.cm.tab20(np.linspace(0, 1, max(data.shape[1], 2)))
        for j in range(data.shape[1]):
            ax.plot(t, data[:, j], color=colors[j], lw=1.2, label=f"{'x' if kind == 'state' else 'u'}{j}")
        if kind == "control":
            for bound in (_bound("u_lb", u_lb, data.shape[1]), _bound("u_ub", u_ub, data.shape[1])):
                if bound is None:
                    continue
                for j in np.flatnonzero(np.isfinite(bound)):
                    ax.axhline(bound[j], color=colors[j], ls="--", lw=0.8)
        ax.set_title(f"{kind} trajectory")
        ax.set_xlabel("node" if time is None else "time [s]")
        ax.set_ylabel(kind)
        ax.grid(True, alpha=0.3)
        if data.shape[1] <= 20:
            ax.legend(fontsize=6, ncol=max(1, data.shape[1] // 10), loc="upper right")
    return _finish(fig, figTitle, "State and control trajectories", path, show)


def plotConvergence(
    costs: Sequence[float],
    muLM: Sequence[float],
    muV: Sequence[float],
    gamma: Sequence[float],
    theta: Sequence[float],
    alpha: Sequence[float],
    figIndex: int = 1,
    show: bool = True,
    figTitle: str = "",
    path: str | os.PathLike | None = None,
) -> Any:
    """Plot the convergence of a solver, one value per iteration (Crocoddyl's arguments).

    Parameters
    ----------
    costs, muLM, muV, gamma, theta, alpha : sequence of float
        Cost, primal and dual regularisation, gradient ``|d[0]|``, stopping criterion and step
        length (e.g. a logger's ``costs, pregs, dregs, grads, stops, steps``).
    """
    values = {
        "cost": _series("costs", costs),
        "muLM": _series("muLM", muLM),
        "muV": _series("muV", muV),
        "gamma": _series("gamma", gamma),
        "theta": _series("theta", theta),
        "alpha": _series("alpha", alpha),
    }
    if len({v.shape[0] for v in values.values()}) != 1:
        lengths = {k: len(v) for k, v in values.items()}
        raise ValueError(f"all series need one value per iteration, got lengths {lengths}")
    fig, axes = _figure(figIndex, (7, 11), 5, 1, sharex=True)
    _log_panel(axes[0], "Cost", "cost", values["cost"], "k.-")
    _log_panel(axes[1], "Regularization", "regularization", values["muLM"], "b.-", label="muLM (primal)")
    _log_panel(axes[1], "Regularization", "regularization", values["muV"], "g.-", label="muV (dual)")
    axes[1].legend(fontsize=7)
    _log_panel(axes[2], "Gradient", "gradient |d0|", np.abs(values["gamma"]), "r.-")
    _log_panel(axes[3], "Stopping criterion", "stopping criteria", values["theta"], "m.-")
    _log_panel(axes[4], "Step length", "step length", values["alpha"], "c.-")
    axes[4].set_xlabel("iteration")
    return _finish(fig, figTitle, "Solver convergence", path, show)


def plotFeasibility(
    ffeass: Sequence[float],
    hfeass: Sequence[float],
    figIndex: int = 1,
    show: bool = True,
    figTitle: str = "",
    path: str | os.PathLike | None = None,
) -> Any:
    """Plot dynamic feasibility (gap norm) and equality feasibility per iteration (log scale)."""
    f, h = _series("ffeass", ffeass), _series("hfeass", hfeass)
    fig, ax = _figure(figIndex, (7, 3.8), 1, 1)
    label = f"feasibility (0 drawn at {_ZERO_FLOOR:g})"
    _log_panel(ax, "Dynamic and equality feasibility", label, f, "b.-", label="dynamic feasibility ||gaps||")
    _log_panel(ax, "Dynamic and equality feasibility", label, h, "r.-", label="equality feasibility")
    ax.set_xlabel("iteration")
    ax.legend(fontsize=8)
    return _finish(fig, figTitle, "Feasibility", path, show)


def gap_norms(logger: Any) -> np.ndarray:
    """Gap norm per iteration of a ``CallbackLogger``: ``ffeass``, else max-norm of its ``fs``."""
    ffeass = getattr(logger, "ffeass", None)
    if ffeass is not None and len(ffeass) > 0:
        return _series("logger.ffeass", ffeass)
    return np.array(
        [max((float(np.max(np.abs(g))) for g in gaps if np.size(g)), default=0.0) for gaps in logger.fs], dtype=float
    )


def plot_convergence_from_logger(
    logger: Any, path: str | os.PathLike | None = None, title: str = "", show: bool = False, figIndex: int = 1
) -> Any:
    """Convergence of a solver from its ``CallbackLogger`` (cost, regularization, gradient,
    stopping criterion, step length, gap norm), saved to ``path`` when given."""
    costs = _series("logger.costs", logger.costs)
    if costs.shape[0] == 0:
        raise ValueError("logger has no iterations recorded (was it passed to solver.setCallbacks?)")
    series = [
        ("Cost", "cost", costs),
        ("Regularization", "regularization (preg)", _series("logger.pregs", logger.pregs)),
        ("Gradient", "gradient |d0|", np.abs(_series("logger.grads", logger.grads))),
        ("Stopping criterion", "stopping criteria", _series("logger.stops", logger.stops)),
        ("Step length", "step length", _series("logger.steps", logger.steps)),
        ("Dynamic feasibility", "||gaps||", gap_norms(logger)),
    ]
    fig, axes = _figure(figIndex, (10, 7.5), 3, 2, sharex=True)
    for ax, (panel_title, label, values) in zip(axes.T.reshape(-1), series, strict=True):
        _log_panel(ax, panel_title, label, values)
    for ax in axes[-1]:
        ax.set_xlabel("iteration")
    return _finish(fig, title, "Solver convergence", path, show)


def plot_feasibility(
    runs: Mapping[str, Any] | Sequence[float],
    path: str | os.PathLike | None = None,
    title: str = "",
    show: bool = False,
    figIndex: int = 1,
) -> Any:
    """Gap norm per iteration of one or several runs on a log scale (Box-FDDP paper, Fig. 4).

    Parameters
    ----------
    runs : mapping label -> gap norms (sequence) or ``CallbackLogger``; or one sequence
        Closed gaps (exact zeros) are drawn at 1e-14.
    """
    items = runs.items() if isinstance(runs, Mapping) else [("", runs)]
    fig, ax = _figure(figIndex, (7, 4), 1, 1)
    for label, run in items:
        values = gap_norms(run) if hasattr(run, "costs") else _series(f"runs[{label!r}]", run)
        _log_panel(ax, "Gap norm per iteration", f"||gaps|| (0 drawn at {_ZERO_FLOOR:g})", values, label=label or None)
    ax.set_xlabel("iteration")
    if isinstance(runs, Mapping):
        ax.legend(fontsize=8)
    return _finish(fig, title, "Dynamic feasibility", path, show)
