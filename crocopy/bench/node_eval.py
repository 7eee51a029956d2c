"""Model-level comparison with Crocoddyl: calc/calcDiff time and the numbers of every node.

``crocopy bench --models [--problems ...]`` builds each problem with both libraries (same builder,
``lib=crocopy`` / ``lib=crocoddyl``), evaluates ``problem.calc`` + ``problem.calcDiff`` on the
builder's guess, and prints

* the median time of ``calc + calcDiff`` of each library (interleaved samples, one thread; Crocoddyl
  with ``problem.nthreads = 1``) and their ratio against the bar (≤ 2×);
* per model kind (the differential model's class, or the action model's for impulses), the largest
  difference over its nodes of the cost, ``xnext`` (as ``xnext_crocoddyl ⊖ xnext_crocopy``) and the
  derivatives ``Fx``, ``Fu``, ``Lx``, ``Lu``, ``Lxx``, ``Lxu``, ``Luu``, each scaled by
  ``max(1, |value|)`` of the quantity (bar: 1e-8).

Needs the ``bench`` extra (Crocoddyl 3.2.1 on Pinocchio 4.0.0).
"""

from __future__ import annotations

import statistics
from types import ModuleType

import numpy as np

from .side_by_side import build_problem, require_crocoddyl
from .timing import limit_threads, loops_for, sample_ms

MODEL_PROBLEMS = ("jump", "taichi")
FIELDS = ("Fx", "Fu", "Lx", "Lu", "Lxx", "Lxu", "Luu")
TIME_BAR = 2.0
EQUAL_BAR = 1e-8


def model_kind(model: object) -> str:
    """The differential model's class name (integrated models) or the model's own."""
    inner = getattr(model, "differential", None)
    return type(inner if inner is not None else model).__name__


def _scaled(a: np.ndarray, b: np.ndarray) -> float:
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.size == 0:
        return 0.0
    return float(np.max(np.abs(a - b)) / max(1.0, float(np.max(np.abs(a)))))


def node_differences(problems: tuple, xs: list, us: list) -> dict[str, dict[str, float]]:
    """Largest scaled difference per model kind and quantity between two built problems."""
    ours, theirs = problems
    for p in (ours, theirs):
        p.calc(xs, us)
        p.calcDiff(xs, us)
    out: dict[str, dict[str, float]] = {}
    nodes = [
        *zip(ours.runningModels, ours.runningDatas, theirs.runningDatas),
        (ours.terminalModel, ours.terminalData, theirs.terminalData),
    ]
    for t, (model, d_ours, d_theirs) in enumerate(nodes):
        kind = model_kind(model) + (" (terminal)" if t == len(nodes) - 1 else "")
        diffs = out.setdefault(kind, {"nodes": 0, "cost": 0.0, "xnext": 0.0, **dict.fromkeys(FIELDS, 0.0)})
        diffs["nodes"] += 1
        diffs["cost"] = max(diffs["cost"], abs(d_ours.cost - d_theirs.cost) / max(1.0, abs(d_theirs.cost)))
        gap = model.state.diff(d_ours.xnext, np.asarray(d_theirs.xnext))
        diffs["xnext"] = max(diffs["xnext"], float(np.max(np.abs(gap))) / max(1.0, float(np.max(np.abs(d_ours.xnext)))))
        for name in FIELDS:
            diffs[name] = max(diffs[name], _scaled(getattr(d_theirs, name), getattr(d_ours, name)))
    return out


def time_calc_calcdiff(problems: tuple, xs: list, us: list, repeats: int) -> tuple[float, float]:
    """Median seconds of ``calc + calcDiff`` of each problem (the side-by-side bench's sampling:
    samples of at least 20 ms, the order of the two problems alternating)."""

    def make(p):
        return lambda: (p.calc(xs, us), p.calcDiff(xs, us))

    calls = [make(p) for p in problems]
    loops = [loops_for(fn) for fn in calls]
    samples: list[list[float]] = [[] for _ in problems]
    for r in range(repeats):
        for k in (0, 1) if r % 2 == 0 else (1, 0):
            samples[k].append(1e-3 * sample_ms(calls[k], loops[k]))
    return statistics.median(samples[0]), statistics.median(samples[1])


def compare_problem(name: str, crocopy: ModuleType, crocoddyl: ModuleType, repeats: int) -> tuple[str, bool]:
    """Markdown section of one problem and whether it meets both bars."""
    ours, xs, us = build_problem(name, crocopy)
    theirs, _, _ = build_problem(name, crocoddyl)
    theirs.nthreads = 1
    t_ours, t_theirs = time_calc_calcdiff((ours, theirs), xs, us, repeats)
    diffs = node_differences((ours, theirs), xs, us)
    ratio = t_ours / t_theirs
    worst = max(v for d in diffs.values() for k, v in d.items() if k != "nodes")
    met = ratio <= TIME_BAR and worst <= EQUAL_BAR
    lines = [
        f"### {name} (T = {ours.T})",
        "",
        f"calc + calcDiff: crocopy {1e3 * t_ours:.2f} ms, Crocoddyl {1e3 * t_theirs:.2f} ms, ratio {ratio:.2f}× "
        f"(bar ≤ {TIME_BAR:g}×: {'met' if ratio <= TIME_BAR else 'not met'}); largest scaled difference "
        f"{worst:.1e} (bar ≤ {EQUAL_BAR:g}: {'met' if worst <= EQUAL_BAR else 'not met'}).",
        "",
        "| model kind | nodes | cost | xnext | " + " | ".join(FIELDS) + " |",
        "|---|---" + "|---" * (2 + len(FIELDS)) + "|",
    ]
    for kind, d in diffs.items():
        values = " | ".join(f"{d[k]:.1e}" for k in ("cost", "xnext", *FIELDS))
        lines.append(f"| {kind} | {d['nodes']} | {values} |")
    return "\n".join(lines) + "\n", met


def run_model_bench(problems: tuple[str, ...] = MODEL_PROBLEMS, repeats: int = 15) -> str:
    """The report of :func:`compare_problem` over ``problems`` (raises ``BenchDependencyError`` without Crocoddyl)."""
    import crocopy

    crocoddyl = require_crocoddyl()
    limit_threads()
    sections = [
        "## Models: crocopy vs Crocoddyl on the same nodes",
        "",
        "Scaled differences: max |crocopy - Crocoddyl| / max(1, |Crocoddyl|) over the nodes of each kind.",
        "",
    ]
    for name in problems:
        text, _ = compare_problem(name, crocopy, crocoddyl, repeats)
        sections.append(text)
    return "\n".join(sections)
