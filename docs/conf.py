"""Sphinx configuration of the soilwater documentation.

Build with ``make docs`` (HTML under ``docs/_build/html``). The API reference is generated
from the numpy docstrings by autosummary, recursively over the package; the case
reference from :mod:`soilwater.case.schema` by the ``case-schema`` directive of
``_ext/case_reference.py``; the gallery from ``examples/plot_*.py`` by sphinx-gallery
(``-D plot_gallery=0`` builds it without running the examples).
"""

import os
import sys
from importlib.metadata import version as installed_version
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent / "_ext"))

project = "soilwater"
author = "the soilwater authors"
copyright = "the soilwater authors, BSD-3-Clause"
release = version = installed_version("soilwater")

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx.ext.intersphinx",
    "sphinx.ext.viewcode",
    "sphinx_gallery.gen_gallery",
    "case_reference",
]

templates_path = ["_templates"]
# experiments/: the measurement scripts the study pages quote, and their README.
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store", "sg_execution_times.rst",
                    "auto_examples/*.ipynb", "auto_examples/*.py", "auto_examples/*.zip",
                    "experiments"]
root_doc = "index"

# Autodoc and autosummary: every module of the package, numpy-style docstrings.
autosummary_generate = True
autosummary_imported_members = False
autodoc_default_options = {"members": True, "undoc-members": False,
                           "show-inheritance": True, "member-order": "bysource"}
autodoc_typehints = "none"
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_ivar = True
napoleon_use_rtype = False
# A docstring's cross-reference to something outside the reference is plain text.
nitpicky = False
default_role = "code"
# Names such as `shape` or `InputError` in the parameter types match several objects:
# they link to none rather than fail the build.
suppress_warnings = ["ref.python"]

# Links to the libraries the docstrings name. Fetching their inventories needs the
# network, so it is on only with SOILWATER_DOCS_INTERSPHINX=1 (the tests build offline).
intersphinx_mapping = {
    "python": ("https://docs.python.org/3", None),
    "numpy": ("https://numpy.org/doc/stable", None),
    "scipy": ("https://docs.scipy.org/doc/scipy", None),
    "skfem": ("https://scikit-fem.readthedocs.io/en/latest", None),
} if os.environ.get("SOILWATER_DOCS_INTERSPHINX") == "1" else {}
intersphinx_timeout = 10

sphinx_gallery_conf = {
    "examples_dirs": "examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_\d\d_",
    "within_subsection_order": "FileNameSortKey",
    "download_all_examples": False,
    "remove_config_comments": True,
}

html_theme = "pydata_sphinx_theme"
html_title = f"soilwater {release}"
html_theme_options = {"navigation_with_keys": False, "show_toc_level": 2,
                      "secondary_sidebar_items": ["page-toc"]}
html_static_path = []
html_show_sourcelink = False
