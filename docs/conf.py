"""Sphinx configuration of isoflow's documentation.

Build: ``pip install -e '.[docs]' && python -m sphinx -W -b html docs docs/_build/html``
(``tests/test_docs.py`` runs the same, warnings as errors). The command
line page is generated from ``isoflow.cli.main.build_parser()`` (sphinx-argparse),
the API pages from ``isoflow.__all__`` and the docstrings (autosummary,
numpydoc), the gallery from ``examples/`` (sphinx-gallery, which runs every
example and shows its figures).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(DOCS))  # api_pages.py and _gallery.py, beside this file

import api_pages  # noqa: E402  (after the path: a module beside this file)

import isoflow  # noqa: E402

project = "isoflow"
author = "the isoflow developers"
copyright = "2026, the isoflow developers"
release = version = isoflow.__version__

extensions = [
    "myst_parser",
    "numpydoc",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx_gallery.gen_gallery",
    "sphinxarg.ext",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "auto_examples/*.ipynb", "auto_examples/*.py", "auto_examples/*.zip",
                    "auto_examples/*.json", "auto_examples/*.md5"]
root_doc = "index"
smartquotes = False  # commands and options are copied as they are: pip install 'isoflow[gpu]'

# Markdown: $...$ and $$...$$ for the paper's equations, ::: fences,
# anchors for every heading down to ### (links like flow.md#one-step)
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3

# the API: one page per public name (api_pages.write makes api.rst from
# isoflow.__all__ before the build reads it)
autosummary_generate = True
autosummary_imported_members = True
# no autodoc_default_options: "members": False there overrides the class
# template's :members:, which leaves a class's page its docstring alone
autodoc_typehints = "none"  # numpydoc's Parameters section says the types
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
templates_path = ["_templates"]  # autosummary/class.rst: a class's page documents its members, to_dict too

# Every reference must resolve (-n with -W), except those that public
# docstrings make into the package's internal modules and to bare names
# of their own module: nothing outside isoflow.__all__ and isoflow.data is
# documented as API, and those references still read as code. A public
# name given by its defining module (isoflow.digital.topology.euler_characteristic)
# links to its page (setup below), which these patterns would hide.
nitpicky = True
nitpick_ignore_regex = [
    (r"py:.*", r"isoflow\.(cli|digital|errors|flow|mesh|results|scale)(\..*)?"),
    (r"py:.*", r"_?[A-Za-z][A-Za-z0-9_]*"),
]
api_pages.write(DOCS / "api.rst", isoflow)


def setup(app) -> None:
    # a public name referred to by its defining module links to its page;
    # a constant's page shows its comment, not its type's docstring
    api_pages.connect(app, isoflow)

sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/[a-z][a-z0-9_]*\.py$",  # every example; _common.py is not one
    "ignore_pattern": r"^_",  # matched against the file name
    "reset_argv": "_gallery.reset_argv",
    # the test suite reads each run's files: run every example on every build there
    "run_stale_examples": bool(os.environ.get("ISOFLOW_EXAMPLES_OUT")),
    "capture_repr": (),
    "download_all_examples": False,
    "remove_config_comments": True,
    "write_computation_times": False,
    "show_signature": False,
    "min_reported_time": 10**9,
    "matplotlib_animations": False,
    "image_scrapers": ("matplotlib",),
    "within_subsection_order": "FileNameSortKey",
}
if os.environ.get("ISOFLOW_DOCS_NO_GALLERY"):  # a quick build of the pages alone
    sphinx_gallery_conf["plot_gallery"] = "False"

html_theme = "pydata_sphinx_theme"
html_title = f"isoflow {version}"
html_static_path = ["_static"]
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "secondary_sidebar_items": ["page-toc"],
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
}
html_show_sourcelink = False
html_last_updated_fmt = None
