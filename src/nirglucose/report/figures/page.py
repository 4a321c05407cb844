"""The report page being built: what every section builder reads, and the figures so far
(a leaf of the figure sections: :mod:`.sections` and :mod:`.diagnostics` both build on it,
neither imports the other back)."""

from __future__ import annotations

import logging
import multiprocessing
import signal
import sys
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from ...models.labels import label, row_privilege
from .inputs import is_ablation_row
from .results import RenderedFigure, Results

__all__ = ["Page", "draw_pending"]

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
    #: Figures numbered but not drawn yet, with their drawing functions: every builder
    #: runs first, then :func:`draw_pending` draws them (on several processes if asked).
    pending: list[tuple[RenderedFigure, Callable[[], Any], dict[str, str]]] = field(
        default_factory=list)

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
        """Number the next figure; keep ``build`` to draw it (:func:`draw_pending`) if it
        is wanted."""
        self.count += 1
        number = str(self.count)
        key, title = key + self.key_suffix, title + self.title_suffix
        if not self.wants(key):
            return
        out = RenderedFigure(key=key, number=number, title=title, caption=caption, note=note)
        self.rendered.append(out)
        if build is not None:
            self.pending.append((out, build, self.label_overrides))


def _draw(build: Callable[[], Any], labels: Mapping[str, str], number: str,
          stem: Path | None, formats: Sequence[str]) -> tuple[bytes, list[Path], str | None]:
    """Draw one figure with the run's model labels: its PNG bytes, the files written under
    ``stem`` and a note if the drawing failed."""
    from ...plots.style import figure_bytes, model_labels, save_figure

    try:
        with model_labels(labels):
            fig = build()
    except (ValueError, KeyError, TypeError, IndexError) as exc:
        logger.exception("figure %s could not be drawn", number)
        return b"", [], f"Figure {number} could not be drawn: {exc}"
    if fig is None:
        return b"", [], None
    png = figure_bytes(fig, "png")
    if stem is not None:
        return png, save_figure(fig, stem, formats), None
    fig.clear()
    return png, [], None


#: The figures a forked drawing process reads (set just before the fork, by index).
_FORKED: list[tuple[Callable[[], Any], Mapping[str, str], str, Path | None,
                   Sequence[str]]] = []


def _quiet_child() -> None:
    """A drawing child leaves Ctrl-C to its parent and dies quietly when the pool ends it
    (the fork inherits the CLI's handlers, which turn both signals into an exception)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


def _draw_forked(i: int) -> tuple[bytes, list[Path], str | None]:
    return _draw(*_FORKED[i])


def draw_pending(page: Page, jobs: int = 1) -> None:
    """Draw every figure :meth:`Page.add` numbered, in page order, into its
    :class:`RenderedFigure` (PNG bytes, files written, a note if it failed).

    With ``jobs > 1`` on Linux the figures are drawn by ``jobs`` forked processes: the
    drawing functions are closures over the loaded results, which a fork inherits (they
    cannot be pickled). Each figure is drawn the same way in either case, so the bytes do
    not depend on ``jobs``.
    """
    items = [(build, labels, out.number,
              None if page.out_dir is None else page.out_dir / f"fig{out.number}_{out.key}",
              page.formats) for out, build, labels in page.pending]
    if jobs > 1 and len(items) > 1 and sys.platform.startswith("linux"):
        _FORKED[:] = items
        try:
            with multiprocessing.get_context("fork").Pool(min(jobs, len(items)),
                                                          initializer=_quiet_child) as pool:
                drawn = pool.map(_draw_forked, range(len(items)), chunksize=1)
                pool.close()  # the children exit when done: no SIGTERM on a normal end
                pool.join()
        finally:
            _FORKED.clear()
    else:
        drawn = [_draw(*item) for item in items]
    for (out, _, _), (png, files, note) in zip(page.pending, drawn, strict=True):
        out.png, out.files = png, files
        if note is not None:
            out.note = note
    page.pending.clear()
    _drop_repeats(page)


def _drop_repeats(page: Page) -> None:
    """A figure whose PNG is byte for byte one earlier on the page is not shown a second
    time: the first one's caption says it stands for both, the repeat's files are removed
    and the figures after it are renumbered (files renamed), so the numbers stay those of
    page order."""
    kept: list[RenderedFigure] = []
    dropped: list[int] = []
    for out in page.rendered:
        twin = next((r for r in kept if out.png and r.png == out.png), None)
        if twin is None:
            kept.append(out)
            continue
        dropped.append(int(out.number))
        title = out.title
        twin.caption += (f" The same figure for {title.split(' on ', 1)[-1]}"
                         if " on " in title else f" The same figure as {title}") \
            + " (identical pixels: drawn once)."
        for f in out.files:
            Path(f).unlink(missing_ok=True)
    if not dropped:
        return
    for r in kept:  # numbers of figures not drawn (not wanted) keep their place
        new = str(int(r.number) - sum(d < int(r.number) for d in dropped))
        if new != r.number:
            renamed = []
            for f in r.files:
                f = Path(f)
                target = f.with_name(f.name.replace(f"fig{r.number}_", f"fig{new}_", 1))
                f.replace(target)
                renamed.append(target)
            r.files = renamed
            if r.note:
                r.note = r.note.replace(f"Figure {r.number} ", f"Figure {new} ")
            r.number = new
    page.rendered[:] = kept
    page.count -= len(dropped)
