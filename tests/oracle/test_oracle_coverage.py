"""The oracle covers crocopy: every residual, activation, cost and constraint class crocopy exports
has a builder in oracle_models (runs without Crocoddyl, so a new class cannot slip past the oracle),
and the declared deviations are the ones docs/crocoddyl_deviations.md lists."""

from __future__ import annotations

import pathlib

import oracle_deviations as od
import oracle_models as om

import crocopy

#: containers and wrappers the node builder uses around every residual
CONTAINERS = {"CostModelResidual", "CostModelSum", "ConstraintModelResidual", "ConstraintModelManager"}
PREFIXES = ("ResidualModel", "ActivationModel", "CostModel", "ConstraintModel")
#: bases and numerical-differentiation wrappers (they compute nothing of their own to compare); ResidualModelNumba
#: is the base of a user's numba residual (crocopy's own, tested in tests/test_residual_numba.py)
NOT_MODELS = ("Abstract", "NumDiff", "Numba")
DOC = pathlib.Path(__file__).resolve().parents[2] / "docs" / "crocoddyl_deviations.md"


def test_every_crocopy_model_class_has_an_oracle_builder():
    exported = {n for n in dir(crocopy) if n.startswith(PREFIXES) and not n.endswith(NOT_MODELS)}
    built = {spec.cls for spec in om.RESIDUALS.values()} | {cls for cls, _ in om.ACTIVATIONS.values()} | CONTAINERS
    assert exported - built == set(), f"no oracle builder for {sorted(exported - built)}"


def test_every_dynamics_kind_and_integrator_is_crossed():
    assert {kind for spec in om.RESIDUALS.values() for kind in spec.kinds} == set(om.ALL)
    assert set(om.INTEGRATORS) >= {"euler", "rk2", "rk3", "rk4"}


def test_every_declared_deviation_is_documented():
    text = DOC.read_text(encoding="utf-8")
    missing = [d.name for d in od.DEVIATIONS if f"`{d.name}`" not in text]
    assert not missing, f"docs/crocoddyl_deviations.md does not describe {missing}"
