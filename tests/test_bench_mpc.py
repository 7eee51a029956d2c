"""``crocopy bench --mpc``: the cycles move every state reference and warm-start each solve from the last one."""

import numpy as np

import crocopy
from crocopy.bench import mpc
from crocopy.problems import registry


def test_cycles_move_every_state_reference_and_chain_the_solves():
    """Each cycle sets every state residual's reference (its last entry moved by -0.001, 0 or +0.001 in turn) and
    solves one iteration from the previous cycle's solution: the last cycle's solution is one iteration from the
    one before it on a problem holding the last references."""
    result = mpc.run_cycles(crocopy, "pend", cycles=2, warmup=1)
    problem, _, _ = registry.build("pend")
    assert result["T"] == problem.T and result["references"] == problem.T + 1
    assert result["ms"] > 0.0 and np.isfinite(result["cost"])
    start = mpc.run_cycles(crocopy, "pend", cycles=1, warmup=1)  # the same first two cycles
    references = [np.array(r.reference) for r in mpc.state_residuals(problem)]
    for r, reference in zip(mpc.state_residuals(problem), references):
        moved = reference.copy()
        moved[-1] += 1e-3  # the third cycle's shift (k = 2)
        r.reference = moved
    solver = crocopy.SolverFDDP(problem)
    solver.solve(start["xs"], start["us"], 1, False)
    assert solver.cost == result["cost"]
    for a, b in zip([*solver.xs, *solver.us], [*result["xs"], *result["us"]]):
        np.testing.assert_array_equal(a, b)


def test_table_has_a_row_per_problem_and_no_crocoddyl_column_without_it():
    table = mpc.run_mpc_bench(("pend",), cycles=1, crocoddyl=False)
    assert table.startswith(mpc.SECTION)
    rows = [line for line in table.splitlines() if line.startswith("| pend |")]
    assert len(rows) == 1
    cells = [c.strip() for c in rows[0].strip("|").split("|")]
    assert cells[1] == "100" and cells[2] == "101" and float(cells[3]) > 0.0 and cells[4] == "not run"
