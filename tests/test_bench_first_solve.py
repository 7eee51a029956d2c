"""``crocopy bench --first-solve`` (crocopy.bench.first_solve): a whole ``crocopy solve`` is timed milestone by
milestone to its end, and the report lists every sample of the fresh and warm runs."""

from __future__ import annotations

import os
import sys

from crocopy.bench import first_solve

SCRIPT = """
import time
print('compiling kernels (first run only): 1/2')
time.sleep(0.1)
print('iter cost')
print('   0  1.000e+00  2.000e+00')
print('jump: SolverBoxFDDP converged after 1 iterations, cost 1, 0.01 s (1.0 ms/iteration)')
t = time.process_time()
while time.process_time() - t < 0.3:
    pass
print('meshcat animation written to jump.html')
"""


def test_a_run_is_timed_to_each_milestone_and_its_end():
    run = first_solve.time_run([sys.executable, "-c", SCRIPT], os.environ, "jump")
    assert run.returncode == 0 and len(run.output) == 5
    assert run.notice <= run.first_iteration <= run.solved <= run.html_written <= run.end
    assert run.first_iteration - run.notice >= 0.05 and 0.2 <= run.html < run.end  # slept 0.1 s, spun 0.3 s
    assert run.cpu >= 0.3  # the child's CPU seconds, spinning included


def test_a_run_that_never_solves_has_no_html_time():
    run = first_solve.time_run([sys.executable, "-c", "import sys; print('usage error'); sys.exit(2)"], os.environ,
                               "jump")
    assert run.returncode == 2 and run.first_iteration is None and run.solved is None and run.html is None


def test_report_gives_medians_and_every_sample():
    fresh = {"notice": [True, True], "first iteration": [20.0, 30.0], "solved": [27.0, 37.0], "html": [1.5, None],
             "end": [29.0, 40.0], "CPU": [50.0, 52.0]}
    warm = {"notice": [False, False], "first iteration": [2.0, 2.2], "solved": [9.0, 9.4], "html": [1.4, 1.6],
            "end": [11.0, 11.5], "CPU": [12.0, 12.5]}
    text = first_solve.format_report({"fresh": fresh, "warm": warm}, "jump", "boxfddp")
    rows = {tuple(c.strip() for c in line.split("|")[1:3]): [c.strip() for c in line.split("|")[3:5]]
            for line in text.splitlines() if line.startswith("| fresh") or line.startswith("| warm")}
    assert rows[("fresh", "first iteration")] == ["25.00", "20.00, 30.00"]
    assert rows[("fresh", "html")] == ["1.50", "1.50, -"] and rows[("fresh", "notice")] == ["yes", "yes, yes"]
    assert rows[("warm", "notice")] == ["no", "no, no"] and rows[("warm", "CPU")] == ["12.25", "12.00, 12.50"]
    assert "`crocopy solve jump --solver boxfddp --html FILE`" in text
