"""Sphinx configuration of maizeviz's API reference (``docs/api``).

The reference is rendered from the numpydoc docstrings of what ``import maizeviz as mv``
offers; the tutorial (``docs/tutorial.md``, whose cells the test suite runs) is its worked
example. Built by ``tests/core/test_api_docs.py`` with warnings as errors::

    python -m sphinx -W -b html docs/api docs/api/_build
"""

from __future__ import annotations

import maizeviz

project = "maizeviz"
author = "the maizeviz authors"
release = version = maizeviz.__version__
extensions = ["sphinx.ext.autodoc", "numpydoc", "myst_parser"]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build"]
root_doc = "index"

# the docstrings' own order and the signatures' annotations as written
autodoc_member_order = "bysource"
autodoc_typehints = "none"
# a class's public methods and properties listed (numpydoc), without a stub page each
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
# the tutorial's headings are anchors
myst_heading_anchors = 2
# the tutorial links the other Markdown pages of docs/, which are not part of this book
suppress_warnings = ["myst.xref_missing"]

html_theme = "alabaster"
html_title = f"maizeviz {release} API"
