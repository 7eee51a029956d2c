"""``crocopy bench --first-solve --fresh-install`` (crocopy.bench.fresh_install): the README's install into a new
venv, the kernels its wheel ships, and that install's first solve."""

from __future__ import annotations

from pathlib import Path

import pytest

from crocopy import cli
from crocopy.bench import fresh_install

ROOT = Path(__file__).resolve().parents[1]


def test_only_a_checkout_of_crocopy_is_installed(tmp_path):
    assert fresh_install.check_source(str(ROOT)) == ROOT
    with pytest.raises(ValueError, match="not a checkout of crocopy"):
        fresh_install.check_source(str(tmp_path))
    (tmp_path / "pyproject.toml").write_text('[project]\nname = "other"\n')
    with pytest.raises(ValueError, match=f"--source {tmp_path}"):
        fresh_install.check_source(str(tmp_path))


def test_the_cli_refuses_a_source_that_is_not_crocopy(tmp_path, capsys):
    assert cli.main(["bench", "--first-solve", "--fresh-install", "--source", str(tmp_path)]) == 2
    assert "not a checkout of crocopy" in capsys.readouterr().err


def test_shipped_files_are_counted_in_the_installed_package(tmp_path):
    folder = tmp_path / "lib" / "python3.11" / "site-packages" / "crocopy" / "_kernel_cache" / "crocopy" / "solvers"
    folder.mkdir(parents=True)
    for name in ("a-1.py311.nbi", "a-1.py311.1.nbc", "a-1.py311.2.nbc"):
        (folder / name).write_bytes(b"x")
    assert fresh_install.shipped_files(tmp_path) == 3
    assert fresh_install.shipped_files(tmp_path / "elsewhere") == 0


@pytest.mark.slow
def test_a_fresh_install_ships_the_jumps_kernels_and_compiles_nothing_on_its_first_solve():
    report = fresh_install.run_fresh_install_bench(str(ROOT), repeats=1, progress=lambda line: None)
    rows = {tuple(c.strip() for c in line.split("|")[1:3]): line.split("|")[3].strip()
            for line in report.splitlines() if line.startswith("| fresh") or line.startswith("| warm")}
    assert rows[("fresh", "notice")] == "no" and rows[("warm", "notice")] == "no"
    assert float(rows[("fresh", "first iteration")]) < 20.0
    assert "kernel cache files" in report and "shipped 0 kernel" not in report
