"""``crocopy bench --first-solve --fresh-install``: the README's install into a new virtual environment, then its
first ``crocopy solve`` (:mod:`crocopy.bench.first_solve`).

The install is ``python -m venv``, then ``pip install SOURCE`` (a checkout of crocopy) in the new environment:
the wheel build compiles the main job's kernels into the wheel (``build_support/crocopy_build.py``).  Its wall
and CPU seconds are reported with the number of kernel cache files the installed copy ships, then the
first-solve rounds run with that environment's ``crocopy`` (empty ``NUMBA_CACHE_DIR`` and
``CROCOPY_CACHE_DIR``, as after installing).  pip's own download cache is used as it comes (it holds
the dependencies' wheels after a first install), so the install time is that of a machine that has
installed the dependencies before.
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from . import first_solve

SECTION = "## A fresh install's first solve (`crocopy bench --first-solve --fresh-install`)"


def check_source(source: str) -> Path:
    """``source`` as a checkout of crocopy (a folder whose ``pyproject.toml`` names the project crocopy);
    ValueError otherwise."""
    path = Path(source).resolve()
    pyproject = path / "pyproject.toml"
    if not pyproject.is_file() or 'name = "crocopy"' not in pyproject.read_text(encoding="utf-8"):
        raise ValueError(f"--source {source}: not a checkout of crocopy (no pyproject.toml naming crocopy)")
    return path


def shipped_files(venv: Path) -> int:
    """Kernel cache files shipped in ``venv``'s installed crocopy (``crocopy/_kernel_cache``)."""
    return sum(1 for lib in venv.glob("lib/python*/site-packages/crocopy/_kernel_cache")
               for p in lib.rglob("*") if p.is_file())


def install(source: Path, venv: Path, env: dict[str, str]) -> tuple[float, float]:
    """Create ``venv`` and ``pip install source`` into it; the wall and CPU seconds of both steps."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True, env=env)
    done = subprocess.run([str(venv / "bin" / "python"), "-m", "pip", "install", "-q", str(source)], env=env,
                          capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"pip install {source} failed:\n{done.stderr[-2000:]}")
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return time.perf_counter() - t0, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def run_fresh_install_bench(source: str, problem: str = "jump", solver: str = "boxfddp", repeats: int = 2,
                            progress: Callable[[str], None] | None = None) -> str:
    """The report: install figures, then :func:`crocopy.bench.first_solve.format_report` of the new environment."""
    path = check_source(source)
    progress = progress or (lambda line: print(line, file=sys.stderr, flush=True))
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV", "NUMBA_CACHE_DIR")}
    with tempfile.TemporaryDirectory(prefix="crocopy-fresh-install-") as scratch:
        venv = Path(scratch) / "venv"
        load = os.getloadavg()[0]
        progress(f"installing {path} into a new venv (load average {load:.2f})")
        wall, cpu = install(path, venv, env)
        files = shipped_files(venv)
        progress(f"installed in {wall:.1f} s ({cpu:.1f} s CPU), {files} kernel cache files shipped")
        samples = first_solve.measure(problem, solver, repeats, env=env, progress=progress,
                                      command=[str(venv / "bin" / "crocopy")])
    notes = (f"`python -m venv` + `pip install .` (pip's download cache warm): {wall:.1f} s wall, {cpu:.1f} s CPU"
             f" (load average {load:.2f} at its start); the wheel shipped {files} kernel cache files.")
    return first_solve.format_report(samples, problem, solver, title=f"{SECTION}\n\n{notes}")
