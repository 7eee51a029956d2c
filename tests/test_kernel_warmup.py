"""The first-run notice (crocopy.kernel_warmup.CompileProgress): printed only when numba compiles a kernel, with a
count of the kernels compiled and of those still to compile; silent when every kernel is loaded from the cache."""

from __future__ import annotations

import importlib
import io
import sys

import pytest

from crocopy import kernel_warmup, kernels
from crocopy.kernel_warmup import COMPILING_NOTICE, CompileProgress, warm_up_kernels

numba = pytest.importorskip("numba")

MODULE = '''
from crocopy import kernels


def _leaf(x, k):
    return k * x


leaf = kernels.compiled(_leaf)


def _caller(x):
    return leaf(x, 4) + leaf(x, 5)


caller = kernels.compiled(_caller)


def _unused(x):
    return leaf(x, 1)


unused = kernels.compiled(_unused)
'''


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


@pytest.fixture
def tiny(monkeypatch, tmp_path):
    """A module of three kernels (``caller`` calls ``leaf`` twice with constant arguments; ``unused`` is not
    called), cached in a fresh folder; calling it again imports it anew (a later process's kernels)."""
    monkeypatch.setattr(kernels, "KERNELS", [])
    monkeypatch.setattr(kernels, "cache_dir", str(tmp_path / "numba"))
    (tmp_path / "tiny_kernels.py").write_text(MODULE)
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, "tiny_kernels", raising=False)
    loaded = []

    def load():
        loaded.append(importlib.reload(loaded[-1]) if loaded else importlib.import_module("tiny_kernels"))
        return loaded[-1]

    return load


def test_the_notice_counts_the_kernels_compiled_and_their_uncached_callees(tiny):
    module = tiny()
    assert kernels.kernel_callees(module.caller) == [module.leaf] and kernels.kernel_callees(module.leaf) == []
    out = io.StringIO()
    spent = warm_up_kernels(lambda: module.caller(1.0), CompileProgress(out, interval=0.0))
    lines = out.getvalue().splitlines()
    assert lines[:2] == [f"{COMPILING_NOTICE}: 1/2", f"{COMPILING_NOTICE}: 2/2"]  # caller first, leaf inside it
    assert lines[2] == f"kernels compiled in {spent:.1f} s: 2 kernels, 2 signatures (cached for the next runs;" \
                       " not counted in the solve time)" and len(lines) == 3
    assert len(module.leaf.signatures) == 1  # leaf(x, 4) and leaf(x, 5): one (float64, int64) signature
    assert module.unused.signatures == [] and kernel_warmup.compilations([module.unused]) == 0


def test_the_notice_is_silent_when_the_cache_holds_every_kernel_the_run_needs(tiny):
    first = tiny()
    assert first.caller(1.0) == 9.0  # compiles and caches caller (and leaf)
    again = tiny()  # new dispatchers, as in a later process; `unused` is still not cached
    assert not kernels.is_cached(again.unused)
    out = io.StringIO()
    assert warm_up_kernels(lambda: again.caller(2.0), CompileProgress(out, interval=0.0)) == 0.0
    assert out.getvalue() == "" and kernel_warmup.compilations([again.caller, again.leaf]) == 0


def test_a_cached_callee_is_not_counted(tiny):
    module = tiny()
    assert module.leaf(1.0, 2) == 2.0  # leaf alone is cached
    again = tiny()
    out = io.StringIO()
    warm_up_kernels(lambda: again.unused(1.0), CompileProgress(out, interval=0.0))
    assert out.getvalue().splitlines()[0] == f"{COMPILING_NOTICE}: 1/1"  # unused only; leaf loads


def test_on_a_terminal_the_count_is_rewritten_in_place(tiny):
    module = tiny()
    out = Terminal()
    warm_up_kernels(lambda: module.caller(1.0), CompileProgress(out, interval=60.0))
    text = out.getvalue()
    assert text.startswith(f"\r{COMPILING_NOTICE}: 1/2\r{COMPILING_NOTICE}: 2/2")
    assert text.count("\n") == 2 and "\nkernels compiled in " in text


def test_elsewhere_a_count_line_is_printed_at_most_every_interval():
    now = [0.0]
    out = io.StringIO()
    progress = CompileProgress(out, interval=5.0, clock=lambda: now[0])
    names = [f"k{i}" for i in range(4)]
    for t, name in zip([0.0, 1.0, 6.0, 7.0], names):
        now[0] = t
        progress(name)  # any object stands for a kernel; a non-kernel has no callees
    now[0] = 9.5
    assert progress.finish() == 9.5
    lines = out.getvalue().splitlines()
    assert lines[:2] == [f"{COMPILING_NOTICE}: 1/1", f"{COMPILING_NOTICE}: 3/3"]
    assert lines[2].startswith("kernels compiled in 9.5 s: 4 kernels, 4 signatures") and len(lines) == 3


def test_nothing_compiled_prints_nothing():
    out = Terminal()
    assert CompileProgress(out).finish() == 0.0 and out.getvalue() == ""


def test_a_kernel_compiled_for_kernels_only_gets_its_python_wrapper_when_python_calls_it(tiny):
    module = tiny()
    assert module.caller(1.0) == 9.0
    (signature,) = module.leaf.signatures
    assert module.leaf.kernels_only == {signature}  # compiled inside caller, without the wrapper
    assert module.leaf(2.0, 3) == 6.0 and module.leaf.kernels_only == set()  # compiled again, wrapper included
    assert kernel_warmup.compilations([module.leaf]) == 2
    again = tiny()  # a later process: each entry is loaded from its own cache slot
    assert again.leaf(2.0, 3) == 6.0 and again.caller(1.0) == 9.0
    assert again.unused(1.0) == 1.0  # compiles unused; leaf's entry for kernels is loaded
    assert kernel_warmup.compilations([again.leaf, again.caller]) == 0


def test_on_compile_is_called_once_at_the_first_compilation(tiny):
    module = tiny()
    started = []
    progress = CompileProgress(io.StringIO(), on_compile=lambda: started.append(True))
    warm_up_kernels(lambda: module.caller(1.0), progress)
    assert started == [True] and progress.signatures == 2
    again = tiny()
    quiet = CompileProgress(io.StringIO(), on_compile=lambda: started.append(True))
    warm_up_kernels(lambda: again.caller(1.0), quiet)
    assert started == [True]  # nothing compiled: not called
