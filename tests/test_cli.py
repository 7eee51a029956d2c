"""Smoke tests of the ``crocopy`` command (in-process, fast problems only)."""

import pytest

import crocopy
from crocopy.cli import main


def test_version(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert crocopy.__version__ in capsys.readouterr().out


def test_list_names_every_registered_problem(capsys):
    from crocopy.problems import registry

    assert main(["list"]) == 0
    out = capsys.readouterr().out
    for name in registry.names():
        assert name in out


def test_solve_pendulum_writes_summary_plot_and_html(tmp_path, capsys):
    html, png = tmp_path / "pend.html", tmp_path / "conv.png"
    assert main(["solve", "pend", "--solver", "fddp", "--quiet", "--maxiter", "5", "--html", str(html),
                 "--plot", str(png)]) == 0
    out = capsys.readouterr().out
    assert "pend: SolverFDDP" in out and "after 5 iterations" in out
    assert html.stat().st_size > 10_000 and "<html" in html.read_text()[:2000].lower()
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_solve_unknown_problem_is_a_clear_error(capsys):
    assert main(["solve", "no-such-problem", "--no-html"]) == 2
    assert "unknown problem 'no-such-problem'" in capsys.readouterr().err


def test_unknown_paper_experiment(capsys):
    assert main(["paper", "hddp", "nope"]) == 2
    assert "known:" in capsys.readouterr().err


def test_table1_row_uses_the_registry_success_rule(capsys):
    from crocopy.problems import registry

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
