"""``crocopy bench --latency`` (crocopy.bench.latency): the first iteration line is recognised in the
verbose table, a launch is timed up to it and then stopped, and the report lists every sample."""

from __future__ import annotations

import io
import os
import sys
import time
from contextlib import redirect_stdout

import pytest

import crocopy
from crocopy.bench import latency
from crocopy.problems import registry


def test_the_first_iteration_line_of_the_verbose_table_is_recognised():
    problem, xs, us = registry.get("quad-goal").build(crocopy)
    solver = crocopy.SolverFDDP(problem)
    solver.setCallbacks([crocopy.CallbackVerbose()])
    out = io.StringIO()
    with redirect_stdout(out):
        solver.solve(xs, us, 3, False)
    lines = out.getvalue().splitlines()
    matching = [i for i, line in enumerate(lines) if latency.ITERATION_LINE.match(line)]
    assert matching == [1]  # the header (line 0) does not match, iteration 0 does, iterations 1 and 2 do not
    assert lines[1].split()[0] == "0"


def test_a_launch_is_timed_to_its_first_iteration_line_then_stopped(tmp_path):
    marker = tmp_path / "still-running"
    script = ("import time, pathlib\nprint('compiling kernels (first run only) ...')\nprint('iter cost')\n"
              "print('   0  1.000e+00  2.000e+00')\ntime.sleep(1.0)\n"
              f"pathlib.Path({str(marker)!r}).write_text('x')\n")
    launch = latency.time_first_iteration([sys.executable, "-c", script], os.environ)
    assert launch.notice is not None and launch.first_iteration is not None
    assert launch.notice <= launch.first_iteration and launch.cpu is not None
    assert launch.output == ["compiling kernels (first run only) ...", "iter cost", "   0  1.000e+00  2.000e+00"]
    time.sleep(1.5)
    assert not marker.exists()  # killed at the line, before it could go on


def test_a_launch_without_iteration_line_reports_none():
    launch = latency.time_first_iteration([sys.executable, "-c", "print('error: no such problem')"], os.environ)
    assert launch.first_iteration is None and launch.notice is None
    assert launch.output == ["error: no such problem"]


def test_report_gives_medians_and_every_sample():
    text = latency.format_report({"fresh": [20.0, 18.0, 30.0], "fresh notice": [1.0, None, 1.2],
                                  "warm": [1.5, 1.7, 1.6], "warm notice": [None, None, None]}, "jump", "boxfddp")
    rows = {line.split("|")[1].strip(): [c.strip() for c in line.split("|")[2:4]]
            for line in text.splitlines() if line.startswith("| ") and "measure" not in line}
    assert rows["fresh"] == ["20.00", "20.00, 18.00, 30.00"]
    assert rows["fresh notice"] == ["1.10", "1.00, -, 1.20"]
    assert rows["warm"][0] == "1.60" and rows["warm notice"] == ["never", "-, -, -"]
    assert "`crocopy solve jump --solver boxfddp --no-html`" in text


def test_the_console_script_of_this_environment_is_used():
    command = latency.crocopy_command()
    assert command[0].startswith(os.path.dirname(sys.executable))


@pytest.mark.skipif(not os.path.isdir("/proc"), reason="cpu_seconds reads Linux /proc")
def test_cpu_seconds_of_a_running_process():
    spent = latency.cpu_seconds(os.getpid())
    assert spent is not None
    burn = time.process_time() + 0.3
    while time.process_time() < burn:
        pass
    assert latency.cpu_seconds(os.getpid()) >= spent + 0.25


def test_cpu_seconds_of_no_process_is_none():
    assert latency.cpu_seconds(2**22 + 12345) is None
