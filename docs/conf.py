"""Sphinx configuration of the lgt_bridge documentation site.

Build (from the repository root; the ``docs`` extra installs the tools)::

    python -m sphinx -W --keep-going -b html docs docs/_build/html

``-D plot_gallery=0`` skips running the examples (the fast build of ``tests/core/test_docs.py``).
"""
import os
import sys
import warnings
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
# Document the sources of this checkout (not another installed copy): the core and the adapters.
if (ROOT / "lgt_bridge").is_dir():
    sys.path[:0] = [str(ROOT), str(ROOT / "adapters")]

os.environ.setdefault("MPLBACKEND", "Agg")
os.environ.setdefault("CI", "1")                 # no progress bars in the gallery's output

import lgt_bridge  # noqa: E402

project = "lgt_bridge"
author = "the lgt_bridge developers"
copyright = "the lgt_bridge developers"
release = version = lgt_bridge.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.mathjax",
    "sphinx-mathjax-offline",        # MathJax 3 copied into _static: math renders without a network
    "sphinx.ext.intersphinx",
    "sphinx.ext.viewcode",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
    "myst_parser",                   # docs/architecture.md stays Markdown (one source, read on GitHub too)
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "auto_examples/*.ipynb", "auto_examples/*.py",
                    "auto_examples/*.zip", "auto_examples/*.json", "auto_examples/*.md5",
                    "figures/*.py", "sg_execution_times.rst"]
templates_path = []
nitpicky = False
default_role = "literal"

# -- autodoc / numpydoc ---------------------------------------------------------------------
autodoc_default_options = {"members": True, "undoc-members": False, "show-inheritance": True}
autodoc_member_order = "bysource"
autodoc_typehints = "none"
autodoc_mock_imports = []
numpydoc_show_class_members = False          # members are listed by autodoc itself
numpydoc_class_members_toctree = False
numpydoc_validation_checks = set()
numpydoc_xref_param_type = False

intersphinx_mapping = {}                     # offline build: no inventories fetched

# -- sphinx-gallery -------------------------------------------------------------------------
# Every example runs at build time except files ending in ``_long.py`` (shown, not run), and
# those whose optional data is not installed (shown, not run, instead of failing the build).
import importlib.util  # noqa: E402

NOT_RUN = [r"[^/\\]*_long\.py"]
if importlib.util.find_spec("example_robot_data") is None:       # the ``robots`` extra
    NOT_RUN.append(r"plot_stiff_pd_radau5\.py")
sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples"),
    "gallery_dirs": str(HERE / "auto_examples"),
    "filename_pattern": r"[/\\](?!(?:%s)$)[^/\\]+\.py$" % "|".join(NOT_RUN),
    "ignore_pattern": r"__init__\.py",
    "within_subsection_order": "ExampleTitleSortKey",   # "... as written today" before "... through the bridge"
    "download_all_examples": False,
    "remove_config_comments": True,
    "abort_on_example_error": False,
    "only_warn_on_example_error": False,
    "capture_repr": (),
    "matplotlib_animations": False,
    "image_scrapers": ("matplotlib",),
    "write_computation_times": True,
    "show_memory": False,
}
warnings.filterwarnings("ignore", category=UserWarning,
                        message="Matplotlib is currently using agg, which is a non-GUI backend")

# -- MyST -----------------------------------------------------------------------------------
myst_heading_anchors = 3
suppress_warnings = ["myst.header"]

# -- HTML -----------------------------------------------------------------------------------
html_theme = "pydata_sphinx_theme"
html_title = f"lgt_bridge {release}"
html_static_path = []
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "navbar_align": "left",
    "header_links_before_dropdown": 5,
    "secondary_sidebar_items": ["page-toc"],
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
}
html_sidebars = {"index": [], "getting_started": [], "theory": [], "performance": [],
                 "architecture": []}
html_show_sourcelink = False
