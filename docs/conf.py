"""Sphinx configuration of the explorer documentation (built by tests/test_docs.py with -W)."""
import explorer

project = "explorer"
author = "the explorer developers"
copyright = "2026, the explorer developers"
version = release = explorer.__version__

extensions = [
    "myst_parser",            # the pages are Markdown (MyST)
    "sphinx.ext.autodoc",     # API reference from the docstrings
    "sphinx.ext.napoleon",    # numpydoc-style sections in docstrings
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
]
source_suffix = {".md": "markdown"}
exclude_patterns = ["_build"]
myst_enable_extensions = ["dollarmath", "colon_fence"]
myst_heading_anchors = 3

autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_default_options = {"members": True, "undoc-members": False}
napoleon_numpy_docstring = True
napoleon_google_docstring = False
napoleon_use_ivar = True

html_theme = "pydata_sphinx_theme"
html_title = "explorer"
html_theme_options = {"navigation_with_keys": False, "show_toc_level": 2}
