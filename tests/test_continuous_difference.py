"""``StateMultibody.diff`` on continuous joints (``q = [cos θ, sin θ]``) is exact at tiny angles, where Pinocchio's
``difference`` returns 0 whenever ``c0 c1 + s0 s1`` rounds above 1, and equals the compiled state difference."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pinocchio as pin
from robots import load

import crocopy
from crocopy.models.rbd.configuration_kernel import state_diff
from crocopy.models.rbd.lowering import lower_model


def exact_angle(c0: float, s0: float, c1: float, s1: float) -> float:
    """The angle from ``(c0, s0)`` to ``(c1, s1)`` (stored doubles, taken as exact), for angles below 1e-6:
    ``atan(y / x) = r (1 - r² / 3)`` with ``y, x`` the exact cross and dot products (the next term is below 1e-24
    relative)."""
    y = Fraction(c0) * Fraction(s1) - Fraction(s0) * Fraction(c1)
    x = Fraction(c0) * Fraction(c1) + Fraction(s0) * Fraction(s1)
    r = y / x
    return float(r * (1 - r * r / 3))


def continuous_pairs(model: pin.Model, n: int, seed: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """``n`` pairs of configurations whose continuous joints differ by angles of 1e-13 to 1e-7."""
    rng = np.random.default_rng(seed)
    pairs = []
    for _ in range(n):
        q0 = pin.integrate(model, pin.neutral(model), rng.uniform(-3.0, 3.0, model.nv))
        q1 = q0.copy()
        for joint in model.joints[1:]:
            if joint.shortname() == "JointModelRUBZ":
                i = joint.idx_q
                a = np.arctan2(q0[i + 1], q0[i]) + rng.choice([-1.0, 1.0]) * 10.0 ** rng.uniform(-13.0, -7.0)
                q1[i], q1[i + 1] = np.cos(a), np.sin(a)
        pairs.append((q0, q1))
    return pairs


def test_continuous_difference_is_exact_at_tiny_angles():
    model = load("kinova")
    state = crocopy.StateMultibody(model)
    rb = lower_model(model)
    joints = [j for j in model.joints[1:] if j.shortname() == "JointModelRUBZ"]
    assert len(joints) == 3
    pinocchio_zero = 0
    for q0, q1 in continuous_pairs(model, 700, seed=4):
        x0, x1 = np.r_[q0, np.zeros(model.nv)], np.r_[q1, np.zeros(model.nv)]
        dx = state.diff(x0, x1)
        into = np.empty(state.ndx)
        state._diff_into(x0, x1, into)
        compiled = np.empty(state.ndx)
        state_diff(rb.jtype, rb.idx_q, rb.idx_v, model.nq, model.nv, x0, x1, compiled)
        np.testing.assert_array_equal(into, dx)
        np.testing.assert_allclose(compiled, dx, rtol=1e-14, atol=0.0)
        reference = pin.difference(model, q0, q1)
        for joint in joints:
            i, k = joint.idx_q, joint.idx_v
            exact = exact_angle(q0[i], q0[i + 1], q1[i], q1[i + 1])
            assert dx[k] != 0.0 or exact == 0.0
            assert abs(dx[k] - exact) <= 3e-16 + 1e-12 * abs(exact)
            pinocchio_zero += reference[k] == 0.0 and exact != 0.0
        others = [k for k in range(model.nv) if all(k != j.idx_v for j in joints)]
        np.testing.assert_array_equal(dx[others], reference[others])
    assert pinocchio_zero > 0  # the draws include angles Pinocchio reads as zero
