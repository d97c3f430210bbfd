"""Sphinx configuration of the transient documentation (``make docs``)."""
import os
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "_ext"))

import transient  # noqa: E402

project = "transient"
author = "the transient authors"
copyright = "the transient authors"
version = release = transient.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.intersphinx",
    "sphinx.ext.mathjax",
    "sphinx-mathjax-offline",
    "sphinxcontrib.bibtex",
    "numpydoc",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
    "sphinxarg.ext",
    "scene_keys",
    "plain_docstrings",
    "validation_pages",
    "public_api",
    "citations",
]

# Every cross-reference must resolve (``make docs`` runs with -n -W): a dead or ambiguous link
# fails the build. Ignored are only numpy's typing internals, which a type alias expands to
# (``transient.forces.gas.PieceFunction``) and numpy does not document, and its scalar types,
# which its inventory lists as attributes where an annotation refers to a class.
nitpicky = True
nitpick_ignore_regex = [("py:class", r"numpy\._typing\..*"), ("py:class", r"numpy\.(float|int)64")]

# The other projects' inventories are in the repository (docs/_intersphinx/README.md says where
# each comes from), so the build reads nothing from the network and links the same every time.
_INVENTORIES = HERE / "_intersphinx"
intersphinx_mapping = {
    name: (url, str(_INVENTORIES / f"{name}.inv"))
    for name, url in {
        "python": "https://docs.python.org/3/",
        "numpy": "https://numpy.org/doc/stable/",
        "scipy": "https://docs.scipy.org/doc/scipy/",
        "matplotlib": "https://matplotlib.org/stable/",
        "h5py": "https://docs.h5py.org/en/stable/",
        "dask": "https://docs.dask.org/en/stable/",
        "distributed": "https://distributed.dask.org/en/stable/",
    }.items()
}

# The works the code and the pages cite (docs/references.bib), listed on docs/references.md.
bibtex_bibfiles = ["references.bib"]
bibtex_default_style = "plain"
bibtex_reference_style = "author_year"
bibtex_cite_id = "cite-{key}"  # stable anchors: references.html#cite-gots2006

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "_intersphinx", "examples/README.txt", "**/GALLERY_HEADER.rst"]
templates_path = ["_templates"]
html_static_path = ["_static"]
html_theme = "pydata_sphinx_theme"
html_title = f"transient {release}"
html_theme_options = {
    "navigation_depth": 2,
    "show_toc_level": 2,
    "secondary_sidebar_items": ["page-toc"],
}
html_sidebars = {"changelog": [], "performance": [], "validation": [], "guide/scene_keys": []}

myst_enable_extensions = ["dollarmath", "colon_fence", "deflist"]
myst_heading_anchors = 3

autosummary_generate = True
autodoc_default_options = {"members": True, "member-order": "bysource"}
autodoc_typehints = "none"  # numpydoc docstrings carry the types
numpydoc_show_class_members = False
numpydoc_validation_checks = set()
# Types in Parameters and Returns link where a name below says where to; any other word of a
# type stays text (so that "float, optional" or "array of float [rad]" need no entry).
numpydoc_xref_param_type = True
numpydoc_xref_ignore = "all"
numpydoc_xref_aliases = {
    "Path": "pathlib.Path",
    "Scene": "transient.Scene",
    "Result": "transient.Result",
    "SweepResult": "transient.sweeps.api.SweepResult",
    "SceneError": "transient.SceneError",
    "SimulationError": "transient.SimulationError",
    "Client": "distributed.Client",
}

sphinx_gallery_conf = {
    "examples_dirs": "examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "abort_on_example_error": True,
    "download_all_examples": False,
    "remove_config_comments": True,
    "matplotlib_animations": False,
    "image_scrapers": ("matplotlib",),
    "image_srcset": ["2x"],  # (a second image at twice the dpi: sharp on high-density screens)
    "within_subsection_order": "FileNameSortKey",
    # The API pages of the public names list the examples that use them (``minigallery``).
    "doc_module": ("transient",),
    "backreferences_dir": "generated/backreferences",
}

# Results, scenes and benchmark records are read from the repository, never from elsewhere.
os.environ.setdefault("MPLBACKEND", "Agg")

# The guide's pictures and a first run's output, made in the build from the model's own code
# (_ext/guide_figures.py), and the landing page's cards.
extensions += ["sphinx_design", "guide_figures"]
# The developer guide's layer diagram and layout tables, made from the import contracts and the
# declarations they show (_ext/developer_pages.py).
extensions += ["developer_pages"]
