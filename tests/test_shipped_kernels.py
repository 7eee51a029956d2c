"""Kernels shipped in the wheel (crocopy.kernels.SHIPPED_DIR, written by build_support/crocopy_build.py): read
before numba's cache, used only for the same source, CPU and numba, never written at run time."""

from __future__ import annotations

import pickle
import sys
from pathlib import Path

import pytest

from crocopy import kernel_warmup, kernels

numba = pytest.importorskip("numba")
ROOT = Path(__file__).resolve().parents[1]


def _quadruple(x):
    return 4.0 * x


@pytest.fixture
def shipped(monkeypatch, tmp_path):
    """A wheel's kernel folder filled with ``_quadruple``'s float entry as the build does; the user's cache empty."""
    monkeypatch.setattr(kernels, "KERNELS", [])
    monkeypatch.setattr(kernels, "cache_dir", str(tmp_path / "user"))
    monkeypatch.setattr(kernels, "SHIPPED_DIR", str(tmp_path / "shipped"))
    monkeypatch.setenv(kernels.BUILD_SWITCH, "1")
    built = kernels.compiled(_quadruple)
    assert built(1.5) == 6.0 and kernel_warmup.compilations([built]) == 1
    monkeypatch.delenv(kernels.BUILD_SWITCH)
    return tmp_path


def _files(folder: Path, suffix: str) -> list[Path]:
    return [p for p in folder.rglob(f"*{suffix}")] if folder.exists() else []


def test_the_build_writes_only_the_shipped_folder_and_an_install_loads_it(shipped):
    assert len(_files(shipped / "shipped", ".nbi")) == 1 and len(_files(shipped / "shipped", ".nbc")) == 1
    assert not _files(shipped / "user", ".nbi")
    installed = kernels.compiled(_quadruple)  # a later process of the installed copy
    assert kernels.is_cached(installed)
    assert installed(2.0) == 8.0 and kernel_warmup.compilations([installed]) == 0  # loaded, not compiled
    assert not _files(shipped / "user", ".nbi")  # nothing written at run time
    assert installed(3) == 12.0 and kernel_warmup.compilations([installed]) == 1  # a signature not shipped
    assert len(_files(shipped / "user", ".nbi")) == 1 and len(_files(shipped / "shipped", ".nbc")) == 1


def _rewrite_index(folder: Path, change) -> None:
    (index,) = _files(folder, ".nbi")
    with open(index, "rb") as f:
        version = pickle.load(f)
        stamp, overloads = pickle.loads(f.read())
    stamp, overloads = change(stamp, overloads)
    index.write_bytes(pickle.dumps(version) + pickle.dumps((stamp, overloads)))


def test_an_entry_for_another_cpu_is_not_used(shipped):
    def other_cpu(stamp, overloads):
        return stamp, {(sig, (triple, "another-cpu", features), *rest): name
                       for (sig, (triple, cpu, features), *rest), name in overloads.items()}

    _rewrite_index(shipped / "shipped", other_cpu)
    installed = kernels.compiled(_quadruple)
    assert installed(2.0) == 8.0 and kernel_warmup.compilations([installed]) == 1
    assert len(_files(shipped / "user", ".nbi")) == 1


def test_an_edited_source_or_another_numba_compiles_again(shipped, monkeypatch):
    _rewrite_index(shipped / "shipped", lambda stamp, overloads: ("the source before an edit", overloads))
    installed = kernels.compiled(_quadruple)
    assert not kernels.is_cached(installed)
    assert installed(2.0) == 8.0 and kernel_warmup.compilations([installed]) == 1
    monkeypatch.setattr(numba, "__version__", "0.0.1")  # an index written by another numba reads as empty
    assert not kernels.is_cached(kernels.compiled(_quadruple))


def test_the_stamp_is_the_sources_sha256(tmp_path):
    import hashlib

    assert kernels.source_digest(_quadruple) == hashlib.sha256(Path(__file__).read_bytes()).hexdigest()
    namespace: dict = {}
    exec(compile("def f(x):\n    return x\n", "<no file>", "exec"), namespace)
    assert kernels.source_digest(namespace["f"]) == ""


def test_the_build_backend_adds_the_dependencies_unless_switched_off(monkeypatch):
    sys.path.insert(0, str(ROOT / "build_support"))
    try:
        import crocopy_build
    finally:
        sys.path.remove(str(ROOT / "build_support"))
    monkeypatch.chdir(ROOT)
    monkeypatch.setattr(crocopy_build._setuptools, "get_requires_for_build_wheel", lambda settings=None: ["wheel"])
    requirements = crocopy_build.runtime_requirements()
    assert any(r.startswith("numba") for r in requirements) and any(r.startswith("pin") for r in requirements)
    monkeypatch.setenv(crocopy_build.SWITCH, "0")
    assert not crocopy_build.enabled()
    assert not any(r.startswith("numba") for r in crocopy_build.get_requires_for_build_wheel())
    monkeypatch.setenv(crocopy_build.SWITCH, "1")
    assert crocopy_build.get_requires_for_build_wheel() == ["wheel", *requirements]


def test_the_shipped_folder_can_be_switched_off(shipped, monkeypatch):
    monkeypatch.setenv(kernels.SHIPPED_SWITCH, "0")
    ignoring = kernels.compiled(_quadruple)
    assert not kernels.is_cached(ignoring)
    assert ignoring(2.0) == 8.0 and kernel_warmup.compilations([ignoring]) == 1
