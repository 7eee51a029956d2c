"""crocopy.bench.floor: the Pinocchio call timer and the floor table (crocopy side; no Crocoddyl needed)."""

import numpy as np
import pinocchio

import crocopy
from crocopy.bench.floor import PinocchioCallTimer, floor_of_problem, format_floor


def test_timer_counts_wrapped_calls_and_restores_the_module():
    aba = pinocchio.aba
    model = pinocchio.buildSampleModelManipulator()
    data = model.createData()
    q, v = pinocchio.neutral(model), np.zeros(model.nv)
    with PinocchioCallTimer() as timer:
        assert pinocchio.aba is not aba
        for _ in range(5):
            pinocchio.aba(model, data, q, v, v)
        assert timer.calls == 5
        assert timer.seconds > 0.0 and timer.pinocchio_seconds >= 0.0
    assert pinocchio.aba is aba


def test_floor_row_of_the_pendulum_and_its_table():
    row = floor_of_problem("pend", crocopy, None, repeats=1)
    assert row["T"] == 100 and row["crocoddyl"] is None
    assert row["crocopy"] > 0.0 and row["pinocchio"] > 0.0
    assert row["calls_per_node"] >= 2.0  # at least the dynamics and their derivatives on every running node
    table = format_floor([row])
    assert "| pend | 100 |" in table and table.splitlines()[-1].endswith("| — | — | — |")
