"""Optional test requirements: the real-browser tests need Chromium, the Dask test the ``distributed`` extra.

Outside CI a missing requirement skips those tests (a ``skipif`` mark, with the reason in the
summary); in CI (environment variable ``CI`` set to ``true`` or ``1``, as ``.ci/run`` does) the mark
does not apply and the ``require_*`` helpers fail the tests, because ``.ci/run`` installs Chromium
and the extras and these checks must run there.
"""

from __future__ import annotations

import importlib
import importlib.util
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


def skip_without_chromium() -> pytest.MarkDecorator:
    """Mark: skip outside CI when Chromium is missing (in CI the test runs and :func:`require_chromium` fails)."""
    return pytest.mark.skipif(chromium_path() is None and not in_ci(),
                              reason=f"chromium not found, real-browser test skipped: {INSTALL_HINT} (CI requires it)")


def require_chromium() -> str:
    """Chromium's path; fails the calling test without it (outside CI :func:`skip_without_chromium` skipped it)."""
    found = chromium_path()
    if found is None:
        pytest.fail(f"chromium not found (required in CI; .ci/run installs it): {INSTALL_HINT}")
    return found


def _module_hint(name: str, extra: str) -> str:
    return f'{name} not importable: pip install ".[{extra}]"'


def skip_without_module(name: str, extra: str) -> pytest.MarkDecorator:
    """Mark: skip outside CI when ``name`` cannot be found (in CI :func:`require_module` fails instead)."""
    return pytest.mark.skipif(importlib.util.find_spec(name) is None and not in_ci(),
                              reason=f"{_module_hint(name, extra)} (CI requires it)")


def require_module(name: str, extra: str) -> ModuleType:
    """Import ``name``; fail the calling test without it, naming the extra that installs it."""
    try:
        return importlib.import_module(name)
    except ImportError as exc:
        pytest.fail(f"{_module_hint(name, extra)} ({exc}) (required in CI; .ci/run installs it)")
