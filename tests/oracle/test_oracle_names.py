"""Oracle: Crocoddyl's helpers and constructor keywords as crocopy gives them (bench extra).

- ``rotationMatrixFromTwoVectors`` equals Crocoddyl's at random and degenerate vectors, except exactly
  opposite ones (Crocoddyl: the identity; crocopy: a half-turn that turns ``a`` into ``b``).
- The contact and impulse constructors take Crocoddyl's argument names: every overload listed by
  Crocoddyl's ``help()`` (its docstring signatures) is a prefix of crocopy's parameter list, and a
  call with those keywords builds the same model in both libraries.
"""

from __future__ import annotations

import inspect
import re

import numpy as np
import pinocchio as pin
import pytest

crocoddyl = pytest.importorskip("crocoddyl")

import oracle_models as om  # noqa: E402

import crocopy  # noqa: E402

pytestmark = pytest.mark.usefixtures("bench_crocoddyl")

CLASSES = ("ContactModel1D", "ContactModel2D", "ContactModel3D", "ContactModel6D", "ImpulseModel3D",
           "ImpulseModel6D", "ContactModelMultiple", "ImpulseModelMultiple")


def test_rotation_from_two_vectors_equals_crocoddyl():
    rng = np.random.default_rng(om.SEED)
    ez = np.array([0.0, 0.0, 1.0])
    pairs = [tuple(rng.normal(size=(2, 3))) for _ in range(20)]
    pairs += [(ez, ez), (ez, np.array([1e-12, 0.0, -1.0])), (np.zeros(3), ez), (ez, [0.0, 3.0, 0.0])]
    for a, b in pairs:
        np.testing.assert_allclose(crocopy.rotationMatrixFromTwoVectors(a, b),
                                   crocoddyl.rotationMatrixFromTwoVectors(np.asarray(a), np.asarray(b)), atol=1e-12)
    # exactly opposite: Crocoddyl's identity does not turn a into b, crocopy's half-turn does
    np.testing.assert_array_equal(crocoddyl.rotationMatrixFromTwoVectors(ez, -ez), np.eye(3))
    np.testing.assert_allclose(crocopy.rotationMatrixFromTwoVectors(ez, -ez) @ ez, -ez, atol=1e-15)


def _overloads(cls) -> list[list[str]]:
    """Argument names of each ``__init__`` overload in Crocoddyl's docstring (without ``self``)."""
    doc = cls.__init__.__doc__ or ""
    heads = re.findall(r"__init__\(\s*\(object\)self,([^\n]*)\) -> None", doc)
    return [re.findall(r"\)\s*(\w+)", head) for head in heads]


@pytest.mark.parametrize("name", CLASSES)
def test_constructor_argument_names(name):
    overloads = _overloads(getattr(crocoddyl, name))
    assert overloads, f"no signature found in crocoddyl.{name}.__init__ docstring"
    mine = list(inspect.signature(getattr(crocopy, name).__init__).parameters)[1:]
    for names in overloads:
        for arg in names:
            assert arg in mine, f"{name}: Crocoddyl's argument {arg!r} ({names}) is not one of crocopy's {mine}"
    longest = max(overloads, key=len)
    assert mine[: len(longest)] == longest, f"{name}: crocopy's {mine} vs Crocoddyl's {longest}"


def test_keyword_construction_gives_the_same_contacts():
    model = om.robot("anymal")
    fid = model.getFrameId("LF_FOOT")
    rot = pin.rpy.rpyToMatrix(0.1, 0.2, 0.3)
    for lib in (crocopy, crocoddyl):
        state = lib.StateMultibody(model)
        c1 = lib.ContactModel1D(state=state, id=fid, xref=0.2, type=pin.WORLD, rotation=rot, nu=12,
                                gains=np.array([1.0, 2.0]))
        c2 = lib.ContactModel2D(state=state, id=fid, xref=np.ones(2), nu=12, gains=np.array([1.0, 2.0]))
        i3 = lib.ImpulseModel3D(state=state, frame=fid, type=pin.LOCAL_WORLD_ALIGNED)
        assert (c1.nc, c1.nu, c1.type, c1.reference, c2.nc, c2.type, i3.nc, i3.type) == (
            1, 12, pin.WORLD, 0.2, 2, pin.LOCAL, 3, pin.LOCAL_WORLD_ALIGNED)
        np.testing.assert_array_equal(c1.Raxis, rot)
