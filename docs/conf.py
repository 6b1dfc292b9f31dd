"""Sphinx configuration of the visprim API reference (``make docs``)."""

from __future__ import annotations

import sys
from pathlib import Path

from sphinx.application import Sphinx

# The package as built by `make install`; the source tree if it is not installed.
ROOT = Path(__file__).resolve().parents[1]
try:
    import visprim
except ImportError:  # pragma: no cover - a source checkout without the install
    sys.path.insert(0, str(ROOT / "python"))
    import visprim

sys.path.insert(0, str(Path(__file__).resolve().parent / "_ext"))

project = "visprim"
author = "The visprim developers"
copyright = "2026, The visprim developers"
release = visprim.__version__
version = release

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",  # the module tables of the API index (no generated pages)
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "sphinx.ext.napoleon",  # the Google-style "Args:" docstrings of visprim.kernels (setup)
    "numpydoc",  # every other docstring
    "cli_reference",  # docs/_ext: the command reference from visprim.cli's parsers
]
napoleon_google_docstring = True
napoleon_numpy_docstring = False

# Docstrings are numpydoc; autodoc lists members in source order.
autodoc_member_order = "bysource"
autodoc_typehints = "none"  # the signatures show them; numpydoc sections give the meaning
# scikit-learn's generated metadata-routing methods document themselves in its own docs.
autodoc_default_options = {
    "members": True,
    "show-inheritance": False,
    "exclude-members": ",".join(
        [
            "get_metadata_routing",
            "set_output",
            "set_fit_request",
            "set_predict_request",
            "set_score_request",
            "set_transform_request",
            "set_predict_proba_request",
            "set_decision_function_request",
            "set_partial_fit_request",
            "set_score_samples_request",
            "set_inverse_transform_request",
        ]
    ),
}
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

autosummary_generate = False
exclude_patterns = ["_build", "_ext", "plot_generated_trial.py"]
html_theme = "alabaster"
# Wide enough for the command usages and the measurement tables at 1280 px.
html_theme_options = {"page_width": "1240px", "sidebar_width": "230px", "body_max_width": "none"}
# Option names keep their two hyphens ("--out", not an en dash).
smartquotes = False
html_title = f"visprim {release}"
html_static_path: list[str] = []
nitpicky = False


def _napoleon_for_kernels_only(
    app: Sphinx, what: str, name: str, obj: object, options: object, lines: list[str]
) -> None:
    """Napoleon reads the Google-style docstrings of ``visprim.kernels`` and nothing else.

    Everywhere else napoleon would take the first ``text: more`` of a constant's ``#:``
    comment for its type ("Type: Look-ahead of the FIR design (frames)"), and numpydoc
    already reads the other docstrings.
    """
    from sphinx.ext.napoleon import _process_docstring

    if name == "visprim.kernels" or name.startswith("visprim.kernels."):
        _process_docstring(app, what, name, obj, options, lines)


def setup(app: Sphinx) -> None:
    """Put napoleon's docstring hook behind :func:`_napoleon_for_kernels_only`."""
    from sphinx.ext.napoleon import _process_docstring

    listeners = app.events.listeners["autodoc-process-docstring"]
    for listener in list(listeners):
        if listener.handler is _process_docstring:
            app.disconnect(listener.id)
    app.connect("autodoc-process-docstring", _napoleon_for_kernels_only)
