"""Markdown report of :mod:`crocopy.bench.side_by_side` (what ``crocopy bench --vs crocoddyl --out`` writes).

The report states the machine (CPU model from ``/proc/cpuinfo``, cores, load average), the versions
(Python, NumPy, Pinocchio, Crocoddyl, crocopy, numba) and the date, then four tables: solves
(iterations, final cost, agreement, wall ms per iteration), phases (crocopy, Crocoddyl and their
ratio per phase), peak memory, and the per-iteration bars of issue 7 (≤ 1.5× Crocoddyl on the ANYmal
jump and walk and the Talos taichi and manipulation, ≤ 2× elsewhere), judged on the interleaved
phase total.
"""

from __future__ import annotations

import datetime
import importlib
import os
import platform
from collections.abc import Sequence

from .side_by_side import PHASES, ProblemResult

BARS = {"jump": 1.5, "walk": 1.5, "taichi": 1.5, "man": 1.5}
"""Per-iteration time bar (crocopy / Crocoddyl) per problem; :data:`DEFAULT_BAR` elsewhere."""

DEFAULT_BAR = 2.0

AGREEMENT_RTOL = 1e-6


def bar_of(name: str) -> float:
    """The per-iteration ratio bar of problem ``name``."""
    return BARS.get(name, DEFAULT_BAR)


def cpu_model() -> str:
    """CPU model name from ``/proc/cpuinfo`` (``platform.processor()`` where that file is missing)."""
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def versions() -> dict[str, str]:
    """Versions of Python and of the packages in the benchmark (``"not installed"`` when absent)."""
    out = {"Python": platform.python_version()}
    for label, module in (
        ("NumPy", "numpy"),
        ("Pinocchio", "pinocchio"),
        ("Crocoddyl", "crocoddyl"),
        ("crocopy", "crocopy"),
        ("numba", "numba"),
    ):
        try:
            out[label] = importlib.import_module(module).__version__
        except ImportError:
            out[label] = "not installed"
    return out


def _num(v: float | None) -> str:
    """A time or memory figure with about three significant digits."""
    if v is None:
        return "—"
    a = abs(v)
    digits = 0 if a >= 100 else 1 if a >= 10 else 2 if a >= 1 else 3
    return f"{v:.{digits}f}"


def _ratio(v: float | None) -> str:
    return "—" if v is None else f"{v:.2f}×"


def _lib(r: ProblemResult, name: str):
    return r.libs.get(name)


def _solve_rows(results: Sequence[ProblemResult]) -> list[str]:
    rows = [
        "| problem | T, nx, nu | solver (maxiter) | crocopy iters | crocopy cost | Crocoddyl iters | Crocoddyl cost"
        f" | cost rel. diff | agree (same iters, cost to {AGREEMENT_RTOL:g}) | crocopy ms/iter | Crocoddyl ms/iter"
        " | ratio | solves |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in results:
        cells = [r.name, ", ".join(map(str, r.dims)), f"{r.solver} ({r.maxiter})"]
        for name in ("crocopy", "crocoddyl"):
            lib = _lib(r, name)
            mark = "" if lib is None or lib.converged else " (not converged)"
            cells += ["—", "—"] if lib is None else [f"{lib.iters}{mark}", f"{lib.cost:.10g}"]
        diff, agree = r.cost_rel_diff(), r.agree(AGREEMENT_RTOL)
        cells.append("—" if diff is None else f"{diff:.1e}")
        cells.append("—" if agree is None else "yes" if agree else "no")
        cells += [_num(lib.ms_per_iter) if (lib := _lib(r, name)) else "—" for name in ("crocopy", "crocoddyl")]
        cells.append(_ratio(r.ratio("ms_per_iter")))
        cells.append("/".join(str(lib.solve_runs) for lib in r.libs.values()))
        rows.append("| " + " | ".join(cells) + " |")
    return rows


def _phase_rows(results: Sequence[ProblemResult]) -> list[str]:
    keys = (*PHASES, "total")
    rows = ["| problem | library | " + " | ".join(keys) + " |", "|---|---|" + "---|" * len(keys)]
    for r in results:
        for name, label in (("crocopy", "crocopy"), ("crocoddyl", "Crocoddyl")):
            if (lib := _lib(r, name)) is not None:
                rows.append(f"| {r.name} | {label} | " + " | ".join(_num(lib.phases[k]) for k in keys) + " |")
        if r.ratio("total") is not None:
            rows.append(f"| {r.name} | ratio | " + " | ".join(_ratio(r.ratio(k)) for k in keys) + " |")
    return rows


def _memory_rows(results: Sequence[ProblemResult]) -> list[str]:
    rows = ["| problem | crocopy MiB | Crocoddyl MiB | ratio |", "|---|---|---|---|"]
    for r in results:
        cells = [_num(lib.memory_mib) if (lib := _lib(r, name)) else "—" for name in ("crocopy", "crocoddyl")]
        rows.append(f"| {r.name} | " + " | ".join(cells) + f" | {_ratio(r.ratio('memory_mib'))} |")
    return rows


def bar_met(r: ProblemResult) -> bool | None:
    """Whether problem ``r`` meets its per-iteration bar (phase total ratio), None without both libraries."""
    ratio = r.ratio("total")
    return None if ratio is None else ratio <= bar_of(r.name)


def bar_verdict(r: ProblemResult) -> str:
    """``met`` (phase total and full-solve wall ratios within the bar), ``met (phases only)`` (the wall
    ratio, measured on fewer and non-interleaved solves, is above it), ``not met``, or ``—``."""
    met = bar_met(r)
    if met is None:
        return "—"
    if not met:
        return "not met"
    wall = r.ratio("ms_per_iter")
    return "met" if wall is not None and wall <= bar_of(r.name) else "met (phases only)"


def _bar_rows(results: Sequence[ProblemResult]) -> list[str]:
    rows = [
        "| problem | bar | per-iteration ratio (phase total) | wall ratio (full solve) | met |",
        "|---|---|---|---|---|",
    ]
    for r in results:
        rows.append(
            f"| {r.name} | ≤ {bar_of(r.name):g}× | {_ratio(r.ratio('total'))} | {_ratio(r.ratio('ms_per_iter'))}"
            f" | {bar_verdict(r)} |"
        )
    return rows


def format_report(results: Sequence[ProblemResult], meta: dict) -> str:
    """The markdown report of ``results``.

    Parameters
    ----------
    results : sequence of ProblemResult
        One entry per problem.
    meta : dict
        ``repeats`` (samples per phase), ``solve_budget`` (s), ``wall_s`` (duration of the run) and
        optionally ``load`` (load averages ``(at start, at end)``, each as from ``os.getloadavg``).
    """
    v = versions()
    load = meta.get("load")
    load_text = f"; load average {load[0][0]:.2f} at start, {load[1][0]:.2f} at end" if load else ""
    solvers = sorted({r.solver for r in results})
    lines = [
        "# crocopy vs Crocoddyl",
        "",
        f"Generated by `crocopy bench --vs crocoddyl` on {datetime.date.today().isoformat()}"
        f" in {meta.get('wall_s', 0.0) / 60:.1f} min.",
        "",
        f"- Machine: {cpu_model()}, {os.cpu_count()} cores{load_text}.",
        "- Versions: " + ", ".join(f"{k} {val}" for k, val in v.items()) + ".",
        f"- Solver: {', '.join(solvers)} from each builder's guess with the problem's iteration limit;"
        " one thread on both sides (BLAS limited to 1 thread, Crocoddyl `problem.nthreads = 1`);"
        " crocopy's box solvers with `compat_crocoddyl = True` (Crocoddyl's algorithm; crocopy's default"
        " follows the papers where Crocoddyl 3.2 departs from them).",
        f"- Phases: medians of {meta.get('repeats')} samples on a fixed trajectory (the builder's guess), the"
        " two libraries interleaved sample by sample. calc = `problem.calc`, calcDiff = `problem.calcDiff`,"
        " backward = `solver.computeDirection(False)`, forward = `solver.tryStep(α)` (the rollout, which"
        " evaluates every node; α the largest of 1, 1/2, ... whose rollout is finite), total = calcDiff"
        " + backward + forward (one iteration with one line-search trial). crocopy's phases run as its solve"
        " runs them: on compiled nodes where they apply (its calcDiff then also evaluates the nodes, which inside"
        " a solve it reuses from the accepted trial).",
        f"- Full solves: wall time / iterations, median over up to {meta.get('repeats')} solves per library"
        f" (alternating), fewer where the next round would pass the {meta.get('solve_budget', 0):g} s budget"
        " (column *solves*); the first solve of each library runs in a fresh process that measures memory.",
        "- Memory: peak resident memory (`VmHWM`, reset after the imports) of building and solving the problem"
        " in that fresh process, above the level after the imports and a 2-iteration warm-up solve of another"
        " small problem (which loads crocopy's compiled numba kernels, with and without compiled nodes; not counted"
        " in the solve time).",
        "",
        "## Solves",
        "",
        *_solve_rows(results),
        "",
        "## Phases (ms)",
        "",
        *_phase_rows(results),
        "",
        "## Peak memory",
        "",
        *_memory_rows(results),
        "",
        "## Bars (issue 7)",
        "",
        "Per-iteration time ≤ 1.5× Crocoddyl on jump, walk, taichi and man, ≤ 2× on the others,"
        " judged on the interleaved phase total; *met (phases only)* where the full-solve wall ratio (fewer,"
        " non-interleaved solves; extra line-search trials and solver overhead) is above the bar.",
        "",
        *_bar_rows(results),
        "",
    ]
    return "\n".join(lines)


def progress_line(r: ProblemResult, seconds: float) -> str:
    """One line summarising a finished problem (for the console while the benchmark runs)."""
    parts = [f"{r.name}: {seconds:.0f} s"]
    for name, lib in r.libs.items():
        parts.append(f"{name} {lib.iters} it, cost {lib.cost:.6g}, {lib.phases['total']:.2f} ms/it")
    if (ratio := r.ratio("total")) is not None:
        parts.append(f"ratio {ratio:.2f}×")
    return "; ".join(parts)
