"""The side-by-side benchmark harness (``crocopy bench --vs crocoddyl``) on the arm and the pendulum.

Structure only, never timings: crocopy-only runs, the markdown report, the bars, the memory
subprocess, the clear failure without Crocoddyl, and (where Crocoddyl is importable) one tiny
side-by-side run through the command line.
"""

import importlib.util
import sys

import pytest

from crocopy.bench import report as bench_report
from crocopy.bench import side_by_side as bench_problems
from crocopy.bench.memory import warmup_problem
from crocopy.bench.side_by_side import BenchDependencyError, LibResult, ProblemResult, bench_problem
from crocopy.cli import main

PHASE_KEYS = {*bench_problems.PHASES, "total"}


@pytest.fixture(scope="module")
def arm_crocopy():
    """crocopy alone on the arm: 3 Box-FDDP iterations, 2 samples, one solve in the memory subprocess."""
    return bench_problem("arm", libraries=("crocopy",), repeats=2, maxiter=3, memory=True, solve_budget=0.0)


def test_crocopy_only_run_has_every_figure(arm_crocopy):
    r = arm_crocopy
    assert (r.name, r.dims, r.solver, r.maxiter) == ("arm", (100, 15, 6), "SolverBoxFDDP", 3)
    lib = r.libs["crocopy"]
    assert set(r.libs) == {"crocopy"}
    assert isinstance(lib.iters, int) and lib.iters == 3 and not lib.converged
    assert lib.cost > 0 and lib.solve_runs == 1  # no budget: the subprocess solve only
    assert set(lib.phases) == PHASE_KEYS and all(v > 0 for v in lib.phases.values())
    assert lib.phases["total"] == pytest.approx(lib.phases["calcDiff"] + lib.phases["backward"] + lib.phases["forward"])
    assert lib.ms_per_iter > 0
    assert lib.memory_mib > 1.0  # the arm (not the warm-up pendulum) allocates above the post-warm-up level
    assert r.ratio("total") is None and r.agree() is None and bench_report.bar_met(r) is None


def test_report_of_a_crocopy_only_run(arm_crocopy):
    text = bench_report.format_report(
        [arm_crocopy], {"repeats": 2, "solve_budget": 30.0, "wall_s": 3.0, "load": ((1.0, 1.0, 1.0), (2.0, 2.0, 2.0))}
    )
    for heading in ("# crocopy vs Crocoddyl", "## Solves", "## Phases (ms)", "## Peak memory", "## Bars (issue 7)"):
        assert heading in text
    assert bench_report.cpu_model() in text and "NumPy" in text and "Pinocchio" in text
    assert "load average 1.00 at start, 2.00 at end" in text
    rows = [line for line in text.splitlines() if line.startswith("| arm |")]
    assert len(rows) == 4  # solves, phases (crocopy only, no ratio row), memory, bars
    solve = [c.strip() for c in rows[0].strip("|").split("|")]
    assert solve[3] == "3 (not converged)" and solve[5] == "—" and solve[7] == solve[8] == "—"
    assert rows[-1].rstrip().endswith("| — |")  # no verdict without Crocoddyl


def _result(name, cp_total, cd_total, cp_cost=1.0, cd_cost=1.0, cp_iters=10, cd_iters=10, cp_wall=None):
    def lib(total, cost, iters, wall=None):
        phases = {"calc": 1.0, "calcDiff": total / 2, "backward": total / 4, "forward": total / 4, "total": total}
        return LibResult(iters, cost, True, wall or 1.1 * total, 5, phases, 10.0 * total)

    return ProblemResult(
        name,
        (10, 4, 1),
        "SolverBoxFDDP",
        100,
        {"crocopy": lib(cp_total, cp_cost, cp_iters, cp_wall), "crocoddyl": lib(cd_total, cd_cost, cd_iters)},
    )


def test_ratios_agreement_and_bars():
    jump_fast, jump_slow = _result("jump", 1.4, 1.0), _result("jump", 1.6, 1.0)
    pend = _result("pend", 1.9, 1.0, cp_cost=1.0 + 2e-7)
    assert jump_fast.ratio("total") == pytest.approx(1.4) and jump_fast.ratio("memory_mib") == pytest.approx(1.4)
    assert jump_fast.ratio("calc") == pytest.approx(1.0) and jump_fast.ratio("ms_per_iter") == pytest.approx(1.4)
    assert bench_report.bar_met(jump_fast) and not bench_report.bar_met(jump_slow)
    assert bench_report.bar_met(pend) and pend.agree()  # ≤ 2× elsewhere; 2e-7 relative agrees
    assert pend.cost_rel_diff() == pytest.approx(2e-7)
    assert not _result("pend", 1.0, 1.0, cp_cost=1.0 + 1e-5).agree()
    assert not _result("pend", 1.0, 1.0, cp_iters=11).agree()
    taichi_wall = _result("taichi", 1.4, 1.0, cp_wall=1.7 * 1.1)  # phases within 1.5×, full-solve wall not
    assert bench_report.bar_met(taichi_wall) and bench_report.bar_verdict(taichi_wall) == "met (phases only)"
    text = bench_report.format_report([jump_fast, jump_slow, pend], {"repeats": 5, "solve_budget": 30.0})
    bars = [
        line for line in text.split("## Bars")[1].splitlines() if line.startswith("| jump") or line.startswith("| pend")
    ]
    assert [b.split("|")[-2].strip() for b in bars] == ["met", "not met", "met"]
    solve = next(line for line in text.splitlines() if line.startswith("| pend | 10, 4, 1 |"))
    assert [c.strip() for c in solve.strip("|").split("|")][7:9] == ["2.0e-07", "yes"]
    assert "| ≤ 1.5× | 1.40× |" in bars[0] and "| ≤ 2× | 1.90× |" in bars[2]
    ratio_rows = [line for line in text.splitlines() if line.startswith("| jump | ratio |")]
    assert ratio_rows[0].split("|")[-2].strip() == "1.40×"


def test_common_steplength_skips_diverging_steps():
    cells = [[1.0], [1.0]]

    def fine_below_half():
        if cells[0][0] > 0.3:
            raise RuntimeError("diverged")
        return 1.0

    def nan_at_quarter():
        return float("nan") if cells[1][0] > 0.2 else 2.0

    assert bench_problems._common_steplength([fine_below_half, nan_at_quarter], cells) == 0.125
    assert cells == [[0.125], [0.125]]


def test_default_problems_are_table1_walk_and_arm():
    from crocopy.problems import registry

    assert bench_problems.VS_PROBLEMS == (*registry.TABLE1, "walk", "arm")
    assert all(name in registry.PROBLEMS for name in bench_problems.VS_PROBLEMS)
    for name in bench_problems.VS_PROBLEMS:  # the memory warm-up never reuses the measured problem's memory
        assert warmup_problem(name) != name and warmup_problem(name) in registry.PROBLEMS


def test_memory_warm_up_loads_the_compiled_line_search(tmp_path):
    """The warm-up of the memory subprocess reaches a feasible iterate, so the line search's compiled kernel (loaded
    at its first call, about 13 MiB) is not counted in the measured solve."""
    import subprocess

    code = ("import crocopy\n"
            "from crocopy.bench.memory import warm_up\n"
            "from crocopy.models.rbd.line_search_kernel import line_search\n"
            "assert not line_search.signatures\n"
            "warm_up(crocopy, 'pend', 'boxfddp')\n"
            "print(len(line_search.signatures))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600,
                         cwd=tmp_path)  # the installed crocopy, not the checkout's folder
    assert out.returncode == 0, out.stderr[-2000:]
    assert int(out.stdout.strip().splitlines()[-1]) >= 1


def test_bad_arguments_are_named():
    with pytest.raises(ValueError, match="solver_name"):
        bench_problem("pend", libraries=("crocopy",), solver_name="newton")
    with pytest.raises(ValueError, match="repeats"):
        bench_problem("pend", libraries=("crocopy",), repeats=0)
    with pytest.raises(ValueError, match="libraries"):
        bench_problem("pend", libraries=("acados",), repeats=1, maxiter=1, memory=False)


def test_cli_without_crocoddyl_names_the_bench_extra(monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "crocoddyl", None)  # makes `import crocoddyl` raise ImportError
    assert main(["bench", "--vs", "crocoddyl", "--problems", "pend"]) == 2
    err = capsys.readouterr().err
    assert "crocopy[bench]" in err and "Crocoddyl" in err


def test_cli_unknown_problem_is_a_clear_error(capsys):
    assert main(["bench", "--vs", "crocoddyl", "--problems", "no-such-problem"]) == 2
    assert "unknown problem 'no-such-problem'" in capsys.readouterr().err


def test_side_by_side_through_the_cli_or_the_missing_extra(tmp_path, capsys):
    """With Crocoddyl: a 2-iteration run writes the report; without: the clear error."""
    out = tmp_path / "BENCH.md"
    argv = [
        "bench",
        "--vs",
        "crocoddyl",
        "--problems",
        "pend",
        "--repeats",
        "1",
        "--maxiter",
        "2",
        "--no-memory",
        "--out",
        str(out),
    ]
    if importlib.util.find_spec("crocoddyl") is None:
        with pytest.raises(BenchDependencyError, match="bench"):
            bench_problems.require_crocoddyl()
        assert main(argv) == 2 and not out.exists()
        return
    assert main(argv) == 0
    text = out.read_text()
    assert text.rstrip("\n") == capsys.readouterr().out.rstrip("\n")
    solve = next(line for line in text.splitlines() if line.startswith("| pend | 100, 4, 1 |"))
    cells = [c.strip() for c in solve.strip("|").split("|")]
    assert cells[3] == "2 (not converged)" and cells[5] == "2 (not converged)"
    assert float(cells[7]) >= 0 and cells[8] in ("yes", "no") and cells[11].endswith("×")
    assert "| pend | ratio |" in text and ("| met |" in text or "| not met |" in text)
    assert "Crocoddyl 3.2.1" in text


def test_crocoddyl_needs_its_pinocchio(monkeypatch):
    if importlib.util.find_spec("crocoddyl") is None:
        with pytest.raises(BenchDependencyError, match="crocopy\\[bench\\]"):
            bench_problems.require_crocoddyl()
        return
    import pinocchio

    monkeypatch.setattr(pinocchio, "__version__", "4.1.0")
    with pytest.raises(BenchDependencyError, match="needs Pinocchio 4.0.0, found 4.1.0"):
        bench_problems.require_crocoddyl()
