"""crocopy's build backend: setuptools', plus the kernels of the README's main job compiled into the wheel.

``pip install .`` builds a wheel on the machine it then installs on.  While it builds, :class:`BuildPy` runs
``crocopy compile --solve jump --solver boxfddp`` (what ``crocopy solve`` calls) on the wheel's own copy of the
sources, with numba writing into ``crocopy/_kernel_cache`` (:data:`crocopy.kernels.SHIPPED_DIR`), so that
the first ``crocopy solve`` after installing loads those kernels instead of compiling them.  For that the
wheel's build environment gets crocopy's own dependencies (:func:`get_requires_for_build_wheel`: numba and
Pinocchio in the versions the install resolves, from pip's cache).

The shipped entries are numba's own, keyed by the numba version, the source's SHA-256 and bytecode, the
argument types and the CPU: a wheel installed on another machine, with another numba, or an edited source
finds no entry and compiles as usual, so the fallback is always correct.  A failed compile leaves a wheel
without (or with fewer) entries and a warning in pip's log, never a failed install.

``CROCOPY_WHEEL_KERNELS=0`` builds a wheel without compiled kernels (no extra build dependencies); editable
installs (``pip install -e .``) never compile here.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
import time

from setuptools import build_meta as _setuptools
from setuptools.build_meta import *  # noqa: F403 - the PEP 517 hooks not redefined here
from setuptools.command.build_py import build_py

SWITCH = "CROCOPY_WHEEL_KERNELS"
"""Environment variable: ``0`` builds wheels without compiled kernels."""

MAIN_JOB = ("jump", "boxfddp")
"""``crocopy solve``'s default problem and solver, whose kernels the wheel ships."""

TIMEOUT = 1800.0


def enabled() -> bool:
    """True unless :data:`SWITCH` is ``0``."""
    return os.environ.get(SWITCH, "1").strip() != "0"


def runtime_requirements(pyproject: str = "pyproject.toml") -> list[str]:
    """crocopy's dependencies as ``pyproject`` lists them (``[]`` where ``tomllib`` is missing: Python 3.10)."""
    try:
        import tomllib
    except ImportError:
        return []
    with open(pyproject, "rb") as f:
        return list(tomllib.load(f)["project"]["dependencies"])


def get_requires_for_build_wheel(config_settings=None) -> list[str]:
    """setuptools' requirements, plus crocopy's dependencies when the wheel ships compiled kernels."""
    requires = list(_setuptools.get_requires_for_build_wheel(config_settings))
    return requires + (runtime_requirements() if enabled() else [])


def compile_into(build_lib: str, job: tuple[str, str] = MAIN_JOB, timeout: float = TIMEOUT) -> bool:
    """Compile ``job``'s kernels with the copy of crocopy in ``build_lib`` into its ``crocopy/_kernel_cache``
    (emptied first); True on success, else a warning on stderr (the wheel then ships what was written)."""
    target = os.path.join(build_lib, "crocopy", "_kernel_cache")
    shutil.rmtree(target, ignore_errors=True)
    with tempfile.TemporaryDirectory(prefix="crocopy-wheel-kernels-") as scratch:  # pip's build env: PYTHONPATH
        path = os.pathsep.join(p for p in (os.path.abspath(build_lib), os.environ.get("PYTHONPATH", "")) if p)
        env = {**os.environ, "PYTHONPATH": path, "CROCOPY_BUILD_KERNEL_CACHE": "1",
               "NUMBA_CACHE_DIR": os.path.join(scratch, "numba"), "CROCOPY_CACHE_DIR": os.path.join(scratch, "user"),
               "PYTHONDONTWRITEBYTECODE": "1", "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
               "MPLBACKEND": "Agg"}
        argv = [sys.executable, "-m", "crocopy.cli", "compile", "--solve", job[0], "--solver", job[1]]
        t0 = time.perf_counter()
        try:
            done = subprocess.run(argv, env=env, cwd=scratch, timeout=timeout, capture_output=True, text=True)
        except (OSError, subprocess.TimeoutExpired) as exc:
            print(f"crocopy: kernels not compiled into the wheel ({exc}); the first solve compiles them",
                  file=sys.stderr)
            return False
    entries = sum(len(files) for _, _, files in os.walk(target))
    if done.returncode != 0:
        tail = " | ".join((done.stdout + done.stderr).strip().splitlines()[-3:])
        print(f"crocopy: compiling kernels into the wheel failed (exit {done.returncode}: {tail}); {entries} cache"
              f" files shipped, the first solve compiles the rest", file=sys.stderr)
        return False
    print(f"crocopy: kernels of `crocopy solve {job[0]} --solver {job[1]}` compiled into the wheel in"
          f" {time.perf_counter() - t0:.0f} s ({entries} cache files)", file=sys.stderr)
    return True


class BuildPy(build_py):
    """setuptools' ``build_py``, then :func:`compile_into` the build folder (wheels only, unless disabled)."""

    def run(self) -> None:
        super().run()
        if not self.editable_mode and enabled() and not self.dry_run:
            compile_into(self.build_lib)
