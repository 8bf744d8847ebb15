"""Sphinx configuration of the blademodel documentation (MyST Markdown pages).

Build with warnings as errors::

    sphinx-build -W --keep-going -b html docs docs/_build/html
"""

import os
import sys

sys.path.insert(0, os.path.abspath(".."))

import blademodel

project = "blademodel"
author = "blademodel contributors"
copyright = "2024, blademodel contributors"
release = blademodel.__version__
version = release

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
]

source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store"]

# MyST: $...$ and $$...$$ math, amsmath environments, ::: fences
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence"]
myst_heading_anchors = 3

# numpydoc-style docstrings through napoleon
napoleon_google_docstring = False
napoleon_numpy_docstring = True
# "Attributes" sections become :ivar: fields of the class, not separate attribute
# directives: dataclass fields documented in a class docstring would otherwise be
# described twice when autodoc also lists the fields.
napoleon_use_ivar = True

autodoc_member_order = "bysource"
autodoc_default_options = {"members": True, "show-inheritance": True}
# signatures stay readable; the types are given in the numpydoc sections
autodoc_typehints = "none"

html_theme = "alabaster"
html_static_path = ["_static"]
html_title = "blademodel"
