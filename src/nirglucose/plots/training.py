"""Figure 7: training dynamics of the networks.

Training and validation loss per epoch for each network and, for the physics-informed
ones, each term of the loss (``train_mse``, ``train_physics``, ...), as recorded in the
benchmark's ``histories.json``.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.transforms import offset_copy

from .style import (
    GREY,
    OKABE_ITO,
    model_color,
    model_label,
    new_axes,
    plain_log_ticks,
    plot_style,
    styled,
)

__all__ = ["TOTAL_LOSS_COLUMNS", "loss_term_columns", "plot_training_history",
           "figure_training_dynamics", "NO_NETWORKS_TEXT",
           "LOSS_AXIS_LABEL"]

#: Columns of a history holding the total losses.
TOTAL_LOSS_COLUMNS: tuple[str, str] = ("train_loss", "val_loss")

_METRIC_SUFFIXES = ("_mgdl", "_pct")

#: Loss axis label: every network standardises glucose (zero mean, unit variance on the
#: training rows) and its data term is the mean squared error there, so 1 is the
#: training mean's loss; physics terms are mean squares of their own residuals.
LOSS_AXIS_LABEL = "loss [MSE, standardised units²]"

#: Relative tolerance under which two loss curves count as one. [-]
_SAME_CURVE_RTOL = 1e-3


def _same_curve(a: np.ndarray, b: np.ndarray) -> bool:
    ok = np.isfinite(a) & np.isfinite(b)
    return bool(ok.any() and np.array_equal(np.isfinite(a), np.isfinite(b))
                and np.allclose(a[ok], b[ok], rtol=_SAME_CURVE_RTOL, atol=0.0))


#: Text of the panel drawn when a run has no networks.
NO_NETWORKS_TEXT = "no networks in this run"

#: Colour of each loss term, the same in every panel (a term's colour used to depend on
#: the model's own colour and the order of its terms). Paul Tol's "muted" colours (Tol P,
#: Colour Schemes, SRON/EPS/TN/09-002, 2021): none is a network's colour.
_TERM_COLOR_BY_NAME = {
    "mse": "#332288",
    "physics": "#CC6677",
    "reflectance": "#117733",
    "scattering_prior": "#AA4499",
}
#: Colours of any other term, in order of appearance.
_TERM_COLORS = ("#44AA99", "#88CCEE", "#DDCC77", "#882255")


def loss_term_columns(history: pd.DataFrame) -> list[str]:
    """Per-term loss columns of a history (``train_*`` / ``val_*`` besides the totals).

    Examples
    --------
    Columns with a unit suffix (``val_rmse_mgdl``) are metrics, not loss terms.

    >>> h = pd.DataFrame({"epoch": [1], "train_loss": [1.0], "val_loss": [1.0],
    ...                   "train_mse": [1.0], "val_rmse_mgdl": [20.0], "lr": [1e-3]})
    >>> loss_term_columns(h)
    ['train_mse']
    """
    return [
        c for c in history.columns
        if c.startswith(("train_", "val_")) and c not in TOTAL_LOSS_COLUMNS
        and not c.endswith(_METRIC_SUFFIXES) and pd.api.types.is_numeric_dtype(history[c])
    ]


@styled
def plot_training_history(
    history: pd.DataFrame,
    *,
    color: str | None = None,
    title: str | None = None,
    log_scale: bool = True,
    held_out: float | None = None,
    ax: Axes | None = None,
) -> Axes:
    """Loss per epoch: training and validation totals and each loss term.

    Parameters
    ----------
    history : pandas.DataFrame
        One row per epoch with ``epoch``, ``train_loss``, optionally ``val_loss`` and
        per-term columns (``train_mse``, ``train_physics``, ...). [loss units of the
        network: MSE on standardised glucose unless the model says otherwise]
    color : str, optional
        Colour of the total-loss lines.
    title : str, optional
        Axes title.
    log_scale : bool
        Logarithmic loss axis (when every value is positive). [-]
    held_out : float, optional
        Held-out (cross-validated) MSE in the same units, a dash-dot line. [loss units]
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure's by default.

    Returns
    -------
    matplotlib.axes.Axes
        The Axes: one line per total-loss column, per loss term, and the held-out one.
    """
    ax = new_axes(ax, figsize=(4.6, 3.4))
    epoch = (history["epoch"].to_numpy(float) if "epoch" in history.columns
             else np.arange(1, len(history) + 1, dtype=float))
    color = color or OKABE_ITO["blue"]
    # Each curve: (split, name, values, colour, total?); a curve equal to one already
    # kept (an SDNN's mse is its total; a physics term that is a single sub-term) is not
    # drawn again but named in that curve's legend entry, so no entry is hidden.
    curves: list[list] = []
    for col, split in (("train_loss", "train"), ("val_loss", "validation")):
        if col in history.columns:
            curves.append([split, "total", history[col].to_numpy(float), color, True])
    terms: dict[str, str] = {}  # term -> colour, shared by its train and val curves
    for col in loss_term_columns(history):
        split, term = col.split("_", 1)
        split = "validation" if split == "val" else "train"
        y = history[col].to_numpy(float)
        if not np.isfinite(y).any():
            continue
        same = next((c for c in curves if c[0] == split and _same_curve(c[2], y)), None)
        if same is not None:
            same[1] += f" = {term}"
            continue
        c = terms.setdefault(term, _TERM_COLOR_BY_NAME.get(
            term, _TERM_COLORS[sum(t not in _TERM_COLOR_BY_NAME for t in terms)
                               % len(_TERM_COLORS)]))
        curves.append([split, term, y, c, False])
    values = []
    for split, name, y, c, total in curves:
        if not np.isfinite(y).any():
            continue  # e.g. no validation split: no empty legend entry
        ax.plot(epoch, y, color=c, ls="--" if split == "validation" else "-",
                lw=1.8 if total else 0.9, zorder=3 if total else 2,
                label=f"{split} {'(' + name + ')' if total else name}")
        values.append(y)
    values += _held_out_line(ax, held_out) if values else []
    finite = np.concatenate(values) if values else np.array([])
    finite = finite[np.isfinite(finite)]
    if log_scale and finite.size and finite.min() > 0:
        ax.set_yscale("log")
        plain_log_ticks(ax.yaxis, finite)
    if not values:
        ax.text(0.5, 0.5, "no loss columns recorded", ha="center", va="center",
                transform=ax.transAxes, color=GREY)
    else:  # below the panel, so that no curve is hidden
        below = offset_copy(ax.transAxes, fig=ax.figure, y=-30, units="points")
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, 0.0),
                  bbox_transform=below, ncol=2, frameon=False)
    ax.set(xlabel="epoch [-]", ylabel=LOSS_AXIS_LABEL,
           title=title if title is not None else "Training dynamics")
    return ax


def _held_out_line(ax: Axes, held_out: float | None) -> list[np.ndarray]:
    """Draw the held-out error as a dash-dot line; its value, for the axis range."""
    if held_out is None or not np.isfinite(held_out):
        return []
    ax.axhline(held_out, color="black", ls="-.", lw=1.1, zorder=4,
               label="held-out (CV, all folds)")
    return [np.array([held_out])]


def figure_training_dynamics(histories: Mapping[str, pd.DataFrame], *, ncols: int = 3,
                             held_out: Mapping[str, float] | None = None) -> Figure:
    """One training-history panel per network, or a panel saying there is none.

    Parameters
    ----------
    histories : mapping of str to pandas.DataFrame
        Model -> per-epoch history (see :func:`plot_training_history`).
    held_out : mapping of str to float, optional
        Model -> its held-out MSE in loss units (see :func:`plot_training_history`).
    ncols : int
        Panels per row. [-]

    Returns
    -------
    matplotlib.figure.Figure
    """
    models = list(histories)
    with plot_style():
        if not models:
            fig = Figure(figsize=(6.0, 1.6), layout="constrained")
            ax = fig.add_subplot()
            ax.set_axis_off()
            ax.text(0.5, 0.5, NO_NETWORKS_TEXT, ha="center", va="center", fontsize=12,
                    color=GREY, transform=ax.transAxes)
            return fig
        ncols = min(ncols, len(models))
        nrows = -(-len(models) // ncols)
        fig = Figure(figsize=(4.2 * ncols, 3.2 * nrows), layout="constrained")
        axes = fig.subplots(nrows, ncols, squeeze=False).ravel()
        for ax, model in zip(axes, models, strict=False):
            plot_training_history(histories[model], color=model_color(model),
                                  title=model_label(model),
                                  held_out=(held_out or {}).get(model), ax=ax)
        for ax in axes[len(models):]:
            ax.set_axis_off()
    return fig
