"""``crocopy bench --compat``: the table on synthetic rows, the solve recorder, and (bench extra) a real
run of one of Crocoddyl's shipped example scripts with crocopy and with Crocoddyl."""

from __future__ import annotations

import importlib.util
import sys

import pytest

from crocopy.bench import compat
from crocopy.bench.compat import GAITS, Row, RunResult, format_row, format_table, relative_difference
from crocopy.cli import main

HAS_CROCODDYL = importlib.util.find_spec("crocoddyl") is not None


def solves(*pairs):
    return [{"solver": "SolverFDDP", "iter": it, "cost": cost, "converged": True} for it, cost in pairs]


def cells(line: str) -> list[str]:
    return [c.strip() for c in line.strip().strip("|").split("|")]


def test_row_of_a_script_that_runs_in_both():
    reference = RunResult(True, solves=solves((72, 8.125 * (1 + 1e-7))))
    row = Row("arm", RunResult(True, solves=solves((72, 8.125))), reference)
    c = cells(format_row(row))
    assert c[:6] == ["arm", "yes", "72", "8.125", "72", "8.125"]
    assert float(c[6]) == pytest.approx(1e-7, rel=1e-3)


def test_row_of_a_failing_script_names_its_first_error_and_escapes_pipes():
    mine = RunResult(False, error="AttributeError: module 'crocopy' has no attribute 'SolverIntro'", where="x.py:12")
    row = Row("double|pendulum", mine, RunResult(True, solves=solves((53, 0.0206))))
    line = format_row(row)
    c = cells(line.replace("\\|", "¦"))
    assert c[0] == "double¦pendulum"
    assert c[1] == "no: AttributeError: module 'crocopy' has no attribute 'SolverIntro' (x.py:12)"
    assert c[2:4] == ["-", "-"] and c[4:6] == ["53", "0.0206"] and c[6] == "-"
    assert relative_difference(mine, row.crocoddyl) is None


def test_several_solves_are_compared_pairwise_in_order():
    many = RunResult(True, solves=solves(*[(i, 1.0 + i) for i in range(1, 7)]))
    ref = RunResult(True, solves=solves(*[(i, 1.0 + i) for i in range(1, 6)], (6, 7.7)))
    assert relative_difference(many, ref) == pytest.approx(0.7 / 7.7)
    c = cells(format_row(Row("gaits", many, ref)))
    assert c[2] == "21 in 6 solves" and c[3] == "7"
    stopped = RunResult(False, error="LinAlgError: Singular matrix", solves=solves((1, 2.0), (2, 3.3)))
    assert relative_difference(stopped, ref) == pytest.approx(0.3 / 3.0)
    assert cells(format_row(Row("gaits", stopped, ref)))[6].endswith("(2 vs 6 solves)")
    assert cells(format_row(Row("gaits", many, ref)))[2] == "21 in 6 solves"
    assert cells(format_row(Row("short", RunResult(True, solves=solves((1, 1.0), (2, 2.0))), None)))[2] == "1, 2"


def test_table_counts_scripts_and_gaits_separately():
    gait = next(iter(GAITS))
    rows = [Row("a", RunResult(True, solves=solves((1, 1.0))), RunResult(True, solves=solves((1, 1.0)))),
            Row("b", RunResult(False, error="TypeError: x"), RunResult(True)),
            Row(gait, RunResult(True), RunResult(True))]
    text = format_table(rows)
    assert "1 of 2 example scripts and 1 of 1 gaits run to their end" in text
    lines = [line for line in text.splitlines() if line.startswith("|")]
    assert len(lines) == 2 + len(rows)
    assert all(len(cells(line)) == 7 for line in lines)


def test_recorder_counts_each_outermost_solve_once():
    class SolverAbstract:
        iter, cost = 0, 0.0

        def solve(self, n=3):
            self.iter, self.cost = n, 1.0 / n
            return True

    class SolverFDDP(SolverAbstract):
        def solve(self, n=3):
            return super().solve(n + 1)

    namespace = type(sys)("fake_crocoddyl")
    namespace.SolverAbstract, namespace.SolverFDDP, namespace.NotASolver = SolverAbstract, SolverFDDP, object
    sink = []
    compat.record_solves(namespace, sink)
    SolverFDDP().solve(4)
    SolverAbstract().solve()
    assert sink == [{"solver": "SolverFDDP", "iter": 5, "cost": 0.2, "converged": True},
                    {"solver": "SolverAbstract", "iter": 3, "cost": 1.0 / 3, "converged": True}]


def test_without_crocoddyl_the_command_names_the_bench_extra(monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "crocoddyl", None)  # makes `import crocoddyl` raise ImportError
    assert main(["bench", "--compat", "--problems", "quadrotor_fwddyn"]) == 2
    assert "bench" in capsys.readouterr().err


@pytest.mark.skipif(not HAS_CROCODDYL, reason="needs the bench extra (Crocoddyl 3.2.1)")
def test_compat_runs_a_shipped_example_with_both_libraries(tmp_path, capsys):
    out = tmp_path / "COMPAT.md"
    assert len(compat.example_scripts()) >= 17
    assert main(["bench", "--compat", "--problems", "quadrotor_fwddyn", "--out", str(out)]) == 0
    text = out.read_text()
    assert text.rstrip("\n") in capsys.readouterr().out
    (row,) = [line for line in text.splitlines() if line.startswith("| quadrotor_fwddyn |")]
    c = cells(row)
    assert c[1] == "yes" or c[1].startswith("no: ")
    assert int(c[4]) > 0 and float(c[5]) > 0.0  # Crocoddyl's own run solved it
    if c[1] == "yes":
        assert float(c[6]) <= 1e-6  # same algorithm: same final cost


@pytest.mark.skipif(not HAS_CROCODDYL, reason="needs the bench extra (Crocoddyl 3.2.1)")
def test_unknown_job_is_refused():
    with pytest.raises(KeyError, match="no-such-script"):
        compat.jobs(["no-such-script"])
