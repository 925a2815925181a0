"""Sphinx configuration of slipwave's documentation (``make docs``)."""

from __future__ import annotations

from pathlib import Path

from slipwave import __version__

ROOT = Path(__file__).resolve().parents[1]

project = "slipwave"
author = "slipwave developers"
copyright = "2026, slipwave developers"  # noqa: A001 (Sphinx's name)
version = release = __version__

extensions = [
    "myst_parser",
    "numpydoc",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.doctest",
]
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
exclude_patterns = ["_build", "README.md"]
myst_heading_anchors = 3

# The API reference: one page per module, generated from the docstrings; a package's
# page lists its modules (its names are documented where they are defined).
templates_path = ["_templates"]
autosummary_generate = True
autosummary_ignore_module_all = True
autodoc_typehints = "none"  # the signatures carry them; numpydoc keeps types out
autodoc_default_options = {"show-inheritance": False}
# T/|N| in docstrings reads as the ratio, not as a reST substitution
rst_prolog = ".. |N| unicode:: U+007C U+004E U+007C\n"
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

# The tutorial runs on the repository's default campaign, from its root.
doctest_global_setup = f"""
import os
os.chdir({str(ROOT)!r})
"""

html_theme = "furo"
html_title = f"slipwave {version}"
html_static_path = ["_static"]
doctest_test_doctest_blocks = ""  # the docstrings' examples run in pytest
