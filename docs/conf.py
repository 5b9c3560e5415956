"""Sphinx configuration: the API from sorpia's docstrings (autodoc + napoleon, numpy style), the command line
from sorpia.cli.build_parser (the cli_reference extension in _ext/), Markdown pages through myst-parser.

Built by `make docs` into build/docs; `make test` builds it with warnings as errors. It documents the
installed sorpia (the Makefile's .venv), so the C++ core's bindings are the ones the tests use.
"""

import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "_ext"))

import sorpia  # noqa: E402

project = "sorpia"
author = "sorpia contributors"
copyright = "sorpia contributors, MIT license"
version = release = sorpia.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "myst_parser",
    "cli_reference",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build"]
root_doc = "index"

# Single backticks in the docstrings name Python objects (`limit_points`, `sorpia.interpolate`).
default_role = "py:obj"
autodoc_member_order = "bysource"
autodoc_typehints = "description"
# sorpia._scipy.CSRMatrix is Any at run time (scipy is imported only where needed): show what it stands for.
autodoc_type_aliases = {"CSRMatrix": "scipy.sparse.csr_matrix"}
autodoc_default_options = {"members": True, "undoc-members": False, "show-inheritance": True}
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False
napoleon_use_ivar = True  # a dataclass's Attributes section as fields, not a second description of each member

myst_heading_anchors = 3
myst_enable_extensions = ["dollarmath"]

html_theme = "alabaster"
html_title = f"sorpia {release}"
html_static_path = []


def _skip_bare_properties(app, what, name, obj, skip, options):
    """Leave out properties without a docstring of their own: pybind11 gives each bound field one whose only
    text is its getter's signature, and the class's Attributes section already describes the field."""
    if isinstance(obj, property) and not (obj.__doc__ or "").strip():
        return True
    return None


def _drop_pybind11_base(app, name, obj, options, bases):
    """pybind11's common base class says nothing to a user of the class."""
    bases[:] = [b for b in bases if b.__name__ != "pybind11_object"]


def setup(app):
    app.connect("autodoc-skip-member", _skip_bare_properties)
    app.connect("autodoc-process-bases", _drop_pybind11_base)
