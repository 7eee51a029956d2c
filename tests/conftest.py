"""Shared test requirements: the real-browser tests need Chromium, the Dask test the ``distributed`` extra.

Outside CI a missing requirement skips those tests with the reason in the summary (``-rs`` is in
the pytest options); in CI (environment variable ``CI`` set to ``true`` or ``1``, as ``.ci/run``
does) it fails them, because ``.ci/run`` installs Chromium and the extras and these checks must
run there.
"""

from __future__ import annotations

import importlib
import os
import shutil
from types import ModuleType

import pytest

CHROMIUM_NAMES = ("chromium", "chromium-browser")
INSTALL_HINT = "install it with `apt-get install -y chromium` (Debian/Ubuntu)"


def in_ci() -> bool:
    """Whether the tests run in CI (``CI=true``), where every requirement is mandatory."""
    return os.environ.get("CI", "").strip().lower() in ("1", "true", "yes")


def chromium_path() -> str | None:
    """The Chromium executable on ``PATH``, or ``None``."""
    for name in CHROMIUM_NAMES:
        found = shutil.which(name)
        if found:
            return found
    return None


def require_chromium() -> str:
    """Chromium's path; skips the calling test without it, or fails it in CI."""
    found = chromium_path()
    if found is not None:
        return found
    if in_ci():
        pytest.fail(f"chromium not found (required in CI; .ci/run installs it): {INSTALL_HINT}")
    pytest.skip(f"chromium not found, real-browser test skipped: {INSTALL_HINT} (CI requires it)")


def require_module(name: str, extra: str) -> ModuleType:
    """Import ``name``; without it skip the calling test (fail it in CI), naming the extra that installs it."""
    try:
        return importlib.import_module(name)
    except ImportError as exc:
        hint = f'{name} not importable ({exc}): pip install ".[{extra}]"'
        if in_ci():
            pytest.fail(f"{hint} (required in CI; .ci/run installs it)")
        pytest.skip(f"{hint} (CI requires it)")


@pytest.fixture(scope="session")
def chromium() -> str:
    """Path of the Chromium executable (skip outside CI / fail in CI when missing)."""
    return require_chromium()


def pytest_report_header(config: pytest.Config) -> str:
    found = chromium_path()
    if found:
        return f"browser tests: {found}"
    return "browser tests: chromium not found, " + ("they will FAIL (CI)" if in_ci() else "they will be skipped")
