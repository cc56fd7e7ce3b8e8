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
exclude_patterns = ["_build", "ford.md"]
html_theme = "alabaster"
html_static_path = []
plot_include_source = True
plot_html_show_source_link = False
plot_formats = [("png", 90)]
nitpicky = False


def _escape_bars(app, what, name, obj, options, lines):
    """Docstrings write |x| for absolute values and norms; reST would read a substitution:
    escape the bars (the docstrings stay plain text for help())."""
    for i, line in enumerate(lines):
        lines[i] = line.replace("|", r"\|")


def setup(app):
    app.connect("autodoc-process-docstring", _escape_bars, priority=400)
