"""Solver settings are checked on assignment: a value out of range, NaN or of the wrong type is refused with an error
naming the setting, what it must be and what was given; valid values (NumPy scalars included) are kept with the
setting's type, and a solve runs with them."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from solver_problems import integrator_problem
from sqp_problems import random_lq

import crocopy
from crocopy.validation import ArgumentTypeError

SQP_SETTINGS = ("termination_tolerance", "use_filter_line_search", "filter_size", "mu_dynamic",
                "extra_iteration_for_last_kkt")
CSQP_SETTINGS = SQP_SETTINGS + (
    "mu_constraint", "lag_mul_inf_norm_coef", "max_qp_iters", "eps_abs", "eps_rel", "sigma", "alpha", "rho_min",
    "rho_max", "rho_update_interval", "adaptive_rho_tolerance", "equality_qp_initial_guess", "reset_y", "reset_rho",
    "update_rho_with_heuristic", "remove_reg", "with_qp_callbacks", "max_solve_time",
)

REFUSED = [
    # (solver, setting, value, exception, words of the message)
    ("SolverSQP", "termination_tolerance", -1e-6, ValueError, ">= 0.0, got -1e-06"),
    ("SolverSQP", "termination_tolerance", math.nan, ValueError, "finite number, got nan"),
    ("SolverSQP", "filter_size", 0, ValueError, "filter_size must be >= 1, got 0"),
    ("SolverSQP", "filter_size", 2.0, ArgumentTypeError, "filter_size must be an integer, got float"),
    ("SolverSQP", "use_filter_line_search", "yes", ArgumentTypeError, "use_filter_line_search must be a bool"),
    ("SolverSQP", "mu_dynamic", math.inf, ValueError, "mu_dynamic must be a finite number"),
    ("SolverCSQP", "mu_constraint", math.nan, ValueError, "mu_constraint must be a finite number"),
    ("SolverCSQP", "max_qp_iters", -5, ValueError, "max_qp_iters must be non-negative, got -5"),
    ("SolverCSQP", "eps_abs", -1.0, ValueError, "eps_abs must be >= 0.0, got -1.0"),
    ("SolverCSQP", "eps_rel", "1e-4", ArgumentTypeError, "eps_rel must be a real number, got str"),
    ("SolverCSQP", "sigma", -1e-6, ValueError, "sigma must be >= 0.0"),
    ("SolverCSQP", "alpha", 0.0, ValueError, "alpha must be > 0.0, got 0.0"),
    ("SolverCSQP", "alpha", 2.0, ValueError, "alpha must be < 2.0, got 2.0"),
    ("SolverCSQP", "rho_min", 0.0, ValueError, "rho_min must be > 0.0"),
    ("SolverCSQP", "rho_max", -1.0, ValueError, "rho_max must be > 0.0"),
    ("SolverCSQP", "rho_update_interval", 0, ValueError, "rho_update_interval must be >= 1, got 0"),
    ("SolverCSQP", "adaptive_rho_tolerance", -5, ValueError, "adaptive_rho_tolerance must be > 0.0"),
    ("SolverCSQP", "reset_rho", 2, ArgumentTypeError, "reset_rho must be a bool"),
    ("SolverCSQP", "max_solve_time", -1.0, ValueError, "max_solve_time must be >= 0.0"),
    ("SolverCSQP", "lag_mul_inf_norm_coef", math.nan, ValueError, "lag_mul_inf_norm_coef must be a finite number"),
    ("SolverFDDP", "th_acceptNegStep", math.nan, ValueError, "th_acceptNegStep must be a finite number"),
    ("SolverBoxFDDP", "th_acceptNegStep", -2.0, ValueError, "th_acceptNegStep must be >= 0.0"),
    ("SolverBoxFDDP", "compat_crocoddyl", "true", ArgumentTypeError, "compat_crocoddyl must be a bool"),
    ("SolverKKT", "x_reg", -1.0, ValueError, "x_reg must be >= 0.0"),
    ("SolverKKT", "u_reg", math.inf, ValueError, "u_reg must be a finite number"),
    ("SolverDDP", "feasNorm", 2, ValueError, "feasNorm must be a FeasibilityNorm (LInf, L1), got 2"),
    ("SolverDDP", "feasNorm", "L1", ArgumentTypeError, "feasNorm must be a FeasibilityNorm"),
    ("SolverIntro", "rho", 1.0, ValueError, "rho must be < 1.0, got 1.0"),
    ("SolverIntro", "rho", -0.1, ValueError, "rho must be >= 0.0, got -0.1"),
    ("SolverIntro", "th_feas", -1e-4, ValueError, "th_feas must be >= 0.0"),
    ("SolverIntro", "zero_upsilon", "no", ArgumentTypeError, "zero_upsilon must be a bool"),
    ("SolverIntro", "th_rank", math.nan, ValueError, "th_rank must be a finite number"),
    ("SolverIntro", "u_reg", -1.0, ValueError, "u_reg must be >= 0.0"),
    ("SolverProjection", "th_rank", math.nan, ValueError, "th_rank must be a finite number"),
    ("SolverProjection", "th_x0", -1e-6, ValueError, "th_x0 must be >= 0.0"),
    ("SolverProjection", "sigma", -1.0, ValueError, "sigma must be >= 0.0"),
    ("SolverHDDP", "rank_scale", "global", ValueError, "rank_scale must be one of ('task', 'peak'), got 'global'"),
    ("SolverHDDP", "th_worse", math.inf, ValueError, "th_worse must be a finite number"),
    ("SolverHDDP", "max_reg_increases", 1.5, ArgumentTypeError, "max_reg_increases must be an integer"),
    ("SolverHDDP", "lambda0", -1e-9, ValueError, "lambda0 must be >= 0.0"),
    ("SolverHDDP", "warm_steps", None, ArgumentTypeError, "warm_steps must be a bool"),
]


def _solver(name: str, problem=None):
    problem = problem if problem is not None else random_lq(seed=1)
    if name == "SolverHDDP":
        return crocopy.SolverHDDP(integrator_problem(), [["state", "goal"], ["control"]])
    return getattr(crocopy, name)(problem)


@pytest.mark.parametrize(("solver", "setting", "value", "error", "words"), REFUSED)
def test_a_bad_setting_is_refused_by_name_and_the_old_value_kept(solver, setting, value, error, words):
    s = _solver(solver)
    before = getattr(s, setting)
    with pytest.raises(error, match=words.replace("(", r"\(").replace(")", r"\)").replace(".", r"\.")):
        setattr(s, setting, value)
    assert getattr(s, setting) == before


@pytest.mark.parametrize("solver", ["SolverSQP", "SolverCSQP"])
def test_the_defaults_assigned_back_keep_their_values_and_types(solver):
    s, fresh = _solver(solver), _solver(solver)
    names = SQP_SETTINGS if solver == "SolverSQP" else CSQP_SETTINGS
    for name in names:
        value = getattr(fresh, name)
        setattr(s, name, value)
        assert getattr(s, name) == value and type(getattr(s, name)) is type(value), name
    for name in ("filter_size", "max_qp_iters", "rho_update_interval"):
        if name in names:
            assert isinstance(getattr(s, name), int), name


def test_numpy_scalars_are_accepted_with_the_settings_types():
    s = _solver("SolverCSQP")
    s.max_qp_iters, s.filter_size, s.eps_abs, s.reset_y = np.int64(50), np.int32(3), np.float32(1e-5), np.bool_(True)
    assert (type(s.max_qp_iters), type(s.filter_size), type(s.eps_abs), type(s.reset_y)) == (int, int, float, bool)
    assert s.max_qp_iters == 50 and s.filter_size == 3 and s.reset_y is True
    s.feasNorm = crocopy.FeasibilityNorm.L1
    assert s.feasNorm is crocopy.FeasibilityNorm.L1
    s.feasNorm = 0
    assert s.feasNorm is crocopy.FeasibilityNorm.LInf


def test_a_negative_merit_weight_stays_allowed_and_a_solve_runs_with_checked_settings():
    """A negative ``mu_dynamic`` selects the multiplier-weighted merit: it is a setting, not an error."""
    problem = random_lq(seed=3, rows=lambda t: (np.zeros((2, 3)), np.eye(2), -0.3 * np.ones(2), 0.3 * np.ones(2)))
    s = crocopy.SolverCSQP(problem)
    s.mu_dynamic, s.mu_constraint = -1.0, -1.0
    s.eps_abs, s.eps_rel, s.max_qp_iters, s.alpha = np.float64(1e-8), 0.0, np.int64(5000), 1.5
    assert s.solve(maxiter=20)
    assert s.KKT <= s.termination_tolerance


@settings(max_examples=40, deadline=None)
@given(value=st.floats(allow_nan=True, allow_infinity=True))
def test_the_admm_relaxation_is_kept_exactly_in_its_open_interval(value):
    s = _solver("SolverCSQP")
    if 0.0 < value < 2.0:
        s.alpha = value
        assert s.alpha == value
    else:
        with pytest.raises(ValueError, match="alpha must be"):
            s.alpha = value
        assert s.alpha == 1.6
