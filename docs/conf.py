"""Sphinx configuration of crocopy's documentation (``sphinx-build -W -b html docs docs/_build/html``)."""

from __future__ import annotations

from importlib.metadata import version as _version

project = "crocopy"
author = "the crocopy developers"
copyright = "2026, the crocopy developers"
release = _version("crocopy")
version = release

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
]

exclude_patterns = ["_build", "DEVELOPING.md"]
root_doc = "index"

autosummary_generate = True
autosummary_imported_members = False
autodoc_default_options = {"members": True, "show-inheritance": True, "ignore-module-all": True}
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_typehints_format = "short"
autoclass_content = "both"
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False
napoleon_use_ivar = True

html_theme = "furo"
html_title = f"crocopy {release}"
html_static_path: list[str] = []


def _skip_class_aliases(app, what, name, obj, skip, options):
    """Skip a class attribute that is another class documented under its own name (Crocoddyl's nested
    names such as ``DifferentialActionModelFreeInvDynamics.ResidualModelActuation``)."""
    if what == "class" and isinstance(obj, type) and obj.__name__ == name and "." not in obj.__qualname__:
        return True
    return None


def setup(app):
    app.connect("autodoc-skip-member", _skip_class_aliases)
