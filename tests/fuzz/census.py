"""Census of bad inputs at crocopy's public boundary (issue 27): every case, one outcome.

Run ``python tests/fuzz/census.py`` (``-v`` lists the cases that are not clear errors).  It enumerates
without randomness (the cases are in ``census_cases.py``, the bad values here) bad values for the
arguments of the public constructors, setters and
``calc``/``calcDiff``/state operations of the core and multibody models (wrong shapes, NaN/inf,
strings, complex, booleans, ``None``, impossible bounds, non-rotations, wrong key types), plus valid
but extreme points (``±1e300``), and classifies each call:

``clear``
    ``ValueError``/``TypeError``/``KeyError`` whose message names the argument;
``unclear``
    any other exception, or one whose message does not name the argument;
``accepted``
    a bad value taken without an error (NumPy's ``ComplexWarning`` does not count as an error);
``silent-nonfinite`` / ``warned-nonfinite``
    NaN or inf in the result, without / with a :class:`crocopy.validation.NonFiniteWarning`;
``ok``
    an extreme but valid point answered with a finite result (or refused clearly);
``hang`` / ``crash``
    no answer within :data:`CASE_SECONDS`, or the process died (the cases run in a worker process
    that is restarted after the case that killed it).
"""

from __future__ import annotations

import collections
import json
import os
import re
import signal
import subprocess
import sys
import warnings
from collections.abc import Callable
from typing import Any

import numpy as np

CASE_SECONDS = 120
OUTCOMES = ("clear", "ok", "unclear", "accepted", "silent-nonfinite", "warned-nonfinite", "hang", "crash")


# ------------------------------------------------------------------ bad values, by kind of argument
def bad_vectors(n: int) -> list[tuple[str, Any]]:
    z = np.zeros(n)
    with_nan, with_inf = z.copy(), z.copy()
    if n:
        with_nan[-1], with_inf[-1] = np.nan, np.inf
    out = [("short", np.zeros(max(n - 1, 0)) if n > 1 else np.zeros(n + 2)), ("long", np.zeros(n + 1)),
           ("matrix", np.zeros((n, 2))), ("strings", ["1"] * n if n else ["1"]), ("text", "abc"),
           ("complex", z + 1j), ("complex-real", z.astype(complex)), ("bool", np.ones(n, bool)), ("none", None),
           ("float", 0.5), ("int", 1), ("dict", {}), ("object", np.array([object()] * max(n, 1), dtype=object)),
           ("ragged", [[1.0], [1.0, 2.0]])]
    if n:
        out += [("nan", with_nan), ("inf", with_inf)]
    return out


def sizeless(values: list[tuple[str, Any]]) -> list[tuple[str, Any]]:
    """``values`` without the wrong lengths, for an argument that sets the dimension (weights, ``uref``)."""
    return [b for b in values if b[0] not in ("short", "long")]


NUMBERS = [("nan", np.nan), ("inf", np.inf), ("-inf", -np.inf), ("string", "1"), ("none", None), ("bool", True),
           ("complex", 1j), ("list", [1.0, 2.0]), ("array", np.array([1.0, 2.0]))]
NEGATIVE = [("negative", -1.0)]
COUNTS = [("negative", -1), ("float", 1.5), ("bool", True), ("string", "3"), ("none", None), ("list", [3]),
          ("complex", 3j)]
FRAMES = [("true", True), ("false", False), ("float", 1.0), ("np-float", np.float64(2.0)), ("unknown", "no_frame"),
          ("none", None), ("negative", -1), ("huge", 10**6), ("list", [1]), ("bytes", b"x"), ("complex", 1j)]
KEYS = [("true", True), ("int", 1), ("float", 1.0), ("none", None), ("tuple", ("a",)), ("bytes", b"x")]
BOOLS = [("string", "yes"), ("two", 2), ("float", 0.5), ("none", None), ("list", [True]), ("array", np.ones(2, bool))]


def bad_rotations() -> list[tuple[str, Any]]:
    shear = np.eye(3)
    shear[0, 1] = 0.5
    return [("reflection", np.diag([1.0, 1.0, -1.0])), ("minus-identity", -np.eye(3)), ("scaled", 2 * np.eye(3)),
            ("shear", shear), ("nan", np.full((3, 3), np.nan)), ("shape", np.eye(2)), ("complex", np.eye(3) + 0j),
            ("none", None), ("float", 1.0), ("strings", [["1"] * 3] * 3), ("near", np.eye(3) + 1e-3)]


def bad_placements() -> list[tuple[str, Any]]:
    import pinocchio as pin

    out = [(name, pin.SE3(R, np.zeros(3))) for name, R in bad_rotations()[:4]]
    nan = pin.SE3.Identity()
    nan.translation = np.array([0.0, np.nan, 0.0])
    return out + [("nan", nan), ("matrix", np.eye(4)), ("none", None), ("string", "x")]


def bad_spatial(cls_name: str, n: int = 6) -> list[tuple[str, Any]]:
    import pinocchio as pin

    nan = getattr(pin, cls_name)(np.full(n, np.nan))
    return [("vector", np.zeros(n)), ("none", None), ("nan", nan), ("string", "x")]


FRAME_TYPES = [("int", 0), ("string", "LOCAL"), ("none", None), ("bool", True)]


# ------------------------------------------------------------------ fixtures
def robot(name: str) -> Any:
    sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))
    from robots import load

    return load(name)


def mb_state(name: str = "solo12") -> Any:
    import crocopy

    return crocopy.StateMultibody(robot(name))


def mb_point(state: Any) -> np.ndarray:
    import pinocchio as pin

    return np.concatenate([pin.neutral(state.pinocchio), np.zeros(state.nv)])


def pinocchio_collector(state: Any) -> Any:
    import pinocchio as pin

    import crocopy

    pdata = pin.Data(state.pinocchio)
    x = mb_point(state)
    pin.forwardKinematics(state.pinocchio, pdata, x[: state.nq], x[state.nq:])
    pin.computeJointJacobians(state.pinocchio, pdata)
    pin.updateFramePlacements(state.pinocchio, pdata)
    return crocopy.DataCollectorMultibody(pdata)


# ------------------------------------------------------------------ the cases
Case = tuple[str, str, str, Callable[[], Any], bool, Any]
"""(target, argument, label, call, valid, value): ``call()`` returns what to scan for NaN/inf (or None)."""


# ------------------------------------------------------------------ classification
class _Hang(Exception):
    pass


QUANTITIES = ("cost", "r", "Rx", "Ru", "a_value", "Ar", "Arr", "Lx", "Lu", "Lxx", "Luu", "Lxu", "Fx", "Fu", "xnext",
              "tau", "dtau_dx", "dtau_du")
"""Results of a data scanned for NaN and inf; any other array of a returned object is scanned for NaN only
(a bound may be infinite)."""


def _has(value: Any, test: Callable[[np.ndarray], np.ndarray]) -> bool:
    try:
        arr = np.asarray(value)
    except Exception:  # noqa: BLE001 - not an array
        return False
    return arr.dtype.kind in "fc" and bool(np.any(test(arr)))


def _nonfinite(obj: Any) -> bool:
    if not hasattr(obj, "__dict__"):
        return any(_has(v, lambda a: ~np.isfinite(a)) for v in (obj if isinstance(obj, tuple | list) else [obj]))
    return (any(_has(getattr(obj, q, None), lambda a: ~np.isfinite(a)) for q in QUANTITIES)
            or any(_has(v, np.isnan) for v in vars(obj).values()))


def names_argument(message: str, name: str) -> bool:
    return re.search(rf"(?<![A-Za-z_]){re.escape(name)}(?![A-Za-z_])", message) is not None


def classify(arg: str, call: Callable[[], Any], valid: bool, value: Any = None) -> tuple[str, str]:
    """The outcome of ``call()`` for argument ``arg`` (a ``KeyError`` quoting the unknown key ``value``
    is clear too) and a detail (the error or warnings)."""
    from crocopy.validation import NonFiniteWarning

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        signal.alarm(CASE_SECONDS)
        try:
            out = call()
        except _Hang:
            return "hang", ""
        except (ValueError, TypeError, KeyError) as exc:
            text = f"{type(exc).__name__}: {exc}"
            quoted = isinstance(exc, KeyError) and isinstance(value, str) and repr(value) in str(exc)
            return ("clear" if quoted or names_argument(str(exc), arg) else "unclear"), text
        except Exception as exc:  # noqa: BLE001 - what the census counts
            return "unclear", f"{type(exc).__name__}: {exc}"
        finally:
            signal.alarm(0)
    if out is not None and _nonfinite(out):
        warned = any(issubclass(w.category, NonFiniteWarning) for w in caught)
        return ("warned-nonfinite" if warned else "silent-nonfinite"), ""
    return ("ok" if valid else "accepted"), "; ".join(str(w.message) for w in caught)[:100]


def _raise_hang(signum: int, frame: Any) -> None:
    raise _Hang


def worker(start: int) -> None:
    """Run the cases from ``start`` on, one JSON line each."""
    from census_cases import cases

    signal.signal(signal.SIGALRM, _raise_hang)
    all_cases = cases()
    print(json.dumps(["total", len(all_cases)]), flush=True)
    for i in range(start, len(all_cases)):
        target, arg, label, call, valid, value = all_cases[i]
        outcome, detail = classify(arg, call, valid, value)
        print(json.dumps([i, target, arg, label, outcome, detail]), flush=True)


def run() -> list[list]:
    """Every case's ``[i, target, argument, label, outcome, detail]``, each worker in its own process."""
    rows: list[list] = []
    start, total = 0, None
    while total is None or start < total:
        done = subprocess.run([sys.executable, __file__, "--worker", str(start)], capture_output=True, text=True,
                              env={**os.environ, "OMP_NUM_THREADS": "1"}, check=False)
        lines = [json.loads(line) for line in done.stdout.splitlines()]
        if not lines or lines[0][0] != "total":
            raise RuntimeError(f"the census worker failed before its first case:\n{done.stderr}")
        total = lines[0][1]
        rows += lines[1:]
        start = rows[-1][0] + 1 if rows else 0
        if start < total:  # the worker died in case ``start``
            rows.append([start, "?", "?", "?", "crash", " ".join(done.stderr.strip().splitlines()[-1:])])
            start += 1
    return rows


def main(argv: list[str]) -> int:
    if argv[:1] == ["--worker"]:
        worker(int(argv[1]))
        return 0
    rows = run()
    counts = collections.Counter(row[4] for row in rows)
    print(f"{len(rows)} cases: " + ", ".join(f"{k} {counts.get(k, 0)}" for k in OUTCOMES))
    if "-v" in argv:
        for row in rows:
            if row[4] not in ("clear", "ok"):
                print(f"  {row[4]:17s} {row[1]}({row[2]}={row[3]}) {row[5]}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
