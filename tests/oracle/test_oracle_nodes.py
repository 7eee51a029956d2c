"""Oracle: crocopy's nodes against Crocoddyl's, number by number (bench extra).

Every residual × every dynamics kind (free; contact with 3D and 6D contacts; impulse with 3D and 6D
impulses; free and contact inverse dynamics) × every integrator of :data:`oracle_models.INTEGRATORS`
(Euler, RK2/3/4, and with control parametrizations PolyZero/PolyOne/PolyTwoRK on a subset of
residuals; :data:`oracle_models.INVDYN_INTEGRATORS` for inverse dynamics), running and terminal, at a
random state and control.  Each node holds the residual as a cost under every activation crocopy implements
(plus the default activation and an inactive item), as an equality (terminal and running-only) and
as an inequality constraint.  The same model is built through the same API in both libraries
(:func:`oracle_models.node`); Crocoddyl runs as a black box.

Every number (dynamics, cost, derivatives, each stage's and each item's data) must equal Crocoddyl's
to ``TOL = 1e-10`` (relative), except where a declared deviation (oracle_deviations.DEVIATIONS)
explains the difference:

- a Jacobian that differs is accepted only when, on this very case, Crocoddyl's disagrees with the
  central differences of Crocoddyl's own values and crocopy's agrees with those of crocopy's;
- a value that differs must be a declared value or terminal deviation, and crocopy's Jacobians of it
  must agree with crocopy's numerical derivatives;
- a Hessian or activation derivative that differs needs an accepted difference in the same item.

Terminal nodes have no dynamics: ``xnext``, ``Fx``, ``Fu`` and the Runge-Kutta stages after the
first are left out there (Crocoddyl's Euler writes ``Fx = I``, its RK leaves ``Fx = 0``).
"""

from __future__ import annotations

import pytest

crocoddyl = pytest.importorskip("crocoddyl")

import oracle_deviations as od  # noqa: E402
import oracle_models as om  # noqa: E402

import crocopy  # noqa: E402

pytestmark = pytest.mark.usefixtures("bench_crocoddyl")

ACTIVATIONS = tuple(name for name, (cls, _) in om.ACTIVATIONS.items() if om.implemented(crocopy, cls))
COSTS = (*ACTIVATIONS, "default")
CASES = [
    od.Case(kind, name, integrator, terminal)
    for kind in om.ALL
    for name, spec in om.RESIDUALS.items()
    if kind in spec.kinds and om.implemented(crocopy, spec.cls)
    for integrator in ((None,) if om.DYNAMICS[kind].impulse
                       else [i for i in om.INTEGRATORS if om.crossed(i, name, kind)])
    for terminal in ((False,) if om.DYNAMICS[kind].impulse else (False, True))
]
TERMINAL_SKIPPED = ("xnext", "Fx", "Fu")


def _compared(key: str, case: od.Case) -> bool:
    if not case.terminal:
        return True
    if key in TERMINAL_SKIPPED:
        return False
    return not (key.startswith("differential[") and not key.startswith("differential[0]."))


def _evaluate(case: od.Case):
    models = {lib.__name__: om.node(lib, case.kind, case.residual, case.integrator, ACTIVATIONS)
              for lib in (crocopy, crocoddyl)}
    x, u = om.sample(case.kind, models["crocopy"].nu, 1)
    u = None if case.terminal else u
    found = {name: om.evaluate(model, x, u, COSTS) for name, model in models.items()}
    return models, found, x, u


def _terminal_rows(key: str, mine, theirs, case: od.Case):
    """Terminal g/h rows (a declared gap): Crocoddyl keeps the ng_T/nh_T terminal rows, crocopy all ng/nh,
    the terminal ones first and zeros after them.  Returns crocopy's terminal rows, or ``mine`` unchanged."""
    _, last = om.split_key(key)
    if not (case.terminal and last in ("g", "h", "Gx", "Gu", "Hx", "Hu") and od.item_of(key) == ""
            and od.deviations(case, "gap")):
        return mine
    rows = theirs.shape[0] if theirs.ndim == mine.ndim else 1  # Crocoddyl returns a 1-row matrix flat
    assert not mine[rows:].any(), f"{key}: crocopy's rows after the {rows} terminal ones are not zero"
    return mine[:rows]


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_node_equals_crocoddyl_or_a_proven_deviation(case):
    models, found, x, u = _evaluate(case)
    mine, theirs = found["crocopy"], found["crocoddyl"]
    missing = [k for k in theirs if _compared(k, case) and k not in mine]
    assert not missing, f"crocopy lacks {missing[:5]}"
    diff = {}
    for key, b in theirs.items():
        if not _compared(key, case):
            continue
        a = _terminal_rows(key, mine[key], b, case)
        if a.shape != b.shape and a.squeeze().shape == b.squeeze().shape:  # Crocoddyl returns a 1-row matrix flat
            a = a.reshape(b.shape)
        assert a.shape == b.shape, f"{key}: shape {a.shape} vs Crocoddyl's {b.shape}"
        err = od.relative_error(a, b)
        if err > od.TOL:
            diff[key] = err
    if not diff:
        return
    explained: set[str] = set()
    # values: declared value/terminal deviations only; crocopy's Jacobians of them checked against numdiff
    values = [k for k in diff if om.split_key(k)[1] not in od.DERIVATIVES | od.HESSIANS | od.ACTIVATION_KEYS]
    if values:
        declared = od.deviations(case, "value") + od.deviations(case, "terminal")
        assert declared, f"values differ from Crocoddyl's with no declared deviation: {_top(diff, values)}"
        explained.update(values)
    # terminal nodes have no control: its Jacobians may differ where a terminal deviation is declared
    if case.terminal and od.deviations(case, "terminal"):
        explained.update(k for k in diff if om.split_key(k)[1] in od.CONTROL_JACOBIANS)
    # Jacobians: proven on this case (later Runge-Kutta stages: by the same key in the first stage,
    # their Jacobians being taken with respect to the stage's own state)
    later = [k for k in diff if om.split_key(k)[1] in od.DERIVATIVES and od.stage(k) > 0 and k not in explained]
    jacobians = [k for k in diff if om.split_key(k)[1] in od.DERIVATIVES and od.stage(k) == 0 and k not in explained]
    jacobians += sorted({od.first_stage(k) for k in later} - set(jacobians))
    own = [k for k in jacobians if om.value_key(k) in diff]  # of a value that differs: crocopy side only
    proofs = od.prove(models, found, case, x, u, jacobians, COSTS, crocoddyl_too=bool(set(jacobians) - set(own)))
    for proof in proofs:
        assert proof.crocopy_right, f"{proof.key}: crocopy's Jacobian is {proof.crocopy:.2e} off its numdiff"
        if proof.key in own:
            explained.add(proof.key)
            continue
        assert od.deviations(case, "derivative"), f"{proof.key} differs ({diff[proof.key]:.2e}), nothing declared"
        assert proof.crocoddyl_wrong, (
            f"{proof.key} differs ({diff[proof.key]:.2e}) but Crocoddyl's Jacobian is only {proof.crocoddyl:.2e} off "
            f"its own numdiff (crocopy's: {proof.crocopy:.2e})"
        )
        explained.add(proof.key)
    explained.update(k for k in later if od.first_stage(k) in explained)
    # activation derivatives: the item's residual differs, or its activation has a declared deviation
    for key in (k for k in diff if om.split_key(k)[1] in od.ACTIVATION_KEYS):
        assert od.item_of(key) + "residual.r" in explained or _activation_item(case, key), (
            f"{key} differs ({diff[key]:.2e}) and {od.activation_of(key)} has no declared Hessian deviation")
        explained.add(key)
    # Hessians: follow an explained difference of the same item (anywhere, for the stacked totals)
    for key in (k for k in diff if om.split_key(k)[1] in od.HESSIANS):
        item = od.item_of(key)
        assert any(od.item_of(k) == item or not item for k in explained) or _activation_item(case, key), (
            f"{key} differs ({diff[key]:.2e}) while its item's Jacobians and activation agree")
    unexplained = set(diff) - explained - {k for k in diff if om.split_key(k)[1] in od.HESSIANS}
    assert not unexplained, _top(diff, unexplained)


def _activation_item(case: od.Case, key: str) -> bool:
    return any(od.activation_of(key) in d.activations for d in od.deviations(case, "activation"))


def _top(diff: dict[str, float], keys) -> str:
    return ", ".join(f"{k}: {diff[k]:.2e}" for k in sorted(keys, key=lambda k: -diff[k])[:6])
