"""Parsed robot models kept on disk (crocopy.problems.model_cache): the file gives back the very model
example-robot-data parses, and a missing, corrupt or unwritable cache falls back to parsing."""

from __future__ import annotations

import example_robot_data
import pinocchio as pin
import pytest

from crocopy.problems import model_cache

ROBOT = "double_pendulum"


@pytest.fixture
def cache(monkeypatch, tmp_path):
    monkeypatch.setenv("CROCOPY_CACHE_DIR", str(tmp_path))
    return tmp_path / "models"


def _unparsable(name, *args, **kwargs):
    raise AssertionError(f"{name} was parsed again instead of read from the cache")


def test_the_cached_model_is_the_parsed_one(cache, monkeypatch):
    parsed = example_robot_data.load(ROBOT).model
    first = model_cache.load_model_cached(ROBOT)
    (path,) = cache.iterdir()
    assert path.name.startswith(ROBOT + "-") and path.suffix == ".bin"
    monkeypatch.setattr(model_cache.example_robot_data, "load", _unparsable)
    second = model_cache.load_model_cached(ROBOT)
    assert isinstance(second, pin.Model) and second == parsed and first == parsed
    assert second is not first


def test_a_corrupt_file_is_parsed_again_and_rewritten(cache):
    model_cache.load_model_cached(ROBOT)
    (path,) = cache.iterdir()
    path.write_bytes(b"garbage")
    assert model_cache.load_model_cached(ROBOT) == example_robot_data.load(ROBOT).model
    assert path.stat().st_size > len(b"garbage")
    assert [p.name for p in cache.iterdir()] == [path.name]  # no temporary file left behind


def test_an_unwritable_cache_still_gives_the_model(monkeypatch, tmp_path):
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    monkeypatch.setenv("CROCOPY_CACHE_DIR", str(blocker))  # the cache folder would be below a file
    assert model_cache.load_model_cached(ROBOT) == example_robot_data.load(ROBOT).model


def test_another_pinocchio_version_does_not_read_the_file(cache, monkeypatch):
    model_cache.load_model_cached(ROBOT)
    monkeypatch.setattr(model_cache.pin, "__version__", "0.0.0-other")
    model_cache.load_model_cached(ROBOT)
    assert len(list(cache.iterdir())) == 2
