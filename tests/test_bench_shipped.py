"""``crocopy bench --vs crocoddyl`` on Crocoddyl's own problems (crocopy.bench.shipped): medians and flags
from synthetic replies, the table, the choice of parts on the command line, the recorder's copies, and
(bench extra) a real run of a shipped example with both libraries."""

from __future__ import annotations

import importlib.util
import sys

import numpy as np
import pytest

from crocopy import cli
from crocopy.bench import compat, shipped
from crocopy.cli import main

HAS_CROCODDYL = importlib.util.find_spec("crocoddyl") is not None


def reply(seconds, iters, cost, calc=1.0, calc_diff=2.0, backward=0.5):
    return {"seconds": seconds, "iter": iters, "cost": cost,
            "phases": {"calc": calc, "calcDiff": calc_diff, "backward": backward}}


def own(iters, cost):
    return {"solver": "SolverFDDP", "iter": iters, "cost": cost, "converged": True, "T": 33}


def test_rows_take_medians_over_rounds_and_flag_a_replay_that_differs():
    solves = {"crocopy": [own(24, 0.5), own(10, 2.0)], "crocoddyl": [own(24, 0.5), own(10, 2.0)]}
    rounds = {
        "crocopy": [[reply(0.24, 24, 0.5, backward=3.0), reply(0.1, 10, 2.0)],
                    [reply(0.48, 24, 0.5, backward=1.0), reply(0.1, 11, 2.1)],
                    [reply(0.36, 24, 0.5, backward=2.0), reply(0.1, 10, 2.0)]],
        "crocoddyl": [[reply(0.024, 24, 0.5, calc=0.5, calc_diff=0.5, backward=1.0), reply(0.01, 10, 2.0)]] * 3,
    }
    first, second = shipped.summarize("quadrotor", solves, rounds)
    assert (first.name, second.name) == ("quadrotor [1]", "quadrotor [2]")
    assert first.libs["crocopy"]["ms_per_iter"] == pytest.approx(15.0)  # median of 10, 20, 15
    assert first.libs["crocopy"]["backward"] == 2.0 and first.libs["crocopy"]["calc_calcDiff"] == 3.0
    assert first.ratio("ms_per_iter") == pytest.approx(15.0) and first.ratio("calc_calcDiff") == pytest.approx(3.0)
    assert first.ratio("backward") == pytest.approx(2.0)
    assert all(lib["replay_ok"] for lib in first.libs.values())
    mismatch = {"crocopy": [own(24, 0.5), own(12, 2.0)], "crocoddyl": solves["crocoddyl"]}
    assert not shipped.summarize("quadrotor", mismatch, rounds)[1].libs["crocopy"]["replay_ok"]
    cells = [c.strip() for c in shipped.format_row(first).strip("|").split("|")]
    assert cells == ["quadrotor [1]", "SolverFDDP", "33", "24 / 0.5", "24 / 0.5", "15", "1", "15.00×", "3.00×",
                     "2.00×"]
    flagged = shipped.format_row(shipped.summarize("q", mismatch, rounds)[1])
    assert "(replay differs from the job's solve)" in flagged


def test_table_lists_rows_then_the_jobs_that_failed():
    solves = {lib: [own(3, 1.0)] for lib in compat.LIBRARIES}
    rounds = {lib: [[reply(0.03, 3, 1.0)]] for lib in compat.LIBRARIES}
    results = [shipped.JobResult("arm", shipped.summarize("arm", solves, rounds)),
               shipped.JobResult("bipedal_walk_ubound", error="crocopy: TypeError: bad argument")]
    text = shipped.format_table(results, repeats=1)
    rows = [line for line in text.splitlines() if line.startswith("| ")]
    assert len(rows) == 2 and rows[1].startswith("| arm | SolverFDDP | 33 |")
    assert all(len(line.split("|")) == len(shipped.HEADER.split("|")) for line in rows)
    assert "- bipedal_walk_ubound: crocopy: TypeError: bad argument" in text
    assert "replayed 1 times" in text


def test_recorder_keeps_copies_of_the_arguments():
    class SolverFDDP:
        iter, cost = 1, 1.0

        def solve(self, xs=(), us=(), maxiter=10):
            xs[0][:] = 7.0  # a solver writing into its guess does not change what was recorded
            return True

    namespace = type(sys)("fake_crocoddyl")
    namespace.SolverFDDP = SolverFDDP
    sink, calls = [], []
    compat.record_solves(namespace, sink, calls)
    guess = [np.zeros(2), np.ones(2)]
    solver = SolverFDDP()
    solver.solve(guess, [np.zeros(1)], maxiter=3)
    ((who, args, kwargs),) = calls
    assert who is solver and kwargs == {"maxiter": 3}
    np.testing.assert_array_equal(args[0][0], np.zeros(2))
    assert guess[0][0] == 7.0 and isinstance(args[0], list)


@pytest.mark.parametrize(("argv", "parts"), [
    ([], ["builders", "shipped", "user", "threads", "mpc", "coverage", "mim"]),
    (["--problems", "pend"], ["builders"]),
    (["--shipped"], ["shipped"]),
    (["--shipped", "arm_manipulation_fwddyn", "--problems", "pend"], ["builders", "shipped"]),
])
def test_the_command_runs_the_parts_asked_for(monkeypatch, capsys, argv, parts):
    ran = []
    monkeypatch.setattr("crocopy.bench.side_by_side.run_vs", lambda *a, **k: ran.append("builders") or "B\n")
    monkeypatch.setattr(shipped, "run_shipped", lambda *a, **k: ran.append("shipped") or "S\n")
    monkeypatch.setattr(compat, "jobs", lambda names=None: list(names or ()))
    monkeypatch.setattr("crocopy.bench.user_residual.run_user_residual_bench",
                        lambda *a, **k: ran.append("user") or "U\n")
    monkeypatch.setattr("crocopy.bench.user_residual.SECTION", "")
    monkeypatch.setattr("crocopy.bench.threads.run_threads_bench", lambda *a, **k: ran.append("threads") or "T\n")
    monkeypatch.setattr("crocopy.bench.threads.SECTION", "")
    monkeypatch.setattr("crocopy.bench.mpc.run_mpc_bench", lambda *a, **k: ran.append("mpc") or "P\n")
    monkeypatch.setattr("crocopy.bench.coverage.run_coverage", lambda *a, **k: ran.append("coverage") or "C\n")
    monkeypatch.setattr("crocopy.bench.command._mim_sections", lambda *a, **k: ran.append("mim") or ["M\n"])
    assert main(["bench", "--vs", "crocoddyl", *argv]) == 0
    assert ran == parts
    expected = {"builders": "B\n", "shipped": "S\n", "user": "U\n\n", "threads": "T\n", "mpc": "P\n",
                "coverage": "C\n", "mim": "M\n"}
    assert capsys.readouterr().out == "\n".join(expected[p] for p in parts) + "\n"


def test_without_crocoddyl_the_shipped_part_names_the_bench_extra(monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "crocoddyl", None)
    assert cli.main(["bench", "--vs", "crocoddyl", "--shipped", "quadrotor_fwddyn"]) == 2
    assert "bench" in capsys.readouterr().err


@pytest.mark.skipif(not HAS_CROCODDYL, reason="needs the bench extra (Crocoddyl 3.2.1)")
def test_an_unknown_job_is_refused_before_any_work(capsys):
    assert main(["bench", "--vs", "crocoddyl", "--shipped", "no-such-script"]) == 2
    assert "no-such-script" in capsys.readouterr().err


@pytest.mark.skipif(not HAS_CROCODDYL, reason="needs the bench extra (Crocoddyl 3.2.1)")
def test_a_shipped_example_is_timed_with_both_libraries(tmp_path, capsys):
    out = tmp_path / "SHIPPED.md"
    assert main(["bench", "--vs", "crocoddyl", "--shipped", "quadrotor_fwddyn", "--repeats", "1",
                 "--out", str(out)]) == 0
    text = out.read_text()
    (row,) = [line for line in text.splitlines() if line.startswith("| quadrotor_fwddyn")]
    cells = [c.strip() for c in row.strip("|").split("|")]
    assert cells[0] == "quadrotor_fwddyn" and cells[1] == "SolverFDDP" and int(cells[2]) > 0
    mine, theirs = (c.split(" / ") for c in cells[3:5])
    assert int(mine[0]) == int(theirs[0]) > 0  # same algorithm, same iterations
    assert float(mine[1]) == pytest.approx(float(theirs[1]), rel=1e-6)
    assert float(cells[5]) > 0 and float(cells[6]) > 0
    assert all(c.endswith("×") and float(c[:-1]) > 0 for c in cells[7:10])
    assert "Not timed" not in text
