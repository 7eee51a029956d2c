"""Session fixtures of the optional requirements (``optional_requirements.py``: Chromium for the
real-browser tests, the ``distributed`` extra for the Dask test) and the report header naming them."""

from __future__ import annotations

import pytest
from optional_requirements import chromium_path, in_ci, require_chromium


@pytest.fixture(scope="session")
def chromium() -> str:
    """Path of the Chromium executable (fails when missing; see ``optional_requirements.skip_without_chromium``)."""
    return require_chromium()


def pytest_report_header(config: pytest.Config) -> str:
    found = chromium_path()
    if found:
        return f"browser tests: {found}"
    return "browser tests: chromium not found, " + ("they will FAIL (CI)" if in_ci() else "they will be skipped")
