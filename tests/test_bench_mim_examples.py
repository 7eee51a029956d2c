"""``crocopy bench --mim-examples``: the sdist's download, check and cache, the extraction of its examples,
the solve recorder, the display stop, the table, the command's arguments and (bench extra) one child run
of a small script written here, with crocopy and with mim-solvers."""

from __future__ import annotations

import hashlib
import importlib.util
import io
import json
import sys
import tarfile
import textwrap
import types

import pytest

from crocopy.bench import mim_examples as mx
from crocopy.bench.compat import Row, RunResult
from crocopy.cli import main

HAS_MIM = importlib.util.find_spec("crocoddyl") is not None and importlib.util.find_spec("mim_solvers") is not None
TOP = mx.SDIST.removesuffix(".tar.gz")


def tarball(files: dict[str, str]) -> bytes:
    buffer = io.BytesIO()
    with tarfile.open(fileobj=buffer, mode="w:gz") as archive:
        for name, text in files.items():
            data = text.encode()
            info = tarfile.TarInfo(name)
            info.size = len(data)
            archive.addfile(info, io.BytesIO(data))
    return buffer.getvalue()


EXAMPLES = {f"{TOP}/examples/{name}.py": f"print({name!r})\n" for name in (*mx.SCRIPTS, "utils_solo12")}


def index_page(digest: str, href: str | None = None) -> bytes:
    href = href or f"https://files.example.org/packages/ab/{mx.SDIST}#sha256={digest}"
    return (f'<html><body><a href="https://x/mim_solvers-0.2.0.tar.gz#sha256={"0" * 64}">mim_solvers-0.2.0.tar.gz'
            f'</a><br/><a href="{href}" data-requires-python="&gt;=3.8">{mx.SDIST}</a></body></html>').encode()


class FakePyPI:
    """``get`` for :func:`mx.fetch_sdist`: the index page and the file, counting the requests."""

    def __init__(self, data: bytes, listed_digest: str | None = None) -> None:
        self.data, self.urls = data, []
        self.digest = listed_digest or hashlib.sha256(data).hexdigest()

    def __call__(self, url: str) -> bytes:
        self.urls.append(url)
        if url == mx.SIMPLE_INDEX:
            return index_page(self.digest)
        assert url == f"https://files.example.org/packages/ab/{mx.SDIST}"
        return self.data


# ------------------------------------------------------------------------------------------ sdist
def test_index_link_gives_url_and_sha256_and_relative_links_resolve():
    url, digest = mx.sdist_url(index_page("c" * 64).decode())
    assert url == f"https://files.example.org/packages/ab/{mx.SDIST}" and digest == "c" * 64
    url, _ = mx.sdist_url(index_page("d" * 64, f"../../packages/{mx.SDIST}#sha256={'d' * 64}").decode())
    assert url == f"https://pypi.org/packages/{mx.SDIST}"


def test_index_without_the_file_or_its_sha256_is_refused():
    with pytest.raises(mx.SdistError, match="lists no mim_solvers-0.3.0.tar.gz"):
        mx.sdist_url("<html><a href='x.tar.gz'>x.tar.gz</a></html>")
    with pytest.raises(mx.SdistError, match="gives no sha256"):
        mx.sdist_url(index_page("", f"https://x/{mx.SDIST}").decode())


def test_download_is_checked_cached_and_not_repeated(tmp_path):
    data = tarball(EXAMPLES)
    expected = hashlib.sha256(data).hexdigest()
    pypi = FakePyPI(data)
    path = mx.fetch_sdist(tmp_path / "cache", get=pypi, expected=expected)
    assert path == tmp_path / "cache" / mx.SDIST and path.read_bytes() == data
    assert len(pypi.urls) == 2
    assert mx.fetch_sdist(tmp_path / "cache", get=pypi, expected=expected) == path
    assert len(pypi.urls) == 2  # the cached file is used
    path.write_bytes(data[:-1])  # a damaged cache is downloaded again
    assert mx.fetch_sdist(tmp_path / "cache", get=pypi, expected=expected).read_bytes() == data
    assert len(pypi.urls) == 4


def test_a_listed_sha256_other_than_the_pinned_one_is_refused(tmp_path):
    pypi = FakePyPI(tarball(EXAMPLES), listed_digest="e" * 64)
    with pytest.raises(mx.SdistError, match=f"gives sha256 {'e' * 64} .* expected"):
        mx.fetch_sdist(tmp_path, get=pypi, expected="f" * 64)
    assert len(pypi.urls) == 1 and not list(tmp_path.iterdir())


def test_bytes_that_do_not_hash_to_the_listed_sha256_are_not_kept(tmp_path):
    data = tarball(EXAMPLES)
    digest = hashlib.sha256(data).hexdigest()
    pypi = FakePyPI(data[:100], listed_digest=digest)
    with pytest.raises(mx.SdistError, match="downloaded 100 bytes with sha256"):
        mx.fetch_sdist(tmp_path, get=pypi, expected=digest)
    assert not list(tmp_path.iterdir())


def test_a_failed_download_says_which_url(tmp_path, monkeypatch):
    def refuse(url, timeout):
        raise OSError("Network is unreachable")

    monkeypatch.setattr(mx.urllib.request, "urlopen", refuse)
    with pytest.raises(mx.SdistError, match=r"could not download https://pypi.org/simple/mim-solvers/: Network"):
        mx.fetch_sdist(tmp_path)


def test_only_the_example_scripts_are_extracted(tmp_path):
    files = {**EXAMPLES, f"{TOP}/setup.py": "", f"{TOP}/examples/data/x.py": "", f"{TOP}/examples/README.md": "",
             f"{TOP}/python/mim_solvers/__init__.py": ""}
    (tmp_path / "s.tar.gz").write_bytes(tarball(files))
    folder = mx.extract_examples(tmp_path / "s.tar.gz", tmp_path / "out")
    assert sorted(p.name for p in folder.iterdir()) == sorted(f"{n}.py" for n in (*mx.SCRIPTS, "utils_solo12"))


def test_an_sdist_without_a_script_is_refused(tmp_path):
    (tmp_path / "s.tar.gz").write_bytes(tarball({k: v for k, v in EXAMPLES.items() if "solo12.py" not in k
                                                 or "utils" in k}))
    with pytest.raises(mx.SdistError, match="no examples/solo12.py"):
        mx.extract_examples(tmp_path / "s.tar.gz", tmp_path / "out")


# ----------------------------------------------------------------------------------- the child side
def test_recorder_wraps_each_class_once_and_reads_kkt_when_there_is_one():
    class SolverSQP:
        iter, cost, KKT = 0, 0.0, 0.0

        def solve(self, n=3):
            self.iter, self.cost, self.KKT = n, 1.0 / n, 1e-3 / n
            return True

    class SolverCSQP(SolverSQP):
        def solve(self, n=3):
            return super().solve(n + 1)

    class SolverFDDP:
        iter, cost = 0, 0.0

        def solve(self):
            self.iter, self.cost = 7, 2.0
            return False

    croc = types.SimpleNamespace(SolverFDDP=SolverFDDP)
    mim = types.SimpleNamespace(SolverSQP=SolverSQP, SolverCSQP=SolverCSQP, SolverFDDP=SolverFDDP)
    sink = []
    mx.record_solves([croc, mim], sink)
    SolverCSQP().solve(4)
    SolverFDDP().solve()
    SolverSQP().solve()
    assert sink == [{"solver": "SolverCSQP", "iter": 5, "cost": 0.2, "converged": True, "KKT": 2e-4},
                    {"solver": "SolverFDDP", "iter": 7, "cost": 2.0, "converged": False, "KKT": None},
                    {"solver": "SolverSQP", "iter": 3, "cost": 1.0 / 3, "converged": True, "KKT": 1e-3 / 3}]


def test_a_viewer_ends_the_run_and_only_the_viewers_of_the_library_are_replaced():
    lib = types.SimpleNamespace(MeshcatDisplay=object, SolverFDDP=object)
    mx.disable_displays(lib)
    assert lib.SolverFDDP is object and not hasattr(lib, "GepettoDisplay")
    with pytest.raises(mx.DisplayReached, match="ends at its MeshcatDisplay"):
        lib.MeshcatDisplay("robot", frameNames=[])


# ------------------------------------------------------------------------------------------ table
def solves(*items):
    return [{"solver": s, "iter": it, "cost": c, "converged": True, "KKT": k} for s, it, c, k in items]


def cells(line: str) -> list[str]:
    return [c.strip() for c in line.strip().strip("|").split("|")]


def test_runs_end_alike_at_their_ends_or_at_the_same_error_on_the_same_line():
    done, other = RunResult(True), RunResult(True, where="ends at its MeshcatDisplay (no display)")
    fail = RunResult(False, error="AttributeError: x", where="t.py:256; raised in crocopy/a.py:3")
    assert mx.same_end(done, other) is True and mx.same_end(done, None) is None
    assert mx.same_end(fail, RunResult(False, error="AttributeError: x", where="t.py:256")) is True
    assert mx.same_end(fail, RunResult(False, error="AttributeError: x", where="t.py:250")) is False
    assert mx.same_end(fail, RunResult(False, error="AttributeError: y", where="t.py:256")) is False
    assert mx.same_end(fail, done) is False and mx.same_end(done, fail) is False
    assert mx.same_end(RunResult(False, error="e"), RunResult(False, error="e")) is False  # no line: unknown


def test_table_rows_show_both_runs_and_the_cost_difference():
    mine = RunResult(True, where="ends at its MeshcatDisplay (no display)", seconds=3.71,
                     solves=solves(("SolverCSQP", 11, 0.6898791671, 5.48e-5)))
    theirs = RunResult(True, seconds=2.0, solves=solves(("SolverCSQP", 11, 0.6898791671 * (1 + 2e-9), 5.48e-5)))
    c = cells(mx.format_row(Row("ur5", mine, theirs)))
    assert c[0] == "ur5" and c[1] == "yes (ends at its MeshcatDisplay (no display))" and c[2] == "yes"
    assert c[3] == "SolverCSQP: 11 it, cost 0.6898791671, KKT 5.480e-05"
    assert c[4].startswith("SolverCSQP: 11 it, cost 0.68987916")
    assert float(c[5]) == pytest.approx(2e-9, rel=1e-2) and c[6] == "3.7 / 2.0"
    broken = RunResult(False, error="ValueError: a|b", where="utils_solo12.py:33")
    c = cells(mx.format_row(Row("solo12", broken, RunResult(True))).replace("\\|", "¦"))
    assert c[1] == "no: ValueError: a¦b (utils_solo12.py:33)" and c[2] == "no (its run: yes)" and c[5] == "-"
    many = RunResult(True, solves=solves(*[("SolverFDDP", i, 1.0, None) for i in range(1, 5)]))
    assert cells(mx.format_row(Row("mpc", many, None)))[3] == ("4 solves, the last: SolverFDDP: 3 it, cost 1; "
                                                               "SolverFDDP: 4 it, cost 1")


def test_table_counts_runs_that_end_and_that_end_alike():
    ok = RunResult(True, solves=solves(("SolverSQP", 36, 5.68, 2e-7)))
    fail = RunResult(False, error="AttributeError: x", where="t.py:256")
    rows = [Row("a", ok, ok), Row("b", fail, RunResult(False, error="AttributeError: x", where="t.py:256")),
            Row("c", ok, None)]
    text = mx.format_table(rows)
    assert "2 of 3 runs of mim-solvers 0.3.0's examples (from its sdist) end" in text
    assert "; 2 of 2 end as mim-solvers' runs do (1 of these stopping at the same error with mim-solvers" in text
    assert "yes: mim-solvers' own run stops at this error too" in text
    assert "; 1 of 1 end as mim-solvers' runs do." in mx.format_table(rows[:1])
    table = [line for line in text.splitlines() if line.startswith("|")]
    assert len(table) == 2 + len(rows) and all(len(cells(line)) == 7 for line in table)


# ------------------------------------------------------------------------------------------ command
def test_unknown_run_is_refused_with_the_known_ones(capsys):
    assert main(["bench", "--mim-examples", "--problems", "ur5", "talos"]) == 2
    err = capsys.readouterr().err
    assert "unknown mim-solvers example run(s) ['talos']" in err and "humanoid_taichi-fddp" in err


def test_without_mim_solvers_the_command_names_the_bench_extra(monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "mim_solvers", None)  # makes `import mim_solvers` raise ImportError
    assert main(["bench", "--mim-examples", "--problems", "ur5"]) == 2
    assert "bench" in capsys.readouterr().err


def test_the_full_crocoddyl_report_says_when_the_mim_sections_were_not_run(monkeypatch):
    from crocopy.bench.command import _mim_sections

    monkeypatch.setitem(sys.modules, "mim_solvers", None)
    sections = _mim_sections(lambda message: None, 1)
    assert len(sections) == 1 and sections[0].startswith("## crocopy vs mim-solvers") and "Not run" in sections[0]
    assert "mim-solvers 0.3.0" in sections[0]


SCRIPT = """\
import sys

import crocoddyl
import mim_solvers
import numpy as np

assert sys.argv[1:] == ["plot"]
model = crocoddyl.ActionModelLQR(2, 2)
model.Lx, model.Lu = np.ones(2), -np.ones(2)
problem = crocoddyl.ShootingProblem(np.ones(2), [model] * 5, model)
solver = mim_solvers.SolverSQP(problem)
solver.setCallbacks([mim_solvers.CallbackLogger()])
xs, us = [np.ones(2)] * 6, [np.zeros(2)] * 5
solver.solve(xs, us, 10)
crocoddyl.SolverDDP(problem).solve(xs, us, 10)
display = crocoddyl.MeshcatDisplay(None)
raise RuntimeError("not reached")
"""


@pytest.mark.skipif(not HAS_MIM, reason="needs the bench extra (Crocoddyl 3.2.1, mim-solvers 0.3.0)")
@pytest.mark.parametrize("library", mx.LIBRARIES)
def test_child_binds_the_library_records_its_solves_and_stops_at_the_viewer(tmp_path, library):
    (tmp_path / "humanoid_taichi.py").write_text(textwrap.dedent(SCRIPT))
    result = mx.run_job(library, "humanoid_taichi", tmp_path, timeout=300)
    assert result.ok, result
    assert result.where == "ends at its MeshcatDisplay (no display)"
    assert [s["solver"] for s in result.solves] == ["SolverSQP", "SolverDDP"]
    sqp, ddp = result.solves
    assert sqp["converged"] and sqp["KKT"] <= 1e-4 and ddp["KKT"] is None
    assert sqp["cost"] == pytest.approx(ddp["cost"], rel=1e-9)
    assert json.dumps(result.solves)  # JSON-able as the child wrote it
