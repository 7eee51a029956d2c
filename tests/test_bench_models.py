"""The model-level comparison of ``crocopy bench --models`` (run here crocopy against itself)."""

import numpy as np

import crocopy
from crocopy.bench.node_eval import FIELDS, compare_problem, model_kind, node_differences
from crocopy.bench.side_by_side import build_problem


def test_identical_problems_have_no_differences_and_a_perturbed_one_shows_up():
    ours, xs, us = build_problem("pend", crocopy)
    other, _, _ = build_problem("pend", crocopy)
    diffs = node_differences((ours, other), xs, us)
    assert set(diffs) == {"DifferentialActionModelFreeFwdDynamics", "DifferentialActionModelFreeFwdDynamics (terminal)"}
    assert diffs["DifferentialActionModelFreeFwdDynamics"]["nodes"] == ours.T
    assert all(v == 0.0 for d in diffs.values() for k, v in d.items() if k != "nodes")
    item = other.runningModels[0].differential.costs.costs["state"]
    item.weight *= 2.0
    diffs = node_differences((ours, other), xs, us)
    changed = diffs["DifferentialActionModelFreeFwdDynamics"]
    assert changed["cost"] > 1e-8 and max(changed[k] for k in FIELDS) > 1e-8


def test_report_section_names_the_bars():
    text, met = compare_problem("pend", crocopy, crocopy, repeats=2)
    assert "bar ≤ 2×" in text and "| model kind |" in text
    assert isinstance(met, bool)
    assert model_kind(crocopy.ActionModelLQR.Random(2, 1)) == "ActionModelLQR"
    assert np.isfinite(float(text.split("ratio ")[1].split("×")[0]))
