"""The ``crocopy`` command: exit statuses, usage errors caught before any work, outputs, first-run notice.

In-process through ``main(argv)`` (which returns the exit status) on the fast problems, plus a few
runs of the installed ``crocopy`` script to check the process's exit status itself.
"""

import os
import re
import subprocess
import sys

import numpy as np
import pytest

import crocopy
from crocopy.cli import EXIT_CONVERGED, EXIT_NOT_CONVERGED, EXIT_USAGE, AfterFirstIteration, main, warm_up_kernels
from crocopy.problems import registry

CROCOPY = os.path.join(os.path.dirname(sys.executable), "crocopy")


@pytest.fixture
def no_work(monkeypatch):
    """Fail the test if a problem gets built (usage errors must be caught before)."""

    def build(self, *args, **kwargs):
        raise AssertionError(f"problem {self.name} was built before the usage error was reported")

    monkeypatch.setattr(registry.ProblemSpec, "build", build)


def _usage_error(capsys, argv: list[str], command: str) -> str:
    assert main(argv) == EXIT_USAGE
    out, err = capsys.readouterr()
    assert out == ""
    assert err.startswith(f"usage: crocopy {command} ") and f"crocopy {command}: error: " in err
    return err


def test_version(capsys):
    assert main(["--version"]) == 0
    assert crocopy.__version__ in capsys.readouterr().out


def test_help_documents_the_exit_statuses(capsys):
    assert main(["solve", "--help"]) == 0
    out = " ".join(capsys.readouterr().out.split())
    assert "0 success (solve: converged), 1 solve did not converge, 2 usage error" in out


def test_list_names_every_registered_problem(capsys):
    assert main(["list"]) == 0
    out = capsys.readouterr().out
    for name in registry.names():
        assert re.search(rf"^{re.escape(name)} +T=", out, re.M)


def test_unconverged_solve_exits_1_and_writes_plot_and_html(tmp_path, capsys):
    html, png = tmp_path / "pend.html", tmp_path / "conv.png"
    argv = ["solve", "pend", "--solver", "fddp", "--quiet", "--maxiter", "5", "--html", str(html), "--plot", str(png)]
    assert main(argv) == EXIT_NOT_CONVERGED
    out = capsys.readouterr().out
    assert "pend: SolverFDDP did not converge (maximum number of iterations (5) reached) after 5 iterations" in out
    assert f"convergence plot written to {png}\n" in out
    assert html.stat().st_size > 10_000 and "<html" in html.read_text()[:2000].lower()
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_converged_solve_exits_0_with_the_reference_iterations(tmp_path, capsys):
    assert main(["solve", "pend", "--quiet", "--no-html"]) == EXIT_CONVERGED
    out = capsys.readouterr().out
    ref = registry.get("pend").reference["boxfddp"]
    assert f"pend: SolverBoxFDDP converged after {ref.iters} iterations" in out
    assert not list(tmp_path.iterdir())


def test_plot_without_suffix_gets_png_and_its_name_is_printed(tmp_path, capsys):
    target = tmp_path / "convergence"
    assert main(["solve", "quad-goal", "--quiet", "--no-html", "--maxiter", "2", "--plot", str(target)]) == 1
    assert f"convergence plot written to {target}.png\n" in capsys.readouterr().out
    assert (tmp_path / "convergence.png").read_bytes()[:4] == b"\x89PNG" and not target.exists()


@pytest.mark.usefixtures("no_work")
@pytest.mark.parametrize("argv", [["solve", "jmup"], ["solve", "no-such-problem", "--no-html"]])
def test_unknown_problem_is_rejected_with_the_choices(capsys, argv):
    err = _usage_error(capsys, argv, "solve")
    assert f"unknown problem {argv[1]!r}; known problems: " + ", ".join(registry.names()) in err


@pytest.mark.usefixtures("no_work")
def test_table1_unknown_row_is_rejected_before_any_row_runs(capsys):
    err = _usage_error(capsys, ["table1", "pend", "jmup"], "table1")
    assert "unknown problem 'jmup'" in err and "quad-goal" in err


@pytest.mark.usefixtures("no_work")
@pytest.mark.parametrize("value", ["0", "-1", "ten"])
def test_non_positive_maxiter_is_a_usage_error(capsys, value):
    err = _usage_error(capsys, ["solve", "pend", "--maxiter", value], "solve")
    assert "argument --maxiter:" in err and value in err


@pytest.mark.usefixtures("no_work")
@pytest.mark.parametrize(("argv", "command", "flag"), [
    (["solve", "pend", "--bogus"], "solve", "--bogus"),
    (["table1", "pend", "--maxiter", "3"], "table1", "--maxiter"),
    (["bench", "--no-such-flag"], "bench", "--no-such-flag"),
    (["paper", "hddp", "table2", "--bogus"], "paper", "--bogus"),
    (["list", "--all"], "list", "--all"),
])
def test_a_bad_flag_prints_the_subcommands_usage(capsys, argv, command, flag):
    err = _usage_error(capsys, argv, command)
    assert "unrecognized arguments: " + flag in err
    assert "{bench,list,solve,table1,paper}" not in err  # not the top-level usage


@pytest.mark.usefixtures("no_work")
def test_plot_into_a_missing_folder_is_rejected_before_solving(tmp_path, capsys):
    err = _usage_error(capsys, ["solve", "pend", "--plot", str(tmp_path / "missing" / "x.png")], "solve")
    assert "--plot" in err and "does not exist" in err


@pytest.mark.usefixtures("no_work")
def test_plot_in_an_unknown_format_is_rejected(tmp_path, capsys):
    err = _usage_error(capsys, ["solve", "pend", "--plot", str(tmp_path / "x.docx")], "solve")
    assert "unknown image format 'docx'" in err and "png" in err


@pytest.mark.usefixtures("no_work")
def test_html_that_cannot_be_written_is_rejected(tmp_path, capsys):
    err = _usage_error(capsys, ["solve", "pend", "--html", str(tmp_path)], "solve")
    assert "is a folder" in err
    err = _usage_error(capsys, ["solve", "pend", "--html", str(tmp_path / "no" / "pend.html")], "solve")
    assert "does not exist" in err
    assert not list(tmp_path.iterdir())  # the check leaves nothing behind


@pytest.mark.usefixtures("no_work")
def test_default_html_is_checked_in_the_working_folder(tmp_path, monkeypatch, capsys):
    """The default ``<problem>.html`` goes to the working folder: a folder of that name blocks it."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "pend.html").mkdir()
    err = _usage_error(capsys, ["solve", "pend"], "solve")
    assert "--html pend.html is a folder" in err


def test_bench_out_and_problems_are_checked(tmp_path, capsys):
    err = _usage_error(capsys, ["bench", "--vs", "crocoddyl", "--out", str(tmp_path / "no" / "B.md")], "bench")
    assert "--out" in err and "does not exist" in err
    err = _usage_error(capsys, ["bench", "--models", "--problems", "jump", "jmup"], "bench")
    assert "unknown problem 'jmup'" in err
    err = _usage_error(capsys, ["bench", "--repeats", "0"], "bench")
    assert "argument --repeats: must be a positive integer" in err


def test_paper_experiment_and_folder_are_checked(tmp_path, capsys):
    err = _usage_error(capsys, ["paper", "hddp", "nope"], "paper")
    assert "unknown experiment hddp 'nope'; known: table1, table2" in err
    err = _usage_error(capsys, ["paper", "box-ddp", "lq", "--out", str(tmp_path / "missing")], "paper")
    assert "is not an existing folder" in err


def test_the_script_exits_with_the_documented_statuses(tmp_path):
    """The installed ``crocopy`` script: 2 for a usage error, 1 for an unconverged solve."""
    env = {**os.environ, "OMP_NUM_THREADS": "1", "MPLBACKEND": "Agg"}
    bad = subprocess.run([CROCOPY, "table1", "jmup"], capture_output=True, text=True, env=env, cwd=tmp_path)
    assert bad.returncode == 2 and "unknown problem 'jmup'" in bad.stderr and bad.stdout == ""
    run = subprocess.run([CROCOPY, "solve", "quad-goal", "--maxiter", "2", "--quiet", "--no-html"],
                         capture_output=True, text=True, env=env, cwd=tmp_path)
    assert run.returncode == 1, run.stderr
    assert "did not converge" in run.stdout and "after 2 iterations" in run.stdout


def test_table1_row_uses_the_registry_success_rule(capsys):
    assert main(["table1", "pend"]) == 0
    out = capsys.readouterr().out
    row = next(line for line in out.splitlines() if line.startswith("| pend |"))
    cells = [c.strip() for c in row.strip("|").split("|")]
    spec = registry.get("pend")
    assert cells[6] == "✓" and int(cells[4]) == 92  # Box-FDDP, same iterations as Crocoddyl 3.2.1
    assert cells[3] == ("✓" if spec.solved(True, float(cells[2])) else "✗")
    assert not spec.solved(True, 100.0 * spec.reference["boxfddp"].cost)
    assert not spec.solved(False, spec.reference["boxfddp"].cost)
    assert "- Box-FDDP solves all 1 rows: yes" in out  # trend summary (crocopy.experiments.table1) after the table
    assert "- Box-DDP fails at least on pend, jump, hop, bar: no (jump (not run), hop (not run)" in out


def test_warm_up_is_silent_when_the_kernels_are_cached(capsys):
    problem, xs, us = registry.get("quad-goal").build(crocopy)
    crocopy.SolverBoxFDDP(problem).solve(xs, us, 2, False)  # loads (or compiles) this process's kernels
    capsys.readouterr()
    assert warm_up_kernels(lambda: crocopy.SolverBoxFDDP(problem).solve(xs, us, 2, False)) == 0.0
    assert capsys.readouterr().err == ""


@pytest.mark.slow
def test_first_run_notice_with_an_empty_kernel_cache(tmp_path):
    """A fresh numba cache: the notice appears, and the timed solve compiles nothing more (its ms/iteration
    is that of a warm run, far below the compilation's seconds)."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache"), "OMP_NUM_THREADS": "1",
           "CROCOPY_SHIPPED_KERNELS": "0"}  # not the kernels a wheel ships
    run = subprocess.run([CROCOPY, "solve", "pend", "--quiet", "--no-html"], capture_output=True, text=True,
                         env=env, cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    assert re.search(r"^compiling kernels \(first run only\): \d+/\d+$", run.stderr, re.M)
    compile_s = float(re.search(r"kernels compiled in ([\d.]+) s", run.stderr).group(1))
    solve_s = float(re.search(r"after 92 iterations, cost [\d.e+-]+, ([\d.]+) s", run.stdout).group(1))
    assert solve_s < compile_s / 2
    again = subprocess.run([CROCOPY, "solve", "pend", "--quiet", "--no-html", "--maxiter", "3"],
                           capture_output=True, text=True, env=env, cwd=tmp_path)
    assert again.returncode == 1 and "compiling" not in again.stderr


@pytest.mark.slow
def test_default_solve_is_a_jump_measured_on_its_trajectory(monkeypatch, capsys):
    """``crocopy solve`` (the ANYmal jump, Box-FDDP) converges; on its trajectory the base apex is
    at least 15 cm above standing and within 2 cm of the height asked, the feet stay within 1.3x
    their standing spread and under the body in flight, and it lands on its four feet.  The
    ``crocopy list`` label's base and CoM rises and the summary's figures are the measured ones."""
    import pinocchio as pin

    from crocopy.problems.quadruped import FEET, JUMP_HEIGHT

    solvers = []

    class Recorded(crocopy.SolverBoxFDDP):
        def __init__(self, problem):
            super().__init__(problem)
            solvers.append(self)

    monkeypatch.setattr(crocopy, "SolverBoxFDDP", Recorded)
    assert main(["solve", "--quiet", "--no-html"]) == EXIT_CONVERGED
    out = capsys.readouterr().out
    solver = solvers[-1]
    problem = solver.problem
    model = problem.terminalModel.state.pinocchio
    data = model.createData()
    fids = [model.getFrameId(f) for f in FEET["anymal"]]
    base, com, spread, feet_z, below = [], [], [], [], []
    for k, x in enumerate(solver.xs):
        q = x[: model.nq]
        pin.framesForwardKinematics(model, data, q)
        feet = np.array([data.oMf[f].translation for f in fids])
        base.append(q[2])
        com.append(pin.centerOfMass(model, data, q)[2])
        spread.append(np.abs(feet[:, :2] - q[:2]).max(axis=0))  # the base stays level (checked below)
        feet_z.append(feet[:, 2])
        if 30 <= k < 70:
            below.append(q[2] - feet[:, 2].max())
            assert np.allclose(q[3:6], 0.0, atol=0.02)  # level: quaternion vector part ~ 0
    rise = max(base) - base[0]
    assert rise >= 0.15 and abs(rise - JUMP_HEIGHT) <= 0.02
    ratio = (np.array(spread) / spread[0]).max()
    assert ratio <= 1.3
    assert min(below) > 0.3  # the feet hang under the body, not thrown up to its height
    np.testing.assert_allclose(feet_z[-1], feet_z[0], atol=0.01)  # back on its four feet
    assert max(feet_z[50]) > 0.05  # and it did leave the ground
    base_cm, com_cm = (float(v) for v in re.search(r"base \+(\d+) cm, CoM \+(\d+) cm",
                                                   registry.get("jump").description).groups())
    assert abs(100 * rise - base_cm) <= 1.0 and abs(100 * (max(com) - com[0]) - com_cm) <= 1.0
    assert f"flight 0.40 s, base apex {100 * rise:.1f} cm above its start" in out
    assert f"feet within {ratio:.2f}x their standing spread" in out and "landed on every foot" in out
    assert "expected from an infeasible start of multiple shooting" in out


def test_cost_climb_is_explained_only_when_the_gaps_were_closing():
    from crocopy.cli import cost_climb_note

    assert cost_climb_note([5.0, 4.0, 3.0], [0.5, 0.0, 0.0]) is None
    note = cost_climb_note([5.0, 5.0, 80.0, 9.0, 3.0], [0.5, 0.5, 0.2, 0.0, 0.0])
    assert "from 5 to 80 (iteration 2)" in note and "infeasible start of multiple shooting" in note
    assert "then down to 3" in note
    assert "unexpected" in cost_climb_note([5.0, 4.0, 9.0, 3.0], [0.0, 0.0, 0.0, 0.0])


def test_readme_lists_every_solve_choice_and_the_compile_command():
    """The README's command table names each ``--solver`` choice of ``crocopy solve --help``, and ``compile``."""
    from crocopy.solvers import SOLVERS

    readme = open(os.path.join(os.path.dirname(__file__), "..", "README.md"), encoding="utf-8").read()
    listed = re.search(r"`crocopy solve \[PROBLEM\] \[--solver ([a-z\\|]+)\]", readme).group(1).split("\\|")
    assert listed == sorted(SOLVERS)
    assert "| `crocopy compile [--solve PROBLEM [--solver S]]` |" in readme


def test_in_background_returns_the_result_or_raises_the_error_of_its_thread():
    import threading

    from crocopy.cli import in_background

    seen = []
    wait = in_background(lambda a, b: seen.append(threading.current_thread().name) or a + b, 2, 3)
    assert wait() == 5 and seen and seen[0] != threading.current_thread().name

    def fail():
        raise KeyError("no robot")

    with pytest.raises(KeyError, match="no robot"):
        in_background(fail)()


def test_deferred_work_runs_in_the_background_once_started_else_when_asked_for():
    import threading

    from crocopy.cli import Deferred

    threads = []
    work = Deferred(lambda x: threads.append(threading.current_thread().name) or x * 2, 21)
    assert work.result() == 42 and threads == [threading.current_thread().name]  # never started: runs here
    work.start()
    first = work.wait
    work.start()
    assert work.wait is first and work.result() == 42 and len(threads) == 2  # started once, on another thread
    assert threads[1] != threading.current_thread().name


def test_after_first_iteration_acts_once_at_the_first_callback():
    calls = []
    callback = AfterFirstIteration(lambda: calls.append(len(calls)))
    for _ in range(3):
        callback(object())
    assert calls == [0]
