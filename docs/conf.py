"""Sphinx configuration of the documentation site (``scripts/build-docs.sh`` -> ``docs/_build/html``).

The pages are the Markdown files of ``docs/`` (MyST), the API reference is generated from the docstrings
(autosummary), and the examples of ``examples/`` are run and rendered as a gallery (sphinx-gallery)."""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

project = "flexible-bennett"
author = "the flexible-bennett developers"
copyright = "2026, " + author
release = "0.1.0"

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "sphinx_gallery.gen_gallery",
]
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
exclude_patterns = ["_build", "results", "Thumbs.db", ".DS_Store", "gallery/*.ipynb", "gallery/*.py"]
myst_enable_extensions = ["dollarmath", "amsmath"]
myst_heading_anchors = 3
# Links from the Markdown pages to source files and result files (JSON pointers) are links to the repository's
# files, which the site does not carry: MyST reports them as unresolved cross-references, not errors.
suppress_warnings = ["myst.xref_missing"]

autosummary_generate = True
autosummary_imported_members = False
# Members defined in each module, not its re-exports (ffrf re-exports its API: documented where defined).
autodoc_default_options = {"members": True, "show-inheritance": True, "ignore-module-all": True}
autodoc_typehints = "description"
autodoc_member_order = "bysource"
napoleon_numpy_docstring = True
napoleon_google_docstring = False

sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples"),
    "gallery_dirs": "gallery",
    "filename_pattern": r"/ex\d\d_",  # every numbered example runs when the site builds
    "ignore_pattern": r"__init__\.py",
    "download_all_examples": False,
    "remove_config_comments": True,
    "plot_gallery": "True",
    "abort_on_example_error": True,
    "within_subsection_order": "FileNameSortKey",
}

html_theme = "furo"
html_title = "flexible-bennett"
