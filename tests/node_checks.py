"""Checks shared by the compiled-node tests: a compiled node against the Python node, and against central
differences of its own ``calc``; solvers with and without compiled nodes."""

from __future__ import annotations

import numpy as np
import pytest

import crocopy

FIELDS = ("xnext", "Fx", "Fu", "Lx", "Lu", "Lxx", "Lxu", "Luu")
"""The node data fields a compiled ``calcDiff`` writes (a terminal node: ``xnext``, ``Fx``, ``Lx``, ``Lxx``)."""


def compare_with_python_node(iam, x: np.ndarray, u: np.ndarray, terminal: bool, rtol: float, atol: float,
                             cost_rel: float) -> None:
    """The compiled node's ``calcDiff`` and ``calc`` at ``(x, u)`` equal the Python node's: ``rtol`` and an
    absolute tolerance of ``atol`` times the field's largest entry (at least 1); costs to ``cost_rel``."""
    fast, slow = iam.createData(), iam.createData()
    evaluator = iam._compiled_node(fast, terminal, {})
    assert evaluator is not None
    uu = None if terminal else u
    evaluator.calcDiff(x, uu, False)
    iam.calc(slow, x, uu)
    iam.calcDiff(slow, x, uu)
    assert fast.cost == pytest.approx(slow.cost, rel=cost_rel, abs=1e-12)
    for name in ("xnext", "Fx", "Lx", "Lxx") if terminal else FIELDS:
        a, b = getattr(fast, name), getattr(slow, name)
        np.testing.assert_allclose(a, b, rtol=rtol, atol=atol * max(1.0, np.abs(b).max(initial=0.0)), err_msg=name)
    other = iam.createData()
    evaluator.calc(x, uu)
    iam.calc(other, x, uu)
    assert fast.cost == pytest.approx(other.cost, rel=1e-10, abs=1e-12)
    np.testing.assert_allclose(fast.xnext, other.xnext, rtol=1e-10, atol=1e-12)


def check_new_evaluator(iam, data, x: np.ndarray, u: np.ndarray) -> None:
    """An evaluator of ``(iam, data)`` made now (after the caller changed the model's parameters) gives the Python
    node's cost, ``Fx`` and ``Fu`` at ``(x, u)``: it read the parameters again."""
    iam._compiled_node(data, False, {}).calcDiff(x, u, False)
    slow = iam.createData()
    iam.calc(slow, x, u)
    iam.calcDiff(slow, x, u)
    assert data.cost == pytest.approx(slow.cost, rel=1e-9)
    for name in ("Fx", "Fu"):
        a, b = getattr(data, name), getattr(slow, name)
        np.testing.assert_allclose(a, b, rtol=1e-7, atol=1e-7 * np.abs(b).max(), err_msg=name)


def check_finite_differences(iam, state, x: np.ndarray, u: np.ndarray, h: float, atol: float,
                             roundoff: float = 0.0) -> None:
    """``Fx, Fu, Lx, Lu`` of the compiled node against central differences (step ``h``) of its own ``calc``:
    ``rtol = 1e-4``, Jacobian columns to ``atol`` times their largest entry (at least 1), gradients to ``atol``
    plus ``roundoff`` times the cost."""
    data = iam.createData()
    evaluator = iam._compiled_node(data, False, {})
    evaluator.calcDiff(x, u, False)
    Fx, Fu, Lx, Lu = (getattr(data, n).copy() for n in ("Fx", "Fu", "Lx", "Lu"))

    def at(dx, du):
        evaluator.calc(state.integrate(x, dx), u + du)
        return data.xnext.copy(), data.cost

    ndx, nu = state.ndx, iam.nu
    xnext0, cost = at(np.zeros(ndx), np.zeros(nu))
    for j in range(ndx + nu):
        e = np.zeros(ndx + nu)
        e[j] = h
        (xp, cp), (xm, cm) = at(e[:ndx], e[ndx:]), at(-e[:ndx], -e[ndx:])
        column = (state.diff(xnext0, xp) - state.diff(xnext0, xm)) / (2 * h)
        jac = Fx[:, j] if j < ndx else Fu[:, j - ndx]
        grad = Lx[j] if j < ndx else Lu[j - ndx]
        np.testing.assert_allclose(column, jac, rtol=1e-4, atol=atol * max(1.0, np.abs(jac).max()))
        assert (cp - cm) / (2 * h) == pytest.approx(grad, rel=1e-4, abs=atol + roundoff * abs(cost))


def make_solver(name: str, problem, compiled: bool = True):
    """crocopy's solver ``name`` on ``problem``; with ``compiled=False`` a subclass that does not opt in to compiled
    nodes, so its solves run the Python nodes."""
    cls = getattr(crocopy, name)
    if not compiled:
        cls = type("Uncompiled" + name, (cls,), {"_nodes_compiled": False})
    return cls(problem)


def failed_solve(problem, xs, us, compiled: bool, maxiter: int) -> tuple:
    """``(solved, iter, reason)`` of an FDDP solve that is expected to fail; the iterate and cost it keeps are
    checked finite."""
    s = make_solver("SolverFDDP", problem, compiled)
    solved = s.solve(xs, us, maxiter)
    assert all(np.isfinite(x).all() for x in s.xs) and all(np.isfinite(u).all() for u in s.us)
    assert np.isfinite(s.cost)
    return solved, s.iter, s.reason


def assert_same_solves(builds: list, maxiter: int = 30) -> None:
    """FDDP from each ``(problem, xs, us)`` of ``builds`` takes the same iterations to the same cost (1e-9)."""
    results = []
    for problem, xs, us in builds:
        solver = crocopy.SolverFDDP(problem)
        solver.solve(xs, us, maxiter)
        results.append((solver.iter, solver.cost))
    for iters, cost in results[1:]:
        assert iters == results[0][0]
        assert cost == pytest.approx(results[0][1], rel=1e-9)


PINOCCHIO_FIELDS = ("oMi", "oMf", "liMi", "v", "ov", "oa", "f", "of", "M", "nle", "tau", "ddq", "com", "vcom", "J", "h")
"""The Pinocchio data fields :func:`data_values` reads.  Not ``a``: after ``aba`` in the LOCAL convention it keeps
values of the previous call (two ``calc`` at one point after one elsewhere differ there, crocopy or not)."""


def data_values(problem) -> dict[str, np.ndarray]:
    """Every number the node datas of ``problem`` hold, by path (``"d3.differential.costs.cost"``): arrays, floats,
    Pinocchio placements, motions, forces and the :data:`PINOCCHIO_FIELDS` of a Pinocchio data, walking the
    attributes and properties of crocopy's data objects (each object once).  Not the compiled nodes' stamps.  The
    datas are read twice and the second reading returned: a field brought up to date when another is read (a
    contact's ``f_local`` and ``fext``, when the contact set's ``fext`` is) shows its value whatever the order."""
    import pinocchio as pin

    values: dict[str, np.ndarray] = {}
    seen: set[int] = set()

    def walk(obj, path: str) -> None:
        if isinstance(obj, np.ndarray):
            values[path] = obj.copy()
        elif isinstance(obj, (float, int, np.floating)) and not isinstance(obj, bool):
            values[path] = np.array(float(obj))
        elif isinstance(obj, pin.SE3):
            values[path] = obj.homogeneous.copy()
        elif isinstance(obj, (pin.Motion, pin.Force)):
            values[path] = obj.vector.copy()
        elif id(obj) in seen:
            return
        elif isinstance(obj, pin.Data):
            seen.add(id(obj))
            for name in PINOCCHIO_FIELDS:
                field = getattr(obj, name)
                items = field if hasattr(field, "__len__") and not isinstance(field, np.ndarray) else [field]
                for i, item in enumerate(items):
                    walk(item, f"{path}.{name}[{i}]")
        elif isinstance(obj, (list, tuple)):
            for i, item in enumerate(obj):
                walk(item, f"{path}[{i}]")
        elif isinstance(obj, dict):
            for key, item in obj.items():
                walk(item, f"{path}[{key!r}]")
        elif type(obj).__module__.startswith("crocopy."):
            seen.add(id(obj))
            names = set(getattr(obj, "__dict__", {}))
            for cls in type(obj).__mro__:
                names |= set(getattr(cls, "__slots__", ()))
                names |= {k for k, v in vars(cls).items() if isinstance(v, property)}
            for name in sorted(names - {"compiled_stamp"}):
                if name.startswith("__"):
                    continue
                try:
                    item = getattr(obj, name)
                except Exception:  # a property with nothing to show for this data
                    continue
                if not callable(item):
                    walk(item, f"{path}.{name}")

    for _ in range(2):
        values.clear()
        seen.clear()
        for t, data in enumerate([*problem.runningDatas, problem.terminalData]):
            walk(data, f"d{t}")
    return values
