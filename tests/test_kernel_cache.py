"""Where the compiled kernels are cached, how a cold cache is told apart without compiling, ``crocopy
compile``, and the user cache folder (crocopy.kernels, crocopy.kernel_warmup, crocopy.user_cache)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from crocopy import kernel_warmup, kernels
from crocopy.user_cache import user_cache_dir

numba = pytest.importorskip("numba")
CROCOPY = os.path.join(os.path.dirname(sys.executable), "crocopy")


def test_user_cache_dir_follows_the_environment(monkeypatch, tmp_path):
    monkeypatch.setenv("CROCOPY_CACHE_DIR", str(tmp_path / "mine"))
    assert user_cache_dir("numba") == tmp_path / "mine" / "numba"
    monkeypatch.delenv("CROCOPY_CACHE_DIR")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert user_cache_dir("models", "x") == tmp_path / "xdg" / "crocopy" / "models" / "x"
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert user_cache_dir() == tmp_path / "home" / ".cache" / "crocopy"


def test_a_read_only_install_caches_kernels_in_the_user_cache(monkeypatch, tmp_path):
    monkeypatch.setenv("CROCOPY_CACHE_DIR", str(tmp_path))
    package = str(tmp_path / "site-packages" / "crocopy")
    assert kernels.cache_dir_fallback(package, "/chosen") == "/chosen"  # NUMBA_CACHE_DIR wins
    monkeypatch.setattr(os, "access", lambda path, mode: True)
    assert kernels.cache_dir_fallback(package, "") == ""  # writable: numba's default, beside the sources
    monkeypatch.setattr(os, "access", lambda path, mode: path != package)
    assert kernels.cache_dir_fallback(package, "") == str(tmp_path / "numba")


def _twice(x):
    return 2.0 * x


def test_compiled_caches_in_its_folder_and_the_cache_tells_cold_from_warm(monkeypatch, tmp_path):
    monkeypatch.setattr(kernels, "KERNELS", [])
    monkeypatch.setattr(kernels, "cache_dir", str(tmp_path))
    previous = numba.config.CACHE_DIR
    kernel = kernels.compiled(_twice)
    assert numba.config.CACHE_DIR == previous  # only this kernel's folder was chosen
    assert kernels.KERNELS == [kernel]
    assert not kernels.is_cached(kernel) and kernels.cache_is_cold()
    assert kernel(1.5) == 3.0
    assert kernels.is_cached(kernel) and not kernels.cache_is_cold()
    assert any(p.suffix == ".nbi" for p in tmp_path.rglob("*")) and any(p.suffix == ".nbc" for p in tmp_path.rglob("*"))
    again = kernels.compiled(_twice)  # a later process: same function, same folder
    assert kernels.is_cached(again)
    assert again(2.0) == 4.0 and kernel_warmup.compilations([again]) == 0  # loaded, not compiled


def test_a_stale_or_unreadable_index_counts_as_cold(monkeypatch, tmp_path):
    monkeypatch.setattr(kernels, "KERNELS", [])
    monkeypatch.setattr(kernels, "cache_dir", str(tmp_path))
    kernel = kernels.compiled(_twice)
    kernel(1.0)
    (index,) = tmp_path.rglob("*.nbi")
    index.write_bytes(b"not an index")
    assert not kernels.is_cached(kernel)
    assert not kernels.is_cached(object())  # not a cached dispatcher
    assert not kernels.cache_is_cold([])


def _thrice(x):
    return 3.0 * x


def _truncate(path: Path) -> None:
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])


@pytest.mark.parametrize("damage", ["truncated index", "garbage index", "truncated data", "foreign data"])
def test_a_damaged_cache_entry_is_set_aside_with_one_warning_and_rebuilt(damage, monkeypatch, tmp_path, caplog):
    monkeypatch.setattr(kernels, "KERNELS", [])
    monkeypatch.setattr(kernels, "cache_dir", str(tmp_path))
    assert kernels.compiled(_twice)(1.0) == 2.0 and kernels.compiled(_thrice)(1.0) == 3.0
    (index,) = tmp_path.rglob("*._twice-*.nbi")
    (data,) = tmp_path.rglob("*._twice-*.nbc")
    (other,) = tmp_path.rglob("*._thrice-*.nbc")
    {"truncated index": lambda: _truncate(index), "garbage index": lambda: index.write_bytes(b"\x80\x04garbage"),
     "truncated data": lambda: _truncate(data), "foreign data": lambda: data.write_bytes(other.read_bytes()),
     }[damage]()
    damaged = index if "index" in damage else data
    with caplog.at_level("WARNING", logger="crocopy"):
        again = kernels.compiled(_twice)  # a later process: reads the damaged entry
        assert again(2.5) == 5.0 and kernel_warmup.compilations([again]) == 1  # compiled, not loaded
    (record,) = caplog.records
    assert record.levelname == "WARNING" and "\n" not in record.getMessage()
    assert f"damaged kernel cache file {damaged} set aside" in record.getMessage()
    caplog.clear()
    with caplog.at_level("WARNING", logger="crocopy"):
        third = kernels.compiled(_twice)  # the rebuilt entry loads cleanly
        assert kernels.is_cached(third) and third(1.0) == 2.0 and kernel_warmup.compilations([third]) == 0
    assert caplog.records == []


TINY = """
import sys
from crocopy import kernel_warmup, kernels

def _scaled(x, s):
    return s * x.sum()

scaled = kernels.compiled(_scaled)
import numpy as np
print(scaled(np.arange(4.0), 0.5), kernel_warmup.compilations([scaled]))
"""


@pytest.mark.parametrize("suffix", [".nbi", ".nbc"])
def test_a_run_on_a_cache_with_a_file_cut_in_half_succeeds_with_one_warning_line(suffix, tmp_path):
    (tmp_path / "tiny.py").write_text(TINY)
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba"), "OMP_NUM_THREADS": "1"}

    def run() -> subprocess.CompletedProcess:
        return subprocess.run([sys.executable, "tiny.py"], capture_output=True, text=True, env=env, cwd=tmp_path,
                              timeout=300)

    first = run()
    assert (first.returncode, first.stdout, first.stderr) == (0, "3.0 1\n", "")
    (cut,) = (tmp_path / "numba").rglob(f"*._scaled-*{suffix}")
    _truncate(cut)
    damaged = run()
    assert damaged.returncode == 0 and damaged.stdout == "3.0 1\n"  # right answer, compiled again
    (line,) = damaged.stderr.splitlines()
    assert line.startswith(f"crocopy: damaged kernel cache file {cut} set aside (")
    repaired = run()
    assert (repaired.returncode, repaired.stdout, repaired.stderr) == (0, "3.0 0\n", "")  # loaded, no warning


def test_an_empty_cache_folder_is_cold_for_every_kernel(tmp_path):
    script = ("import crocopy\nfrom crocopy import kernels\n"
              "print(len(kernels.KERNELS), kernels.cache_is_cold(), any(map(kernels.is_cached, kernels.KERNELS)))")
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path), kernels.SHIPPED_SWITCH: "0"}  # not the wheel's kernels
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env, cwd=tmp_path,
                          timeout=300)
    assert done.returncode == 0, done.stderr
    count, cold, any_cached = done.stdout.split()
    assert int(count) >= 10 and cold == "True" and any_cached == "False"


@pytest.mark.slow
def test_crocopy_compile_fills_an_empty_cache_then_solve_compiles_nothing(tmp_path):
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba"), "CROCOPY_CACHE_DIR": str(tmp_path / "user"),
           "OMP_NUM_THREADS": "1", kernels.SHIPPED_SWITCH: "0"}
    first = subprocess.run([CROCOPY, "compile"], capture_output=True, text=True, env=env, cwd=tmp_path)
    assert first.returncode == 0, first.stderr
    assert first.stderr.startswith(kernel_warmup.COMPILING_NOTICE)
    compiled = int(first.stdout.split("(")[1].split()[0])
    assert compiled >= len(kernels.KERNELS) and f"cache under {tmp_path / 'numba'}" in first.stdout
    assert any(Path(tmp_path / "user" / "models").iterdir())  # the robots' parsed models were kept too
    again = subprocess.run([CROCOPY, "compile"], capture_output=True, text=True, env=env, cwd=tmp_path)
    assert again.returncode == 0 and "(0 signatures compiled" in again.stdout and again.stderr == ""
    solve = subprocess.run([CROCOPY, "solve", "jump", "--maxiter", "2", "--quiet", "--no-html"],
                           capture_output=True, text=True, env=env, cwd=tmp_path)
    assert solve.returncode in (0, 1) and "compiling" not in solve.stderr


def test_without_any_writable_cache_folder_the_kernel_still_compiles(monkeypatch, tmp_path, caplog):
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    monkeypatch.setattr(kernels, "KERNELS", [])
    monkeypatch.setattr(kernels, "cache_dir", str(blocker / "numba"))  # below a file: cannot be created
    monkeypatch.setattr(numba.config, "CACHE_LOCATOR_CLASSES", "UserProvidedCacheLocator", raising=False)
    with caplog.at_level("WARNING", logger="crocopy"):
        kernel = kernels.compiled(_twice)
    assert kernel(4.0) == 8.0 and kernels.KERNELS == [kernel]
    assert "_twice: compiled in every process, not cached" in caplog.text
    assert not kernels.is_cached(kernel) and kernels.cache_is_cold()
