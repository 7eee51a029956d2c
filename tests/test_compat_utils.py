"""Crocoddyl's helpers: save* files, the stop-watch profiler, ``DisplayAbstract``, and the
clear error for a Crocoddyl name crocopy does not implement."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import crocopy
from crocopy.crocoddyl_names import CROCODDYL_NAMES
from crocopy.solvers import stopwatch


def _solved():
    model = crocopy.ActionModelLQR(3, 2)
    problem = crocopy.ShootingProblem(np.ones(3), [model] * 5, model)
    solver = crocopy.SolverFDDP(problem)
    logger = crocopy.CallbackLogger()
    solver.setCallbacks([logger])
    solver.solve()
    return solver, logger


def _load(path):
    with open(path, "rb") as f:
        return pickle.load(f)


def test_save_oc_solution_convergence_and_logfile(tmp_path):
    solver, logger = _solved()
    crocopy.saveOCSolution(tmp_path / "oc.pkl", solver.xs, solver.us)
    content = _load(tmp_path / "oc.pkl")
    assert set(content) == {"xs", "us", "ks", "Ks"} and content["ks"] is None and content["Ks"] is None
    assert type(content["xs"]) is list and all(type(x) is np.ndarray for x in content["xs"])
    for saved, x in zip(content["xs"], solver.xs):
        np.testing.assert_array_equal(saved, x)
    crocopy.saveOCSolution(tmp_path / "gains.pkl", solver.xs, solver.us, solver.k, solver.K)
    content = _load(tmp_path / "gains.pkl")
    np.testing.assert_array_equal(content["Ks"][2], solver.K[2])
    np.testing.assert_array_equal(content["ks"][0], solver.k[0])

    crocopy.saveConvergence(tmp_path / "conv.pkl", [3.0, 1.0], [1e-9, 1e-8], [1.0, 2.0], [0.1], [0.2], [1.0, 0.5])
    assert _load(tmp_path / "conv.pkl") == {
        "costs": [3.0, 1.0], "muLM": [1e-9, 1e-8], "muV": [1.0, 2.0], "gamma": [0.1], "theta": [0.2],
        "alpha": [1.0, 0.5],
    }

    crocopy.saveLogfile(tmp_path / "log.pkl", logger)
    log = _load(tmp_path / "log.pkl")
    assert set(log) == {"xs", "us", "fs", "steps", "iters", "costs", "primal-reg", "dual-reg", "stops", "grads"}
    assert log["iters"] == logger.iters and log["costs"] == logger.costs and log["primal-reg"] == logger.pregs
    assert len(log["fs"]) == len(logger.fs) and log["fs"][-1][0].shape == (3,)
    np.testing.assert_array_equal(log["us"][-1], solver.us[-1])


def test_stop_watch_times_solver_phases_only_when_enabled(capsys):
    stopwatch.stop_watch_reset_all()
    _solved()
    with pytest.raises(KeyError, match="SolverDDP::solve"):
        crocopy.stop_watch_get_total_time("SolverDDP::solve")
    crocopy.enable_profiler()
    try:
        solver, _ = _solved()
    finally:
        crocopy.disable_profiler()
    total = crocopy.stop_watch_get_total_time("SolverDDP::solve")
    assert total > 0.0
    inner = crocopy.stop_watch_get_total_time("SolverFDDP::tryStep")
    assert 0.0 < inner < total
    low, avg, high = (
        crocopy.stop_watch_get_min_time("SolverDDP::backwardPass"),
        crocopy.stop_watch_get_average_time("SolverDDP::backwardPass"),
        crocopy.stop_watch_get_max_time("SolverDDP::backwardPass"),
    )
    assert 0.0 < low <= avg <= high
    crocopy.stop_watch_report(4)
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("*** PROFILING RESULTS [ms]")
    row = next(line.split() for line in lines if line.startswith("SolverDDP::solve"))
    assert int(row[5]) == 1 and float(row[6]) == pytest.approx(1e3 * total, abs=1e-4)
    _solved()
    assert crocopy.stop_watch_get_total_time("SolverDDP::solve") == total
    crocopy.stop_watch_reset_all()
    with pytest.raises(KeyError):
        crocopy.stop_watch_get_average_time("SolverDDP::solve")


def test_profiled_functions_keep_their_results_and_exceptions():
    def boom():
        raise RuntimeError("boom")

    timed = stopwatch.profiled("test::boom", boom)
    crocopy.enable_profiler()
    try:
        with pytest.raises(RuntimeError, match="boom"):
            timed()
        assert stopwatch.profiled("test::add", lambda a, b=1: a + b)(2, b=3) == 5
    finally:
        crocopy.disable_profiler()
    assert crocopy.stop_watch_get_max_time("test::boom") >= 0.0
    assert timed.__name__ == "boom"


class RecordingDisplay(crocopy.DisplayAbstract):
    """A display written from Python that records what it is asked to show."""

    def __init__(self, robot, rate=-1, freq=1):
        crocopy.DisplayAbstract.__init__(self, robot, rate, freq)
        self.shown = []

    def display(self, xs, us=(), rs=(), ps=(), pds=(), fs=(), ss=(), dts=(), factor=1.0):
        self.shown.append((list(xs), list(us), list(dts), factor))

    def setVisibility(self, name, status):
        pass

    def displayFramePoses(self, ps):
        pass

    def displayContactForce(self, f):
        pass

    def displayThrustForce(self, f):
        pass


def test_display_abstract_subclass_plays_a_solver():
    with pytest.raises(TypeError):
        crocopy.DisplayAbstract(None)
    dam = crocopy.DifferentialActionModelLQR.Random(2, 2)
    model = crocopy.IntegratedActionModelEuler(dam, 0.05)
    solver = crocopy.SolverFDDP(crocopy.ShootingProblem(np.ones(4), [model] * 3, model))
    solver.solve()
    shown = RecordingDisplay("robot", freq=2)
    assert (shown.robot, shown.rate, shown.freq) == ("robot", -1.0, 2)
    shown.displayFromSolver(solver, factor=2.0)
    xs, us, dts, factor = shown.shown[0]
    assert len(xs) == 4 and len(us) == 3 and dts == [0.05] * 3 and factor == 2.0
    assert shown.getTimeSequenceFromSolver(solver) == pytest.approx([0.0, 0.05, 0.1, 0.15])
    with pytest.raises(ValueError, match="freq"):
        RecordingDisplay("robot", freq=0)
    assert issubclass(crocopy.MeshcatDisplay, crocopy.DisplayAbstract)


def test_crocoddyl_names_crocopy_lacks_fail_clearly():
    missing = sorted(n for n in CROCODDYL_NAMES if not hasattr(crocopy, n))
    assert missing, "the test needs a Crocoddyl name that crocopy does not implement"
    for name in missing:
        with pytest.raises(AttributeError, match=f"crocopy does not implement Crocoddyl's {name} "):
            getattr(crocopy, name)
    with pytest.raises(AttributeError, match="module 'crocopy' has no attribute 'NotACrocoddylName'") as info:
        crocopy.NotACrocoddylName  # noqa: B018
    assert "does not implement" not in str(info.value)


def test_crocoddyl_names_list_is_names_only_and_covers_what_crocopy_implements():
    assert all(name.isidentifier() and not name.startswith("_") for name in CROCODDYL_NAMES)
    for name in ("SolverFDDP", "ShootingProblem", "ActivationModelQuadFlatExp", "saveOCSolution", "StateNumDiff",
                 "FeasibilityNorm", "DisplayAbstract", "stop_watch_report", "MeshcatDisplay"):
        assert name in CROCODDYL_NAMES and hasattr(crocopy, name)
