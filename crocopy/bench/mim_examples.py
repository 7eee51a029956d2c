"""``crocopy bench --mim-examples``: mim-solvers' own Python examples, run with crocopy in its place.

mim-solvers' wheel has no examples; its source distribution on PyPI has them (``examples/ur5.py``,
``solo12.py`` with its ``utils_solo12.py``, ``humanoid_taichi.py``).  The sdist named by
:data:`SDIST` is fetched once from the simple index :data:`SIMPLE_INDEX` (its sha256, given by the
index link, must be :data:`SDIST_SHA256`), kept in the user cache folder
(:func:`crocopy.user_cache.user_cache_dir`, ``mim-solvers/``) and checked again at each later use.
Its ``examples/*.py`` are extracted into a temporary folder and only executed, never read or copied.

Each run of :data:`JOBS` (a script and its command-line words) is made twice, each time in its own
subprocess with a timeout, ``MPLBACKEND=Agg`` and no display (the machinery of :mod:`crocopy.bench.compat`;
a script that opens a viewer ends there: ``ur5.py`` opens one and then loops forever):

- with ``sys.modules["crocoddyl"]`` bound to crocopy (``crocoddyl.utils`` is the Crocoddyl wheel's
  folder, executed on crocopy) and ``sys.modules["mim_solvers"]`` bound to :mod:`crocopy.mim_solvers`;
- with Crocoddyl 3.2.1 and mim-solvers 0.3.0 themselves (the ``bench`` extra, whose ``numpy<2.4`` lets
  ``solo12``'s friction-cone residual write its 1-element array into Crocoddyl's residual vector).

Every outermost ``solve`` call is recorded: solver class, iterations, final cost, and the KKT
residual when the solver has one.  The report is a markdown table: does the run end with crocopy (or
its first error), does it end as mim-solvers' run does (also both at the same error on the same line),
crocopy's solves next to mim-solvers', and the largest relative cost difference over the solves both
runs made.
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import hashlib
import html.parser
import json
import os
import pathlib
import runpy
import sys
import tarfile
import tempfile
import time
import types
import urllib.parse
import urllib.request
from collections.abc import Callable, Iterable, Sequence
from typing import Any

from ..user_cache import user_cache_dir
from . import compat
from .compat import RunResult
from .side_by_side import BenchDependencyError, require_crocoddyl

SIMPLE_INDEX = "https://pypi.org/simple/mim-solvers/"
SDIST = "mim_solvers-0.3.0.tar.gz"
SDIST_SHA256 = "1663defe2f59f8e4e657237e175a3ca20d8903a521a6d4dc562146ab4a029059"
"""The sha256 of :data:`SDIST` as PyPI's simple index gives it (a release file never changes)."""
SCRIPTS = ("ur5", "solo12", "humanoid_taichi")
"""mim-solvers' example scripts (``utils_solo12.py`` is a module of ``solo12``)."""
JOBS: dict[str, tuple[str, tuple[str, ...]]] = {
    "ur5": ("ur5", ()),
    "solo12": ("solo12", ()),
    "humanoid_taichi": ("humanoid_taichi", ("plot",)),
    "humanoid_taichi-fddp": ("humanoid_taichi", ("plot", "use_fddp")),
}
"""Runs, in report order: name → (script, its command-line words).  ``humanoid_taichi`` reads ``plot``
(draw the solution with ``crocoddyl.utils.biped.plotSolution``) and ``use_fddp`` (Crocoddyl's
``SolverFDDP`` instead of ``SolverSQP``) from ``sys.argv``."""
TIMEOUT = 900.0
DOWNLOAD_TIMEOUT = 60.0
LIBRARIES = ("crocopy", "mim_solvers")


class SdistError(RuntimeError):
    """mim-solvers' sdist could not be fetched or does not have the expected content."""


# ------------------------------------------------------------------------------------ the sdist
class _Links(html.parser.HTMLParser):
    """The ``href`` of every ``<a>`` of a PEP 503 simple index page, by the link's text."""

    def __init__(self) -> None:
        super().__init__()
        self.links: dict[str, str] = {}
        self._href: str | None = None

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        if tag == "a":
            self._href = dict(attrs).get("href")

    def handle_data(self, data: str) -> None:
        if self._href is not None and data.strip():
            self.links[data.strip()] = self._href
            self._href = None


def sdist_url(index_page: str, base: str = SIMPLE_INDEX) -> tuple[str, str]:
    """The download URL of :data:`SDIST` in a simple index page and the sha256 its link gives.

    Raises
    ------
    SdistError
        If the page has no link to :data:`SDIST`, or the link carries no ``#sha256=`` fragment.
    """
    parser = _Links()
    parser.feed(index_page)
    href = parser.links.get(SDIST)
    if href is None:
        raise SdistError(f"{base} lists no {SDIST}")
    url, _, fragment = urllib.parse.urljoin(base, href).partition("#")
    digest = urllib.parse.parse_qs(fragment).get("sha256", [""])[0]
    if not digest:
        raise SdistError(f"the link to {SDIST} on {base} gives no sha256 ({href!r})")
    return url, digest


def _sha256(path: pathlib.Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _get(url: str) -> bytes:
    try:
        with urllib.request.urlopen(url, timeout=DOWNLOAD_TIMEOUT) as response:  # noqa: S310 - https URLs only
            return response.read()
    except OSError as exc:
        raise SdistError(f"could not download {url}: {exc}") from None


def fetch_sdist(cache: pathlib.Path | None = None, get: Callable[[str], bytes] = _get,
                expected: str = SDIST_SHA256) -> pathlib.Path:
    """The path of :data:`SDIST` in ``cache`` (default: ``user_cache_dir("mim-solvers")``), downloaded
    first when it is not there or its sha256 is not ``expected``.

    ``get(url) -> bytes`` fetches a URL (the index page, then the file).

    Raises
    ------
    SdistError
        If the index or the file cannot be fetched, the index link's sha256 is not ``expected``, or the
        downloaded bytes do not hash to it.
    """
    cache = cache or user_cache_dir("mim-solvers")
    path = cache / SDIST
    if path.is_file() and _sha256(path) == expected:
        return path
    url, digest = sdist_url(get(SIMPLE_INDEX).decode("utf-8", "replace"))
    if digest != expected:
        raise SdistError(f"{SIMPLE_INDEX} gives sha256 {digest} for {SDIST}, expected {expected}")
    data = get(url)
    got = hashlib.sha256(data).hexdigest()
    if got != digest:
        raise SdistError(f"{url}: downloaded {len(data)} bytes with sha256 {got}, the index gives {digest}")
    cache.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(f"{path.name}.{os.getpid()}.part")
    partial.write_bytes(data)
    os.replace(partial, path)
    return path


def extract_examples(sdist: pathlib.Path, dest: pathlib.Path) -> pathlib.Path:
    """Extract the sdist's ``examples/*.py`` into ``dest``; returns the folder holding them.

    Raises
    ------
    SdistError
        If a script of :data:`SCRIPTS` is missing from the archive.
    """
    with tarfile.open(sdist, "r:gz") as archive:
        members = [m for m in archive.getmembers() if m.isfile() and pathlib.PurePosixPath(m.name).parent.name
                   == "examples" and m.name.endswith(".py") and len(pathlib.PurePosixPath(m.name).parts) == 3]
        for member in members:
            member.name = pathlib.PurePosixPath(member.name).name
            archive.extract(member, dest, filter="data")
    missing = [s for s in SCRIPTS if not (dest / f"{s}.py").is_file()]
    if missing:
        raise SdistError(f"{sdist.name} has no examples/{', examples/'.join(f'{s}.py' for s in missing)}")
    return dest


def jobs(names: Sequence[str] | None = None) -> list[str]:
    """The runs to make: every one of :data:`JOBS`, or ``names`` among them (``KeyError`` naming the unknown)."""
    if not names:
        return list(JOBS)
    unknown = [n for n in names if n not in JOBS]
    if unknown:
        raise KeyError(f"unknown mim-solvers example run(s) {unknown}; known: {', '.join(JOBS)}")
    return list(names)


# ----------------------------------------------------------------------------------- in the child
def bind_crocopy() -> None:
    """``import crocoddyl`` gives crocopy (as in :func:`crocopy.bench.compat.bind_crocopy`) and
    ``import mim_solvers`` gives :mod:`crocopy.mim_solvers`."""
    compat.bind_crocopy(compat.crocoddyl_folder())
    import crocopy.mim_solvers

    sys.modules["mim_solvers"] = crocopy.mim_solvers


def record_solves(modules: Iterable[types.ModuleType], sink: list[dict[str, Any]]) -> None:
    """Record each outermost ``solve`` of every solver class the ``modules`` export (each class once)
    into ``sink`` (:func:`crocopy.bench.compat.record_solves`), with its ``KKT`` when it has one."""
    classes: dict[int, type] = {}
    for module in modules:
        for name in dir(module):
            cls = getattr(module, name, None)
            if name.startswith("Solver") and isinstance(cls, type):
                classes.setdefault(id(cls), cls)
    unique = types.SimpleNamespace(**{f"Solver{k}": cls for k, cls in enumerate(classes.values())})
    compat.record_solves(unique, sink)
    for cls in classes.values():
        if "solve" in cls.__dict__:
            cls.solve = _with_kkt(cls.__dict__["solve"], sink)


def _with_kkt(recorded: Callable, sink: list[dict[str, Any]]) -> Callable:
    def solve(self, *args, **kwargs):
        before = len(sink)
        converged = recorded(self, *args, **kwargs)
        if len(sink) > before and "KKT" not in sink[-1]:
            kkt = getattr(self, "KKT", None)
            sink[-1]["KKT"] = float(kkt) if kkt is not None else None
        return converged

    return solve


DISPLAYS = ("MeshcatDisplay", "GepettoDisplay", "RvizDisplay")
"""The viewer classes a script may open (``ur5.py`` opens a ``MeshcatDisplay`` unconditionally and then
loops forever, showing its solution)."""


class DisplayReached(Exception):
    """Raised when a script creates a viewer: what follows only shows the solution, so its run ends there."""


def disable_displays(lib: types.ModuleType) -> None:
    """Make each viewer class of :data:`DISPLAYS` that ``lib`` has raise :class:`DisplayReached`."""
    for name in DISPLAYS:
        if hasattr(lib, name):
            setattr(lib, name, functools.partial(_reach_display, name))


def _reach_display(name: str, *args: Any, **kwargs: Any) -> None:
    raise DisplayReached(f"ends at its {name} (no display)")


def run_child(library: str, job: str, folder: str, result_file: str) -> int:
    """Run the script of ``job`` (in ``folder``) as ``__main__`` with one library in this process, with the
    job's command-line words and the folder first on ``sys.path`` (as ``python script.py plot`` would), and
    write its :class:`~crocopy.bench.compat.RunResult` as JSON."""
    if library == "crocopy":
        bind_crocopy()
    import crocoddyl  # mim-solvers needs Crocoddyl imported first
    import matplotlib.pyplot as plt
    import mim_solvers

    plt.show = lambda *args, **kwargs: None
    disable_displays(crocoddyl)
    result = RunResult(ok=False)
    record_solves([crocoddyl, mim_solvers], result.solves)
    script, words = JOBS[job]
    path = pathlib.Path(folder) / f"{script}.py"
    sys.argv = [str(path), *words]
    sys.path.insert(0, folder)
    start = time.perf_counter()
    try:
        runpy.run_path(str(path), run_name="__main__")
        result.ok = True
    except DisplayReached as exc:
        result.ok, result.where = True, str(exc)
    except SystemExit as exc:
        result.ok = exc.code in (None, 0)
        if not result.ok:
            result.error = f"SystemExit: {exc.code}"
    except BaseException as exc:  # noqa: BLE001 - any failure of the script is the measurement
        result.error, result.where = compat.first_error_line(exc), compat._where(exc, pathlib.Path(folder))
    result.seconds = time.perf_counter() - start
    pathlib.Path(result_file).write_text(json.dumps(dataclasses.asdict(result)), encoding="utf-8")
    return 0


# ---------------------------------------------------------------------------------- in the parent
def run_job(library: str, job: str, folder: pathlib.Path, timeout: float = TIMEOUT) -> RunResult:
    """Run ``job`` (its script in ``folder``) with ``library`` in a subprocess (:func:`.compat.run_in_subprocess`)."""
    return compat.run_in_subprocess("crocopy.bench.mim_examples", (library, job, str(folder)), timeout)


def require_mim_solvers() -> None:
    """Crocoddyl and mim-solvers of the bench extra (``BenchDependencyError`` naming it otherwise)."""
    require_crocoddyl()
    try:
        import mim_solvers  # noqa: F401
    except ImportError as exc:
        raise BenchDependencyError(f"crocopy bench --mim-examples needs mim-solvers 0.3.0 ({exc}): "
                                   "pip install 'crocopy[bench]'") from None


def run_mim_examples(names: Sequence[str] | None = None, timeout: float = TIMEOUT, reference: bool = True,
                     cache: pathlib.Path | None = None,
                     progress: Callable[[str], None] | None = None) -> list[compat.Row]:
    """Every run of :data:`JOBS` (or ``names``) with crocopy and, if ``reference``, with mim-solvers; a
    :class:`~crocopy.bench.compat.Row` each (its ``crocoddyl`` run is mim-solvers')."""
    wanted = jobs(names)
    require_mim_solvers()
    sdist = fetch_sdist(cache)
    rows = []
    with tempfile.TemporaryDirectory(prefix="crocopy-mim-sdist-") as tmp:
        folder = extract_examples(sdist, pathlib.Path(tmp))
        for job in wanted:
            mine = run_job("crocopy", job, folder, timeout)
            theirs = run_job("mim_solvers", job, folder, timeout) if reference else None
            rows.append(compat.Row(job, mine, theirs))
            if progress:
                progress(format_row(rows[-1]))
    return rows


# ------------------------------------------------------------------------------------------ table
HEADER = ("| run | runs to its end with crocopy | ends as mim-solvers' run | crocopy solves | mim-solvers solves | "
          "relative cost difference | seconds, crocopy / mim-solvers |")


def same_end(mine: RunResult, theirs: RunResult | None) -> bool | None:
    """Whether both runs ended alike: both to their end, or both at the same error on the same line of the
    script (``None`` without a reference run)."""
    if theirs is None:
        return None
    if mine.ok or theirs.ok:
        return mine.ok and theirs.ok
    line = [(r.where or "").split("; ")[0] for r in (mine, theirs)]
    return mine.error == theirs.error and line[0] == line[1] != ""


def _solves(result: RunResult | None) -> str:
    """``Solver: iter it, cost c, KKT k`` per solve (the last two of many), ``-`` when none."""
    if result is None or not result.solves:
        return "-"

    def one(s: dict[str, Any]) -> str:
        kkt = f", KKT {s['KKT']:.3e}" if s.get("KKT") is not None else ""
        return f"{s['solver']}: {s['iter']} it, cost {s['cost']:.10g}{kkt}"

    shown = result.solves if len(result.solves) <= 2 else result.solves[-2:]
    more = f"{len(result.solves)} solves, the last: " if len(result.solves) > 2 else ""
    return more + "; ".join(one(s) for s in shown)


def _status(result: RunResult) -> str:
    """``yes`` (with where it stopped showing, if it did), or ``no:`` and the first error."""
    return "yes" + (f" ({result.where})" if result.where else "") if result.ok else compat._status(result)


def format_row(row: compat.Row) -> str:
    mine, theirs = row.crocopy, row.crocoddyl
    diff = compat.relative_difference(mine, theirs)
    counts = (len(mine.solves), len(theirs.solves) if theirs is not None else 0)
    solves = f" ({counts[0]} vs {counts[1]} solves)" if diff is not None and counts[0] != counts[1] else ""
    same = "yes" if mine.ok else "yes: mim-solvers' own run stops at this error too"
    alike = {None: "-", True: same, False: "no" + (f" (its run: {_status(theirs)})" if theirs else "")}
    seconds = f"{mine.seconds:.1f} / " + (f"{theirs.seconds:.1f}" if theirs is not None else "-")
    cells = [row.name, _status(mine), alike[same_end(mine, theirs)], _solves(mine), _solves(theirs),
             ("-" if diff is None else f"{diff:.1e}") + solves, seconds]
    return "| " + " | ".join(cell.replace("|", "\\|") for cell in cells) + " |"


def format_table(rows: Sequence[compat.Row]) -> str:
    """The markdown report: a summary line, then one row per run."""
    ok = sum(r.crocopy.ok for r in rows)
    alike = sum(bool(same_end(r.crocopy, r.crocoddyl)) for r in rows)
    upstream = sum(bool(same_end(r.crocopy, r.crocoddyl)) and not r.crocopy.ok for r in rows)
    compared = sum(r.crocoddyl is not None for r in rows)
    version = SDIST.removeprefix("mim_solvers-").removesuffix(".tar.gz")
    lines = [
        "## mim-solvers' own examples with crocopy (`crocopy bench --mim-examples`)",
        "",
        f"{ok} of {len(rows)} runs of mim-solvers {version}'s examples (from its sdist) end with `crocoddyl` bound "
        f"to crocopy and `mim_solvers` to `crocopy.mim_solvers`; {alike} of {compared} end as mim-solvers' runs do"
        + (f" ({upstream} of these stopping at the same error with mim-solvers and Crocoddyl themselves: the example "
           "is broken upstream)." if upstream else "."),
        "",
        HEADER,
        "|" + "---|" * HEADER.count(" | ") + "---|",
        *(format_row(r) for r in rows),
    ]
    return "\n".join(lines) + "\n"


def run_mim_examples_cli(names: Sequence[str] | None, out: str | None) -> int:
    """The ``crocopy bench --mim-examples`` command: run, print the table, write it to ``out``."""
    return compat.report_cli(run_mim_examples, format_table, names, out, (SdistError,))


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m crocopy.bench.mim_examples", description="a child run")
    parser.add_argument("--child", nargs=4, metavar=("LIBRARY", "JOB", "FOLDER", "RESULT"), required=True)
    args = parser.parse_args(argv)
    library, job, folder, result_file = args.child
    if library not in LIBRARIES or job not in JOBS:
        parser.error(f"LIBRARY must be one of {LIBRARIES}, JOB one of {tuple(JOBS)}")
    return run_child(library, job, folder, result_file)


if __name__ == "__main__":
    sys.exit(main())
