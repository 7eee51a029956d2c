"""Oracle: every activation against Crocoddyl's, and the proof of each activation Hessian that differs.

Values and gradients (``a_value``, ``Ar``) must equal Crocoddyl's to 1e-10 at random residuals (inside
and outside the bounds and barrier radii).  ``Arr`` must too, except for the activations of the
declared deviations, where the test proves who is right:

- true Hessians: ``Arr`` against central differences of the library's own ``Ar``;
- the Gauss-Newton Hessian of ``2NormBarrier(true_hessian=False)``: ``a = ½ s²`` with
  ``s = ‖r‖ - alpha``, so its Gauss-Newton Hessian is ``∇s ∇sᵀ = Ar Arᵀ / (2a)``;
- the quadratic-flat activations: crocopy's ``Arr`` is the diagonal of the central differences of
  its ``Ar`` (the whole matrix with crocopy's ``true_hessian=True``), Crocoddyl's is neither.
"""

from __future__ import annotations

import numpy as np
import pytest

crocoddyl = pytest.importorskip("crocoddyl")

import oracle_deviations as od  # noqa: E402
import oracle_models as om  # noqa: E402

import crocopy  # noqa: E402

NR = 6
H = 1e-6
DECLARED = {name for d in od.DEVIATIONS if d.sort == "activation" for name in d.activations}
FLAT = {"quad_flat_exp", "quad_flat_log"}
TRUE_HESSIAN = DECLARED - {"norm_barrier"} - FLAT
IMPLEMENTED = [name for name, (cls, _) in om.ACTIVATIONS.items() if om.implemented(crocopy, cls)]


def residuals() -> list[np.ndarray]:
    rng = np.random.default_rng(om.SEED)
    return [0.3 * rng.normal(size=NR), rng.normal(size=NR), 3.0 * rng.normal(size=NR)]


def evaluate(lib, name: str, r: np.ndarray):
    model = om.ACTIVATIONS[name][1](lib, NR)
    data = model.createData()
    model.calc(data, r)
    model.calcDiff(data, r)
    return model, data, float(data.a_value), np.array(data.Ar, copy=True), np.array(data.Arr, copy=True)


def numeric_hessian(model, data, r: np.ndarray) -> np.ndarray:
    """Central differences of ``Ar``."""
    columns = []
    for e in np.eye(NR) * H:
        model.calcDiff(data, r + e)
        plus = np.array(data.Ar, copy=True)
        model.calcDiff(data, r - e)
        columns.append((plus - np.array(data.Ar)) / (2 * H))
    return np.array(columns).T


def hessian_error(lib, name: str, r: np.ndarray) -> float:
    """Relative error of ``Arr`` against central differences of ``Ar``."""
    model, data, _, _, Arr = evaluate(lib, name, r)
    return od.relative_error(Arr, numeric_hessian(model, data, r))


@pytest.mark.parametrize("name", IMPLEMENTED)
def test_activation_equals_crocoddyl(name):
    for r in residuals():
        _, _, a, Ar, Arr = evaluate(crocopy, name, r)
        _, _, b, Br, Brr = evaluate(crocoddyl, name, r)
        assert abs(a - b) <= od.TOL * max(1.0, abs(b)), f"{name}: a = {a} vs Crocoddyl's {b}"
        assert od.relative_error(Ar, Br) <= od.TOL, f"{name}: Ar differs"
        if name not in DECLARED:
            assert od.relative_error(Arr, Brr) <= od.TOL, f"{name}: Arr differs with no declared deviation"


@pytest.mark.parametrize("name", sorted(TRUE_HESSIAN & set(IMPLEMENTED)))
def test_crocopy_hessian_is_the_derivative_of_its_gradient_and_crocoddyls_is_not(name):
    errors = [(hessian_error(crocopy, name, r), hessian_error(crocoddyl, name, r)) for r in residuals()]
    assert all(mine <= od.ND_TOL for mine, _ in errors), f"{name}: crocopy's Arr is off its numdiff: {errors}"
    assert any(theirs > 1e-3 for _, theirs in errors), f"{name}: Crocoddyl's Arr agrees with its numdiff: {errors}"


@pytest.mark.parametrize("name", sorted(FLAT))
def test_quad_flat_hessian_is_the_diagonal_of_the_derivative_in_crocopy_and_neither_in_crocoddyl(name):
    cls = om.ACTIVATIONS[name][0]
    for r in (residuals()[0], 2.0 * residuals()[0]):  # inside the basin, where the Hessian is not ~0
        model, data, _, _, Arr = evaluate(crocoddyl, name, r)
        numeric = numeric_hessian(model, data, r)
        assert od.relative_error(Arr, numeric) > 1e-3 and od.relative_error(Arr, np.diag(np.diag(numeric))) > 1e-3
        if not om.implemented(crocopy, cls):
            continue
        model, data, _, _, Arr = evaluate(crocopy, name, r)
        numeric = numeric_hessian(model, data, r)
        assert od.relative_error(Arr, np.diag(np.diag(numeric))) <= od.ND_TOL
        whole = getattr(crocopy, cls)(NR, 1.5, True)
        whole_data = whole.createData()
        whole.calc(whole_data, r)
        whole.calcDiff(whole_data, r)
        assert od.relative_error(np.array(whole_data.Arr), numeric) <= od.ND_TOL


def test_norm_barrier_gauss_newton_is_whole_in_crocopy_and_diagonal_in_crocoddyl():
    r = 0.2 * residuals()[1]  # inside the barrier radius (alpha = 2)
    for lib, whole in ((crocopy, True), (crocoddyl, False)):
        _, _, a, Ar, Arr = evaluate(lib, "norm_barrier", r)
        gauss_newton = np.outer(Ar, Ar) / (2.0 * a)
        assert a > 0.0
        if whole:
            assert od.relative_error(Arr, gauss_newton) <= od.TOL
        else:
            assert od.relative_error(Arr, np.diag(np.diag(gauss_newton))) <= od.TOL
            assert od.relative_error(Arr, gauss_newton) > 1e-2
