"""Sphinx configuration of the pysindy-xl documentation.

Build with ``bash docs/build.sh`` (warnings are errors). The API reference pages are written
at configuration time from the ``__all__`` lists of the public modules (into the ignored
``gen_modules/`` folder), so the reference always matches the code; sphinx-gallery executes
every script of ``examples/`` and renders its output and figures.
"""

from __future__ import annotations

import importlib
import os
import sys
import warnings
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(DOCS / "_ext"))

from pxl_docs import GALLERY_EXCLUDED, write_api_pages, write_cli_help  # noqa: E402

import pysindy_xl  # noqa: E402

# -- project -----------------------------------------------------------------------------------
project = "pysindy-xl"
author = "pysindy-xl developers"
copyright = "pysindy-xl developers"  # noqa: A001 - Sphinx setting
release = pysindy_xl.__version__
version = ".".join(release.split(".")[:2])

# -- general -----------------------------------------------------------------------------------
extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
]
templates_path = ["_templates"]
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store", "auto_examples/*.ipynb",
                    "auto_examples/*.py", "auto_examples/*.zip"]
default_role = "literal"  # `x` is literal code, never an unresolved cross-reference
add_module_names = False
toc_object_entries = False

# -- API reference -----------------------------------------------------------------------------
#: Public modules documented in the reference, in reading order; absent ones are skipped.
API_MODULES = [
    "pysindy_xl",
    "pysindy_xl.feature_library",
    "pysindy_xl.catalog",
    "pysindy_xl.optimizers",
    "pysindy_xl.fit",
    "pysindy_xl.weak",
    "pysindy_xl.dynamics",
    "pysindy_xl.export.jax_dynamics",
    "pysindy_xl.io",
    "pysindy_xl.data",
    "pysindy_xl.export.gym_env",
    "pysindy_xl.control",
    "pysindy_xl.expressions",
    "pysindy_xl.mujoco",
    "pysindy_xl.benchmark",
    "pysindy_xl.quality",
    "pysindy_xl.held_out",
    "pysindy_xl.cli",
]
API_SKIPPED = write_api_pages(API_MODULES, DOCS / "gen_modules" / "api")
CLI_AVAILABLE = write_cli_help("pysindy_xl.cli", DOCS / "gen_modules" / "cli_help.rst.inc")

# The pages to scan for autosummary tables, listed explicitly: with ``True`` an incremental
# build would only scan the pages known to its cached environment and miss new modules.
autosummary_generate = [
    f"gen_modules/api/{name}.rst" for name in API_MODULES if name not in API_SKIPPED
]
autosummary_generate_overwrite = True
autodoc_typehints = "none"  # numpydoc sections already state the types
autodoc_member_order = "bysource"
autodoc_inherit_docstrings = False
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_attributes_as_param_list = True

# -- example gallery ---------------------------------------------------------------------------
#: Examples that need a piece of the package that may be missing: file -> (module, attribute).
GALLERY_REQUIREMENTS = {
    "double_pendulum_implicit.py": ("pysindy_xl", "ImplicitOptimizer"),
    "cart_double_pendulum_mixed.py": ("pysindy_xl", "MixedOptimizer"),
    "jax_batched.py": ("pysindy_xl.export.jax_dynamics", "simulate_batch"),
    "jax_gradient.py": ("pysindy_xl.export.jax_dynamics", "simulate"),
    "identified_cartpole_controller.py": ("pysindy_xl.export.gym_env", "make_env"),
    "swing_up_identified.py": ("pysindy_xl.control", "learn_to_control"),
}


def _missing_requirement(module: str, attribute: str) -> bool:
    try:
        return not hasattr(importlib.import_module(module), attribute)
    except ImportError:
        return True


GALLERY_SKIPPED = sorted(
    name for name, (module, attribute) in GALLERY_REQUIREMENTS.items()
    if (ROOT / "examples" / name).exists() and _missing_requirement(module, attribute)
)
_ignored = [r"__init__\.py"] + [
    name.replace(".", r"\.") for name in sorted(set(GALLERY_SKIPPED) | set(GALLERY_EXCLUDED))
]



sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"\.py$",  # execute every example, not only plot_*.py
    "ignore_pattern": "|".join(_ignored),
    "within_subsection_order": "pxl_docs.gallery_order",
    "backreferences_dir": "gen_modules/backreferences",
    "doc_module": ("pysindy_xl",),
    "abort_on_example_error": True,
    "only_warn_on_example_error": False,
    "remove_config_comments": True,
    "download_all_examples": False,
    "image_scrapers": ("matplotlib",),
    "reset_modules": ("matplotlib", "pxl_docs.reset_jax"),
    "min_reported_time": 1,
    "write_computation_times": True,
}

# Examples run with a non-interactive backend; silence the note matplotlib emits about it.
os.environ.setdefault("MPLBACKEND", "Agg")
warnings.filterwarnings("ignore", message="Matplotlib is currently using agg")

# -- HTML --------------------------------------------------------------------------------------
html_theme = "pydata_sphinx_theme"
html_title = f"pysindy-xl {release}"
html_theme_options = {
    "navbar_align": "left",
    "show_toc_level": 2,
    "navigation_with_keys": False,
    "secondary_sidebar_items": ["page-toc", "sourcelink"],
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
}
html_sidebars = {"index": [], "theory": [], "coming_from_pysindy": []}
html_show_sourcelink = True


def skip_foreign_member(app, what, name, obj, skip, options):
    """Leave out members that classes inherit from scikit-learn or pysindy.

    scikit-learn attaches ``set_*_request`` and ``set_output`` to every subclass, so they look
    like members of our classes; their docstrings refer to scikit-learn's own documentation.
    """
    module = getattr(obj, "__module__", None) or ""
    if module.split(".")[0] in ("sklearn", "pysindy"):
        return True
    return None


def setup(app):
    from sphinx.util import logging

    app.connect("autodoc-skip-member", skip_foreign_member)

    logger = logging.getLogger("pysindy_xl.docs")
    for name in API_SKIPPED:
        logger.info("API reference: module %s is not importable, skipped", name)
    for name in GALLERY_SKIPPED:
        module, attribute = GALLERY_REQUIREMENTS[name]
        logger.info("gallery: %s skipped (%s.%s is missing)", name, module, attribute)
    for name, reason in GALLERY_EXCLUDED.items():
        logger.info("gallery: %s left out (%s)", name, reason)
