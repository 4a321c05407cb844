"""Shared look of every figure: a colour-blind-safe palette, model colours, saving.

The palette is Okabe & Ito's eight colours, distinguishable under the common forms of
colour-vision deficiency [1]_. Each registered model keeps one colour in every figure
(:data:`MODEL_COLORS`); any other name gets the next unused palette colour.

References
----------
.. [1] Okabe M, Ito K. Color Universal Design (CUD): how to make figures and
   presentations that are friendly to colorblind people. J*Fly, 2008.
   https://jfly.uni-koeln.de/color/
"""

from __future__ import annotations

import io
from collections.abc import Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from functools import wraps
from pathlib import Path

import matplotlib as mpl
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from ..dataset import atomic_write
from ..models.labels import label

__all__ = [
    "OKABE_ITO",
    "GREY",
    "MODEL_COLORS",
    "MODEL_MARKERS",
    "STATUS_COLORS",
    "DATA_COLOR",
    "RC_PARAMS",
    "FIGURE_FORMATS",
    "model_color",
    "model_colors",
    "model_label",
    "model_labels",
    "model_marker",
    "plot_style",
    "styled",
    "new_axes",
    "save_figure",
    "figure_bytes",
    "plain_number",
    "plain_log_ticks",
]

#: Okabe–Ito palette, name -> hex colour.
OKABE_ITO: dict[str, str] = {
    "black": "#000000",
    "orange": "#E69F00",
    "sky_blue": "#56B4E9",
    "bluish_green": "#009E73",
    "yellow": "#F0E442",
    "blue": "#0072B2",
    "vermillion": "#D55E00",
    "reddish_purple": "#CC79A7",
}

#: Grey used for secondary marks (grid lines, the unity line, reference values).
GREY = "#6E6E6E"

#: Fixed colour of each registered model. Yellow, too pale for lines on white, is kept
#: for fills; SDNN gets the neutral grey that usually extends the palette.
MODEL_COLORS: dict[str, str] = {
    "ebl": OKABE_ITO["blue"],
    "pls": OKABE_ITO["sky_blue"],
    "oracle": OKABE_ITO["black"],
    "original-pinn": OKABE_ITO["vermillion"],
    "optimized-pinn": OKABE_ITO["orange"],
    "rte-pinn": OKABE_ITO["bluish_green"],
    "selective-rte-pinn": OKABE_ITO["reddish_purple"],
    "sdnn": "#8C8C8C",
    # reference rows: two of Paul Tol's "muted" colours (also colour-blind safe; Tol P,
    # Colour Schemes, SRON/EPS/TN/09-002, 2021) and a light grey for no skill
    "gp": "#882255",
    "gbr": "#999933",
    "mean": "#BBBBBB",
    # the forward-model estimator and the hybrids: three more of Tol's muted colours
    "physics-inversion": "#332288",
    # the deployable inversion: magenta of Tol's "vibrant" scheme (same reference)
    "device-inversion": "#EE3377",
    "ebl+gp": "#44AA99",
    "physics-inversion+gp": "#CC6677",
    # the PINNs with the forward-model physics term: the rest of Tol's muted set
    "original-pinn-fm": "#AA4499",
    "optimized-pinn-fm": "#DDCC77",
    "rte-pinn-fm": "#117733",
    "selective-rte-pinn-fm": "#88CCEE",
}

#: Marker of each registered model (a second cue besides colour).
MODEL_MARKERS: dict[str, str] = {
    "ebl": "o",
    "pls": "s",
    "oracle": "*",
    "original-pinn": "^",
    "optimized-pinn": "v",
    "rte-pinn": "D",
    "selective-rte-pinn": "P",
    "sdnn": "X",
    "gp": "h",
    "gbr": "p",
    "mean": "d",  # a filled marker: a line marker vanishes into a horizontal error bar
    "physics-inversion": "8",
    "device-inversion": "<",
    "ebl+gp": "H",
    "physics-inversion+gp": ">",
    # a forward-model PINN: its study twin's marker (the colour tells them apart)
    "original-pinn-fm": "^",
    "optimized-pinn-fm": "v",
    "rte-pinn-fm": "D",
    "selective-rte-pinn-fm": "P",
}

#: Colour of each diabetes status of the simulated cohort: four shades of brown, a hue
#: no model has, so that no colour means a model in one figure and a group in another.
STATUS_COLORS: dict[str, str] = {
    "normal": "#E8D2AE",
    "prediabetes": "#C99A5B",
    "type1": "#94632B",
    "type2": "#4F3315",
}

#: Colour of data that belong to no model (measurements, inputs, the cohort).
DATA_COLOR = "#4D4D4D"

#: File formats :func:`save_figure` writes by default.
FIGURE_FORMATS: tuple[str, ...] = ("png", "svg")

#: Matplotlib settings applied while a figure is built (:func:`plot_style`).
RC_PARAMS: dict[str, object] = {
    "figure.dpi": 100,
    "savefig.dpi": 110,
    "font.size": 9.5,
    "axes.titlesize": 10.5,
    "axes.labelsize": 9.5,
    "xtick.labelsize": 8.5,
    "ytick.labelsize": 8.5,
    "legend.fontsize": 8,
    "legend.framealpha": 0.9,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "axes.grid": False,
    "axes.prop_cycle": mpl.cycler(color=list(MODEL_COLORS.values())),
    "svg.fonttype": "none",
    "svg.hashsalt": "nirglucose",
    "image.cmap": "viridis",
}

_FALLBACK = (
    OKABE_ITO["blue"],
    OKABE_ITO["vermillion"],
    OKABE_ITO["bluish_green"],
    OKABE_ITO["orange"],
    OKABE_ITO["reddish_purple"],
    OKABE_ITO["sky_blue"],
    OKABE_ITO["black"],
    "#8C8C8C",
)


def model_colors(models: Iterable[str]) -> dict[str, str]:
    """Colour of each model: the fixed one if registered, else the next palette colour.

    Parameters
    ----------
    models : iterable of str
        Model names, in display order. [-]

    Returns
    -------
    dict of str to str
        Model name -> hex colour. [-]

    Examples
    --------
    >>> model_colors(["ebl", "mine"])
    {'ebl': '#0072B2', 'mine': '#D55E00'}
    """
    names = list(models)
    used = {MODEL_COLORS[m] for m in names if m in MODEL_COLORS}
    spare = [c for c in _FALLBACK if c not in used] or list(_FALLBACK)
    out: dict[str, str] = {}
    k = 0
    for m in names:
        if m in MODEL_COLORS:
            out[m] = MODEL_COLORS[m]
        else:
            out[m] = spare[k % len(spare)]
            k += 1
    return out


def model_color(model: str) -> str:
    """Colour of one model (registered models keep theirs; others get the palette's first)."""
    return model_colors([model])[model]


def model_marker(model: str) -> str:
    """Marker of one model (``'o'`` for unregistered names)."""
    return MODEL_MARKERS.get(model, "o")


#: Labels that replace :func:`nirglucose.models.labels.label` inside :func:`model_labels`.
_LABEL_OVERRIDES: ContextVar[Mapping[str, str] | None] = ContextVar("model_label_overrides",
                                                                      default=None)


@contextmanager
def model_labels(overrides: Mapping[str, str]) -> Iterator[None]:
    """Context in which :func:`model_label` gives ``overrides[model]`` where it has one
    (the report marks a PINN trained with its physics weight at 0 ``physics off`` in
    every figure of its preset).

    Examples
    --------
    >>> with model_labels({"ebl": "EBL (physics off)"}):
    ...     model_label("ebl")
    'EBL (physics off)'
    >>> model_label("ebl")
    'Enhanced Beer–Lambert'
    """
    token = _LABEL_OVERRIDES.set({**(_LABEL_OVERRIDES.get() or {}), **overrides})
    try:
        yield
    finally:
        _LABEL_OVERRIDES.reset(token)


def model_label(model: str) -> str:
    """Display name of a model in a figure: :func:`nirglucose.models.labels.label`, or
    its override inside :func:`model_labels`.

    Examples
    --------
    >>> model_label("ebl")
    'Enhanced Beer–Lambert'
    """
    return (_LABEL_OVERRIDES.get() or {}).get(str(model)) or label(model)


@contextmanager
def plot_style() -> Iterator[None]:
    """Context in which :data:`RC_PARAMS` apply (the global rcParams stay untouched)."""
    with mpl.rc_context(RC_PARAMS):
        yield


def plain_number(x: float, _pos: int | None = None) -> str:
    """Tick label without exponents: 0.01, 1, 100, 10k, 1M.

    Examples
    --------
    >>> [plain_number(v) for v in (0.02, 5, 1000, 20000, 3e6)]
    ['0.02', '5', '1000', '20k', '3M']
    """
    if x >= 1e6:
        return f"{x / 1e6:g}M"
    if x >= 1e4:
        return f"{x / 1e3:g}k"
    return f"{x:g}"


def plain_log_ticks(axis, values) -> None:
    """Readable ticks on a log axis: plain numbers, 1-2-5 steps when under two decades.

    Parameters
    ----------
    axis : matplotlib.axis.Axis
        ``ax.xaxis`` or ``ax.yaxis``, already on a log scale.
    values : array_like
        The data shown on it (its positive finite values set the span). [axis unit]
    """
    import numpy as np
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v) & (v > 0)]
    decades = float(np.log10(v.max() / v.min())) if v.size else 0.0
    subs = (1.0, 2.0, 5.0) if decades < 2.0 else (1.0,)
    axis.set_major_locator(LogLocator(base=10.0, subs=subs, numticks=10))
    axis.set_major_formatter(FuncFormatter(plain_number))
    axis.set_minor_formatter(NullFormatter())


def styled(fn):
    """Decorator: run a plot function inside :func:`plot_style`."""

    @wraps(fn)
    def wrapper(*args, **kwargs):
        with plot_style():
            return fn(*args, **kwargs)

    return wrapper


def new_axes(ax: Axes | None, figsize: Sequence[float] = (5.0, 4.0), **subplot_kw) -> Axes:
    """Return ``ax``, or the Axes of a new Figure (no pyplot state) if it is None."""
    if ax is not None:
        return ax
    with plot_style():
        fig = Figure(figsize=tuple(figsize), layout="constrained")
        return fig.add_subplot(**subplot_kw)


def save_figure(
    fig: Figure, stem: str | Path, formats: Sequence[str] = FIGURE_FORMATS
) -> list[Path]:
    """Write ``fig`` as ``<stem>.<fmt>`` for each format, then close it.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure; closed (its canvas released) after writing.
    stem : str or path
        Output path without suffix; its directory must exist. [-]
    formats : sequence of str
        File formats, e.g. ``("png", "svg")``. [-]

    Returns
    -------
    list of pathlib.Path
        The files written, one per format.
    """
    stem = Path(stem)
    paths = []
    with plot_style():
        for fmt in formats:
            path = stem.with_name(f"{stem.name}.{fmt}")
            paths.append(atomic_write(path, lambda tmp, f=fmt: fig.savefig(tmp, format=f)))
            path.chmod(0o644)  # the temporary file was private; figures are for sharing
    _close(fig)
    return paths


def figure_bytes(fig: Figure, fmt: str = "png", *, close: bool = False) -> bytes:
    """The figure encoded as ``fmt`` (``'png'`` or ``'svg'``), optionally closing it."""
    buf = io.BytesIO()
    with plot_style():
        fig.savefig(buf, format=fmt)
    if close:
        _close(fig)
    return buf.getvalue()


def _close(fig: Figure) -> None:
    import matplotlib.pyplot as plt

    # Figures built here have no pyplot manager; plt.close handles both kinds.
    plt.close(fig)
    fig.clear()
