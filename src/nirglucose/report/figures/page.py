"""The report page being built: what every section builder reads, and the figures so far
(a leaf of the figure sections: :mod:`.sections` and :mod:`.diagnostics` both build on it,
neither imports the other back)."""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from ...models.labels import label, row_privilege
from .inputs import is_ablation_row
from .results import RenderedFigure, Results

__all__ = ["Page"]

logger = logging.getLogger(__package__)  # the package's name, as before the split


@dataclass
class Page:
    """What every section builder of :func:`render_figures` reads, and the figures so far.

    ``add`` numbers every figure in page order (so the contents and the captions
    agree), draws the wanted ones and keeps them in :attr:`rendered`.
    """

    results: Results
    out_dir: Path | None
    formats: Sequence[str]
    wanted: set[str] | None
    compare: Mapping[str, pd.DataFrame] | None
    #: The other presets' runs of the same benchmark (figures drawn for each too).
    peers: Sequence[Results] = ()
    rendered: list[RenderedFigure] = field(default_factory=list)
    count: int = 0
    #: Models fitted for the architecture figure, by name (the features figure reuses EBL).
    fitted: dict[str, Any] = field(default_factory=dict)
    #: Added to every key and title (a preset's figures drawn for each preset).
    key_suffix: str = ""
    title_suffix: str = ""

    @property
    def models(self) -> list[str]:
        return self.results.models

    @property
    def preds(self) -> pd.DataFrame:
        return self.results.predictions

    @property
    def pred_models(self) -> list[str]:
        have = set(self.preds["model"])
        return [m for m in self.models if m in have and not is_ablation_row(m)]

    @property
    def user_data(self) -> bool:
        """A user's measurements (:attr:`Results.user_data`)."""
        return self.results.user_data

    @property
    def rep_note(self) -> str:
        p = self.preds
        n_rep = int(p["repeat"].nunique()) if "repeat" in p.columns else 1
        return (f"every out-of-fold prediction of all {n_rep} repeats pooled, so the zone "
                f"shares equal the table's" if n_rep > 1 else "every out-of-fold prediction")

    @property
    def label_overrides(self) -> dict[str, str]:
        """Figure labels of this run's PINNs tuned to λ = 0 (``physics off``) and of its
        privileged rows (``reference``), for every figure of the run."""
        params = self.results.meta.get("model_params") or {}
        out = {str(m): f"{label(str(m))} (physics off)" for m, p in params.items()
               if isinstance(p, dict) and p.get("lambda_phys") == 0 and "/" not in str(m)}
        out.update({m: f"{label(m)} (reference)" for m in self.models
                    if m != "oracle" and "/" not in m and row_privilege(m) is not None})
        return out

    def wants(self, *keys: str) -> bool:
        """Whether any of ``keys`` is to be drawn."""
        return self.wanted is None or bool(self.wanted & set(keys))

    def add(self, key: str, title: str, caption: str, build: Callable[[], Any] | None,
            note: str | None = None) -> None:
        """Number the next figure; draw it (``build``) if it is wanted.

        A figure whose PNG is byte for byte one already on the page is not added a
        second time: the first one's caption says it stands for both.
        """
        from ...plots.style import figure_bytes, model_labels, save_figure

        self.count += 1
        number = str(self.count)
        key, title = key + self.key_suffix, title + self.title_suffix
        if not self.wants(key):
            return
        out = RenderedFigure(key=key, number=number, title=title, caption=caption, note=note)
        fig = None
        if build is not None:
            try:
                with model_labels(self.label_overrides):
                    fig = build()
            except (ValueError, KeyError, TypeError, IndexError) as exc:
                logger.exception("figure %s could not be drawn", number)
                out.note = f"Figure {number} could not be drawn: {exc}"
        if fig is not None:
            out.png = figure_bytes(fig, "png")
            twin = next((r for r in self.rendered if r.png and r.png == out.png), None)
            if twin is not None:  # the same picture (e.g. a preset's identical environment)
                twin.caption += (f" The same figure for {title.split(' on ', 1)[-1]}"
                                 if " on " in title else f" The same figure as {title}") \
                    + " (identical pixels: drawn once)."
                self.count -= 1
                fig.clear()
                return
            if self.out_dir is not None:
                out.files = save_figure(fig, self.out_dir / f"fig{number}_{key}", self.formats)
            else:
                fig.clear()
        self.rendered.append(out)
