"""Parsed robot models kept on disk, so that a builder does not parse the robot's URDF in every process.

``example_robot_data.load(name)`` parses the URDF and builds the visual and collision geometry
(meshes): about 2 s for ANYmal, most of ``crocopy solve jump``'s start-up.  The builders only need
the kinematic ``pinocchio.Model``, which Pinocchio writes and reads back exactly
(``saveToBinary``/``loadFromBinary``, equal by ``==``) in well under a millisecond.

:func:`load_model_cached` keeps one such file per robot in
:func:`crocopy.user_cache.user_cache_dir` ``/ "models"``, named after the robot and a digest of the
Pinocchio and example-robot-data versions and install folders (another install or version never
reads it).  A missing, unreadable or unwritable file only means the URDF is parsed again.
"""

from __future__ import annotations

import hashlib
import os
import tempfile
from pathlib import Path

import example_robot_data
import pinocchio as pin

from crocopy.user_cache import user_cache_dir


def _model_file(name: str) -> Path:
    stamp = "|".join((pin.__version__, pin.__file__, example_robot_data.__file__, _erd_version()))
    digest = hashlib.sha256(stamp.encode()).hexdigest()[:16]
    return user_cache_dir("models") / f"{name}-{digest}.bin"


def _erd_version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("example-robot-data")
    except PackageNotFoundError:
        return "unknown"


def _save(model: pin.Model, path: Path) -> None:
    """Write ``model`` to ``path`` atomically (a concurrent reader sees the whole file or none)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".tmp")
    os.close(fd)
    try:
        model.saveToBinary(tmp)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def load_model_cached(name: str) -> pin.Model:
    """example-robot-data's ``load(name).model``, read from the cache file when there is one (else parsed
    and written there)."""
    path = _model_file(name)
    if path.is_file():
        model = pin.Model()
        try:
            model.loadFromBinary(str(path))
            return model
        except (RuntimeError, OSError, ValueError):
            pass
    model = example_robot_data.load(name).model
    try:
        _save(model, path)
    except (RuntimeError, OSError):
        pass
    return model
