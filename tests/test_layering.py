"""The layers never import upward: every import of every module, including those inside functions.

Layers, bottom to top:

* core: ``crocopy/`` without its apps (numpy, scipy, numba; never Pinocchio, meshcat or a task);
* ``crocopy.models`` (``models/``): Pinocchio-backed models and the meshcat display;
* ``crocopy.problems`` (``problems/``): problem builders;
* apps: ``crocopy.bench``, ``crocopy.experiments`` and ``crocopy.cli``.

``crocopy/__init__.py`` is the flat facade (Crocoddyl's API) and re-exports ``crocopy.models``; it is
the one core module allowed to name a higher layer.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE_DIRS = {"crocopy": ROOT / "crocopy", "crocopy.models": ROOT / "models", "crocopy.problems": ROOT / "problems"}
APPS = ("crocopy.bench", "crocopy.experiments", "crocopy.cli")
FACADE = "crocopy"


def module_files() -> dict[str, Path]:
    """Dotted module name → file, for every module of the three source trees."""
    modules = {}
    for package, folder in PACKAGE_DIRS.items():
        for path in folder.rglob("*.py"):
            parts = list(path.relative_to(folder).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            modules[".".join([package, *parts])] = path
    return modules


def imported_modules(source: str, module: str, is_package: bool) -> set[str]:
    """Absolute names of every module imported by ``source`` (relative imports resolved)."""
    package = module if is_package else module.rpartition(".")[0]
    names = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            names.add(target)
            names.update(f"{target}.{alias.name}" for alias in node.names)
    return names


def private_imports(source: str) -> list[str]:
    """``from crocopy... import _name`` and relative ``from . import _name`` lines: private names shared."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom) and (node.level or (node.module or "").startswith("crocopy")):
            private = [a.name for a in node.names if a.name.startswith("_") and not a.name.startswith("__")]
            found += [f"{'.' * node.level}{node.module or ''}.{name}" for name in private]
    return found


def within(name: str, prefixes: tuple[str, ...]) -> bool:
    return any(name == p or name.startswith(p + ".") for p in prefixes)


def layer_violations(module: str, imports: set[str]) -> list[str]:
    """The imports of ``module`` that reach a layer it must not depend on."""
    if within(module, ("crocopy.problems",) + APPS):
        return []
    if within(module, ("crocopy.models",)):
        forbidden = ("crocopy.problems",) + APPS
    elif module == FACADE:
        forbidden = ("crocopy.problems",) + APPS
    else:  # the core, solvers included
        forbidden = ("crocopy.models", "crocopy.problems", "pinocchio", "meshcat") + APPS
    return sorted(name for name in imports if within(name, forbidden))


MODULES = module_files()


def test_every_tree_is_read():
    assert "crocopy.solvers.ddp" in MODULES and "crocopy.models.state_multibody" in MODULES
    assert "crocopy.problems.registry" in MODULES and "crocopy.bench.side_by_side" in MODULES


@pytest.mark.parametrize("module", sorted(MODULES))
def test_module_imports_only_its_own_layer_or_below(module):
    path = MODULES[module]
    imports = imported_modules(path.read_text(), module, path.name == "__init__.py")
    assert layer_violations(module, imports) == []


@pytest.mark.parametrize("module", sorted(MODULES))
def test_no_private_name_is_shared_across_modules(module):
    assert private_imports(MODULES[module].read_text()) == []


def test_checker_flags_upward_imports_even_inside_functions():
    source = "import numpy\n\ndef f():\n    from ..models import StateMultibody\n    import pinocchio\n"
    imports = imported_modules(source, "crocopy.solvers.ddp", False)
    assert layer_violations("crocopy.solvers.ddp", imports) == ["crocopy.models", "crocopy.models.StateMultibody",
                                                                 "pinocchio"]
    bench = imported_modules("from crocopy.bench.timing import limit_threads\n", "crocopy.models.contacts", False)
    assert layer_violations("crocopy.models.contacts", bench) == ["crocopy.bench.timing",
                                                                  "crocopy.bench.timing.limit_threads"]
    assert layer_violations("crocopy.models.contacts", {"crocopy.state"}) == []
    assert layer_violations("crocopy.bench.floor", {"crocopy.models", "pinocchio"}) == []
    assert private_imports("from .side_by_side import _loops, build_problem\n") == [".side_by_side._loops"]
