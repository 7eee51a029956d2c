"""The documentation's code: every script in ``docs/snippets`` (shown by ``literalinclude``) runs.

Each runs in-process (``runpy``) in a temporary folder; the Dask one needs the ``distributed``
extra and ten full solves, so it is ``slow``.
"""

from __future__ import annotations

import re
import runpy
import sys
from pathlib import Path

import pytest

SNIPPETS = Path(__file__).resolve().parents[1] / "docs" / "snippets"

RUNS = [
    pytest.param("first_solve.py", r"converged=True iterations=\d+ .*\nfinal position .*\nanimation: quad-goal\.html",
                 id="first_solve"),
    pytest.param("compose_arm.py", r"\d+ iterations, cost 5\.74\d*, end effector [\d.]+ mm from the target",
                 id="compose_arm"),
    pytest.param("solver_families.py", r"^(\S.{28}converged=True .*\n){7}$", id="solver_families"),
    pytest.param("constrained_reach.py", r"FDDP, box as a penalty .*\nCSQP, box as a constraint +iterations= *\d+ "
                 r"cost=14\.58\d+ max y=0\.2500", marks=pytest.mark.slow, id="constrained_reach"),
    pytest.param("dask_cluster.py", r"10 solves in [\d.]+ s; best start .*, cost [\d.e-]+",
                 marks=pytest.mark.slow, id="dask_cluster"),
]


def test_every_snippet_is_run():
    assert {p.values[0] for p in RUNS} == {p.name for p in SNIPPETS.glob("*.py")}


def test_every_snippet_is_shown_in_the_docs():
    pages = "\n".join(p.read_text() for p in SNIPPETS.parent.rglob("*.rst"))
    for p in RUNS:
        assert f"snippets/{p.values[0]}" in pages, p.values[0]


@pytest.mark.parametrize(("script", "expected"), RUNS)
def test_snippet_runs(script, expected, tmp_path, monkeypatch, capsys):
    if script == "dask_cluster.py":
        pytest.importorskip("distributed")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "argv", [script])
    runpy.run_path(str(SNIPPETS / script), run_name="__main__")
    out = capsys.readouterr().out
    assert re.search(expected, out), out[-2000:]
    if script == "solver_families.py":
        shown = (SNIPPETS.parent / "solvers" / "index.rst").read_text()
        assert all(f"   {line}" in shown for line in out.splitlines()), "docs/solvers/index.rst shows another output"
    if script == "first_solve.py":
        assert (tmp_path / "quad-goal.html").stat().st_size > 10_000
