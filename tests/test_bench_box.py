"""Self-sensitivity helpers of ``crocopy bench --box-parity`` (crocopy only, no Crocoddyl needed)."""

import numpy as np
import pytest

import crocopy
from crocopy.bench.box_parity import (
    CHAOS_EPS,
    PERTURBATIONS,
    Replay,
    Trace,
    first_divergence,
    is_chaotic,
    perturb_guess,
    self_spread,
    solve_trace,
    verdict,
)


def trace(costs, steps=None):
    steps = steps or [1.0] * len(costs)
    return Trace(len(costs), costs[-1], True, 0.0, [(c, 1.0, a, i) for i, (c, a) in enumerate(zip(costs, steps))])


def test_perturbation_is_relative_reproducible_and_checked():
    state = crocopy.StateVector(3)
    xs = [np.array([1e3, 0.0, -2.0]), np.zeros(3)]
    us = [np.array([5e2, 1e-3])]
    same = perturb_guess([state] * 2, xs, us, 0.0, 1)
    assert all(np.array_equal(a, b) and a is not b for a, b in zip(same[0] + same[1], xs + us))
    xs_p, us_p = perturb_guess([state] * 2, xs, us, 1e-8, 7)
    assert all(0.0 < np.abs(a - b).max() < 1e-5 for a, b in zip(xs_p + us_p, xs + us))
    # same draws on a guess scaled down to |x|∞ = 1, |u_0| = 1: the steps scale with max(1, |x|∞), max(1, |u_j|)
    unit_x, unit_u = perturb_guess([state] * 2, [xs[0] / 1e3, xs[1]], [np.array([1.0, 1e-3])], 1e-8, 7)
    assert np.allclose(xs_p[0] - xs[0], 1e3 * (unit_x[0] - xs[0] / 1e3), rtol=1e-6)
    du, du_unit = us_p[0] - us[0], unit_u[0] - np.array([1.0, 1e-3])
    assert du[0] == pytest.approx(5e2 * du_unit[0], rel=1e-6) and du[1] == pytest.approx(du_unit[1], rel=1e-6)
    again = perturb_guess([state] * 2, xs, us, 1e-8, 7)
    other = perturb_guess([state] * 2, xs, us, 1e-8, 8)
    assert all(np.array_equal(a, b) for a, b in zip(xs_p + us_p, again[0] + again[1]))
    assert not np.array_equal(xs_p[0], other[0][0])
    with pytest.raises(ValueError, match="states"):
        perturb_guess([state], xs, us, 1e-8, 0)
    with pytest.raises(ValueError, match="eps"):
        perturb_guess([state] * 2, xs, us, -1.0, 0)


def test_perturbation_stays_on_the_manifold():
    import pinocchio as pin

    state = crocopy.StateMultibody(pin.buildSampleModelHumanoidRandom())  # free flyer: quaternion in q[3:7]
    x = state.rand()
    (xp,), _ = perturb_guess([state], [x], [], 1e-9, 3)
    assert abs(np.linalg.norm(xp[3:7]) - 1.0) < 1e-14
    assert 1e-11 < np.abs(state.diff(x, xp)).max() < 1e-7
    (x0,), _ = perturb_guess([state], [x], [], 0.0, 3)
    assert np.array_equal(x0, x)  # exact copy, not x ⊕ 0


def test_self_spread_and_chaos_verdict():
    base = trace([10.0, 5.0, 2.0, 1.0])
    runs = [
        (1e-12, trace([10.0, 5.0, 2.0, 1.0 + 1e-9])),
        (1e-12, trace([10.0, 5.0, 2.0, 1.0 + 1e-8])),
        (1e-10, trace([10.0, 5.0, 2.5, 1.5, 1.2], [1.0, 1.0, 0.5, 1.0, 1.0])),
    ]
    spread = self_spread(base, runs)
    assert spread.iters == {1e-12: (4, 4), 1e-10: (5, 5)}
    assert spread.cost[1e-12] == pytest.approx(1e-8) and spread.cost[1e-10] == pytest.approx(0.2)
    assert spread.divergence == {1e-12: None, 1e-10: 2}
    assert not is_chaotic(spread, 1e-12) and is_chaotic(spread, 1e-10)
    assert is_chaotic(self_spread(base, [(1e-12, trace([10.0, 5.0, 2.0, 1.0, 1.0]))]), 1e-12)  # iterations only
    assert is_chaotic(self_spread(base, [(1e-12, trace([10.0, 5.0, 2.0, np.inf]))]), 1e-12)  # blow-up
    with pytest.raises(KeyError, match="eps"):
        is_chaotic(spread, 1e-14)
    assert CHAOS_EPS in {e for e, _ in PERTURBATIONS}


def test_divergence_ignores_the_iteration_entry_but_sees_the_step():
    a = trace([3.0, 2.0, 1.0])
    b = Trace(3, 1.0, True, 0.0, [(c, s, x, 99) for c, s, x, _ in a.log])
    assert first_divergence(a, b) is None
    assert first_divergence(a, trace([3.0, 2.0, 1.0], [1.0, 0.5, 1.0])) == 1


def test_perturbed_solve_of_a_stable_row_stays_on_the_unperturbed_iterates():
    base = solve_trace(crocopy, "quad-goal", "boxfddp", maxiter=4, compat=True)
    pert = solve_trace(crocopy, "quad-goal", "boxfddp", maxiter=4, compat=True, perturbation=(1e-12, 1))
    assert [row[3] for row in pert.log] == list(range(4))
    assert first_divergence(base, pert) is None
    assert 0.0 < abs(pert.cost - base.cost) < 1e-9 * abs(base.cost)


def test_replay_classifies_missed_steps():
    replay = Replay([1e-12, 0.5, 3e-11, np.inf, 2e-7], [True, False, True, False, False], {1: 0.9, 3: 1e-9})
    assert replay.misses() == [1, 3, 4] and replay.step_mismatches == [1, 3, 4]
    assert replay.matched_error() == 3e-11 and replay.worst == (3, np.inf)
    assert replay.unexplained() == [3] and replay.unchecked() == [4]
    assert Replay().worst == (None, 0.0) and Replay().matched_error() == 0.0


def test_verdict_separates_met_chaotic_and_real_differences():
    ref = trace([10.0, 5.0, 2.0, 1.0])
    off = trace([10.0, 5.0, 2.1, 1.3])
    chaotic = self_spread(ref, [(CHAOS_EPS, trace([10.0, 5.0, 2.2, 1.5]))])
    stable = self_spread(ref, [(CHAOS_EPS, trace([10.0, 5.0, 2.0, 1.0]))])
    explained = Replay([1e-12, 1e-12, 0.05, 1e-11], [True, True, True, True], {2: 0.1})
    real = Replay([1e-12, 1e-12, 0.05, 1e-11], [True, True, True, True], {2: 1e-13})
    assert verdict(ref, trace([10.0, 5.0, 2.0, 1.0 + 1e-9]), chaotic, real) == "bar met"
    text = verdict(ref, off, chaotic, explained)
    assert text.startswith("ill-conditioned (chaotic); no algorithmic difference found") and "iteration 2" in text
    assert verdict(ref, off, chaotic, real).startswith("REAL DIFFERENCE at iterations [2]")
    assert verdict(ref, off, stable, explained).startswith("unexplained")
    assert verdict(ref, off, chaotic, None).startswith("ill-conditioned (chaotic):")
    assert verdict(ref, off, None, None).startswith("not classified")
