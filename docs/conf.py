"""Sphinx configuration of conmech's documentation (built by scripts/docs.sh)."""
import conmech

project = "conmech"
author = "conmech developers"
copyright = "2026, conmech developers (MIT)"
release = conmech.__version__
extensions = ["sphinx.ext.autodoc", "sphinx.ext.mathjax", "numpydoc",
              "matplotlib.sphinxext.plot_directive"]
numpydoc_show_class_members = False
numpydoc_validation_checks = set()
autodoc_default_options = {"members": True, "undoc-members": False}
# signatures show numpy's ArrayLike by its name, not its ~25-line expansion (the modules use
# `from __future__ import annotations`, so the annotations are strings autodoc can map)
autodoc_type_aliases = {"ArrayLike": "ArrayLike", "npt.ArrayLike": "ArrayLike",
                        "NDArray": "NDArray"}
autodoc_typehints_format = "short"
python_maximum_signature_line_length = 88      # one parameter per line beyond that
exclude_patterns = ["_build", "ford.md", "ford_assets"]
html_theme = "alabaster"
html_theme_options = {"page_width": "1180px", "sidebar_width": "230px"}
html_static_path = ["_static"]
html_css_files = ["conmech.css"]
templates_path = ["_templates"]
# every page links to the FORD site (build/docs/fortran, beside this one)
html_sidebars = {"**": ["about.html", "navigation.html", "fortran_link.html",
                        "searchbox.html"]}
plot_include_source = True
plot_html_show_source_link = False
# figures at the width of the text (110 dpi x 8 in), fonts readable at that size
plot_formats = [("png", 110)]
plot_rcparams = {"figure.figsize": (8.0, 4.6), "font.size": 11, "axes.titlesize": 12,
                 "legend.fontsize": 10}
nitpicky = False


def _escape_bars(app, what, name, obj, options, lines):
    """Docstrings write |x| for absolute values and norms; reST would read a substitution:
    escape the bars (the docstrings stay plain text for help())."""
    for i, line in enumerate(lines):
        lines[i] = line.replace("|", r"\|")


def _alias_names():
    """Sphinx 9 prints an alias inside a union or a Callable by its repr,
    TypeAliasForwardRef('ArrayLike'); print the name, as it does for a bare annotation."""
    try:
        from sphinx.util.inspect import TypeAliasForwardRef
    except ImportError:          # other Sphinx versions: nothing to mend
        return
    TypeAliasForwardRef.__repr__ = lambda self: self.name


_alias_names()


def setup(app):
    app.connect("autodoc-process-docstring", _escape_bars, priority=400)
