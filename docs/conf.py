"""Sphinx configuration of the nirglucose documentation site (``make docs``).

Sphinx + numpydoc + the PyData theme, because the docstrings are already numpydoc with
doctested examples (the convention of pvlib, scikit-learn and xarray, whose sites use
the same stack); myst-parser renders the Markdown pages (the user guide moved out of the
README, ``features.md``, ``user_guide/your_data.md``); sphinx-gallery runs ``examples/`` in the build.
The CLI reference is generated here at build time from ``nirglucose <command> --help``.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
# a source checkout builds without installation too (``make docs`` installs it anyway)
sys.path.insert(0, str(ROOT / "src"))
os.environ.setdefault("MPLBACKEND", "agg")

import nirglucose  # noqa: E402

# autosummary writes one page per documented name into ``generated/`` and never deletes
# one: a page left from a renamed module would stay in the build (a duplicate target)
import shutil  # noqa: E402

shutil.rmtree(DOCS / "generated", ignore_errors=True)

project = "nirglucose"
author = "nirglucose developers"
copyright = "nirglucose developers, MIT licence"  # noqa: A001
release = nirglucose.__version__
version = release

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.extlinks",
    "sphinx.ext.mathjax",
    "numpydoc",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
templates_path = ["_templates"]
exclude_patterns = [
    "_build",
    "Thumbs.db",
    ".DS_Store",
    "auto_examples/*.ipynb",
    "auto_examples/*.py",
    "auto_examples/*.zip",
    "auto_examples/*.json",
    "auto_examples/*.md5",
    "auto_examples/*.codeobj.json",
]
root_doc = "index"

# -- API reference: autosummary over each public module's __all__, rendered by numpydoc
autosummary_generate = True
autosummary_ignore_module_all = False  # document exactly the names in __all__
autosummary_imported_members = False
autodoc_typehints = "none"  # numpydoc's Parameters section carries the types
autodoc_member_order = "bysource"
autodoc_default_options = {"show-inheritance": False}
numpydoc_show_class_members = False  # the class template lists members itself
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
numpydoc_validation_checks: set[str] = set()

# ``:doi:`10.xxxx/...``` in the docstrings' References sections
extlinks = {"doi": ("https://doi.org/%s", "doi:%s")}
# A References list may hold more than the text cites (a reading list); numpydoc then
# leaves an uncited, renamed citation, which is no error here.
suppress_warnings = ["ref.citation"]

# -- Markdown pages
myst_enable_extensions = ["colon_fence", "dollarmath"]
myst_heading_anchors = 3

# -- Examples gallery: every script runs in the build, on the CPU, in a few seconds
sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "abort_on_example_error": True,
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "show_memory": False,
    "plot_gallery": "True",
}

# -- HTML
html_theme = "pydata_sphinx_theme"
html_title = f"nirglucose {release}"
html_static_path: list[str] = []
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
}
html_show_sourcelink = False

# -- CLI reference: the help of each command, generated at build time
CLI_COMMANDS = [
    "simulate", "keys", "models", "parts", "benchmark", "sweep", "fit", "predict", "export-c",
    "report",
]
_HELP = """
import sys
from typer.main import get_command
from nirglucose.cli import app
get_command(app).main(sys.argv[1:], prog_name="nirglucose", standalone_mode=True)
"""


def _cli_help(args: list[str]) -> str:
    env = {**os.environ, "COLUMNS": "100", "NO_COLOR": "1", "TERM": "dumb",
           "PYTHONPATH": os.pathsep.join([str(ROOT / "src"), os.environ.get("PYTHONPATH", "")])}
    done = subprocess.run(
        [sys.executable, "-c", _HELP, *args, "--help"], capture_output=True, text=True,
        env=env, check=True,
    )
    return "\n".join(line.rstrip() for line in done.stdout.splitlines()).strip() + "\n"


def _write_cli_reference(app) -> None:  # noqa: ARG001 (Sphinx passes the application)
    out = DOCS / "_generated" / "cli"
    out.mkdir(parents=True, exist_ok=True)
    for name, args in [("nirglucose", []), *[(c, [c]) for c in CLI_COMMANDS]]:
        text = _cli_help(args)
        path = out / f"{name}.txt"
        if not path.exists() or path.read_text(encoding="utf-8") != text:
            path.write_text(text, encoding="utf-8")


_CITE = re.compile(r"\[(\d+)\]_")
_CITE_TARGET = re.compile(r"^\s*\.\. \[(\d+)\]", re.MULTILINE)


def _module_citations(app, what, name, obj, options, lines) -> None:  # noqa: ARG001
    """Render ``[n]_`` that points at the module's References list as plain ``[n]``.

    A function or class docstring here may cite its module's numbered references
    (``Shot noise [2]_``), as code comments point back to them; numpydoc renames
    citations per docstring, so such a reference has no target on the page. It stays
    a visible "[n]" pointing at the module page's References.
    """
    text = "\n".join(lines)
    own = set(_CITE_TARGET.findall(text))
    new = _CITE.sub(lambda m: m.group(0) if m.group(1) in own else f"[{m.group(1)}]", text)
    if new != text:
        lines[:] = new.split("\n")


def _skip_member(app, what, name, obj, skip, options):  # noqa: ARG001
    # scikit-learn's generated metadata-routing setters (set_fit_request, ...) are not
    # part of this package's API, and their docstrings point into scikit-learn's site
    if name.startswith("set_") and name.endswith("_request"):
        return True
    return None


def setup(app):
    from pygments.lexers.special import TextLexer

    app.add_lexer("csv", TextLexer)  # the device files in user_guide/your_data.md
    app.connect("builder-inited", _write_cli_reference)
    app.connect("autodoc-process-docstring", _module_citations, priority=100)
    app.connect("autodoc-skip-member", _skip_member)
