"""Smoke test of ``examples/``: every script runs end to end on a tiny iteration budget and writes
its meshcat animation (a self-contained HTML file holding a ``set_animation`` command).

Scripts run in-process (``runpy``) inside a temporary folder, so the interpreter, the imports and
the parsed robot models are shared between them.  Scripts with a ``--maxiter`` option get it; in
the others every solver's ``solve`` is capped to :data:`MAXITER` iterations.
"""

from __future__ import annotations

import re
import runpy
import sys
from pathlib import Path

import pytest

import crocopy
from crocopy.models.display.html import static_html_commands

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
MAXITER = 2
SLOW = pytest.mark.slow

RUNS = [
    pytest.param("quadrotor.py", ["narrow", "--maxiter", "2"], ["quad-narrow.html"], id="quadrotor"),
    pytest.param("quadruped_gaits.py", ["pace", "--maxiter", "1"], ["pace.html"], id="quadruped_gaits"),
    pytest.param("arm_reaching.py", [], ["arm.html"], id="arm_reaching"),
    pytest.param("user_residual.py", [], ["reach.html"], id="user_residual"),
    pytest.param("double_pendulum.py", [], ["pend.html"], id="double_pendulum"),
    pytest.param("quadruped_jump.py", [], ["jump.html"], id="quadruped_jump"),
    pytest.param("boxfddp_vs_boxddp.py", [], ["pend_gaps.png", "trot-short_gaps.png"], id="boxfddp_vs_boxddp"),
    pytest.param("humanoid_manipulation.py", ["--maxiter", "1"], ["man.html"], id="humanoid_manipulation"),
    pytest.param("humanoid_taichi.py", ["--maxiter", "1"], ["taichi.html"], marks=SLOW, id="humanoid_taichi"),
    pytest.param("monkey_bar.py", ["--maxiter", "1"], ["bar.html"], marks=SLOW, id="monkey_bar"),
]
"""``(script, arguments, files it must write)``; the Talos ones beyond the first are slow."""


def _solvers() -> list[type]:
    return [c for c in vars(crocopy).values() if isinstance(c, type) and issubclass(c, crocopy.SolverAbstract)]


def _capped(solve):
    def capped(self, init_xs=None, init_us=None, maxiter=100, *args, **kwargs):
        return solve(self, init_xs, init_us, min(maxiter, MAXITER), *args, **kwargs)

    return capped


def _cap_solvers(monkeypatch: pytest.MonkeyPatch) -> None:
    """Cap the iteration budget of every crocopy solver's ``solve`` to :data:`MAXITER`."""
    for cls in _solvers():
        if "solve" in vars(cls):
            monkeypatch.setattr(cls, "solve", _capped(vars(cls)["solve"]))


def test_every_example_is_run():
    listed = {p.values[0] for p in RUNS}
    assert listed == {p.name for p in EXAMPLES.glob("*.py")}


def test_animations_are_named_after_their_registry_problem():
    """One name per problem: an example's ``<name>.html`` is what ``crocopy solve <name>`` writes."""
    from crocopy.problems import registry

    pages = [Path(name).stem for p in RUNS for name in p.values[2] if name.endswith(".html")]
    assert pages and set(pages) <= set(registry.names())


@pytest.mark.parametrize(("script", "argv", "outputs"), RUNS)
def test_example_runs_and_writes_its_animation(script, argv, outputs, tmp_path, monkeypatch, capsys):
    path = EXAMPLES / script
    if "--maxiter" not in path.read_text():
        _cap_solvers(monkeypatch)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "argv", [str(path), *argv])
    runpy.run_path(str(path), run_name="__main__")
    printed = capsys.readouterr().out
    for name in outputs:
        out = tmp_path / name
        assert out.is_file() and out.stat().st_size > 10_000, name
        if name.endswith(".html"):
            assert name in printed
            animations = [c for c in static_html_commands(out) if c["type"] == "set_animation"]
            assert len(animations) == 1
            tracks = [t for a in animations[0]["animations"] for t in a["clip"]["tracks"]]
            assert tracks and max(len(t["keys"]) for t in tracks) > 1


def test_double_pendulum_animates_the_converged_swing_up(tmp_path, monkeypatch, capsys):
    """Run in full (no cap): the animation is Box-FDDP's converged solve, and each solver's printed summary
    line is its actual outcome (Box-DDP's is round-off sensitive: it may stop at its limit or converge to a
    worse minimum than Box-FDDP's swing-up)."""
    import crocopy.models.display.html as html

    animated = []
    export = html.export_html_from_solver

    def recording(robot, solver, path, *args, **kwargs):
        animated.append((type(solver).__name__, solver.iter, solver.cost, solver.reason))
        return export(robot, solver, path, *args, **kwargs)

    monkeypatch.setattr(html, "export_html_from_solver", recording)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "argv", [str(EXAMPLES / "double_pendulum.py")])
    solvers = runpy.run_path(str(EXAMPLES / "double_pendulum.py"), run_name="__main__")["solvers"]
    printed = capsys.readouterr().out
    [(name, iters, cost, reason)] = animated
    assert name == "SolverBoxFDDP" and reason == "converged"
    assert f"animation of SolverBoxFDDP's swing-up ({iters} iterations, cost {cost:.6g})" in printed
    assert set(solvers) == {"SolverBoxFDDP", "SolverBoxDDP"}
    for name, solver in solvers.items():
        [line] = [ln for ln in printed.splitlines() if ln.startswith(f"{name}: ")]
        match = re.fullmatch(rf"{name}: converged=(True|False) \((.+)\) iterations=(\d+) cost=(\S+)", line)
        assert match, line
        converged = match[1] == "True"
        assert converged == (solver.reason == "converged") and match[2] == solver.reason, line
        assert int(match[3]) == solver.iter and float(match[4]) == pytest.approx(solver.cost, rel=1e-5), line
        assert converged or (solver.iter == 500 and "500" in solver.reason), line
    assert solvers["SolverBoxFDDP"].cost < solvers["SolverBoxDDP"].cost
