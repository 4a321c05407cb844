"""The HTML report of a benchmark run: figures and tables in one self-contained file.

:mod:`~nirglucose.report.figures` computes each figure's inputs from a results
directory and renders the figures; :mod:`~nirglucose.report.html` builds the page.

>>> from nirglucose.report import build_report
>>> build_report("results/", "results/report.html")  # doctest: +SKIP
"""

from __future__ import annotations

from .figures import RenderedFigure, Results, load_results, render_figures
from .html import build_report, render_html
from .sweep import sweep_section

__all__ = ["build_report", "render_html", "load_results", "render_figures", "Results",
           "RenderedFigure", "sweep_section"]
