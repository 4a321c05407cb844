"""The tuning's validation curve of each PINN: CV RMSE against the physics weight λ.

Input: :func:`nirglucose.models.tuning.lambda_curve` per PINN and preset (the packaged
tuning file, on the tuning seeds, never the reported ones); nothing here computes.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from matplotlib.figure import Figure

from .style import GREY, model_color, model_label, model_marker, plot_style

__all__ = ["figure_lambda_curves"]


def figure_lambda_curves(curves: Mapping[str, Mapping[str, dict]]) -> Figure:
    """One panel per preset: each PINN's tuning-CV RMSE against λ.

    Parameters
    ----------
    curves : mapping
        ``{preset: {pinn: curve}}`` with ``curve`` as returned by
        :func:`~nirglucose.models.tuning.lambda_curve` (``lambda_phys``,
        ``slice_cv_rmse_mgdl``, ``profile_cv_rmse_mgdl``, ``tuned_lambda_phys``,
        ``no_skill_rmse_mgdl``).

    Returns
    -------
    matplotlib.figure.Figure
        The slice (tuned training parameters, only λ changes) solid, the profile (best
        tuning draw per λ) dashed, the tuned λ ringed; λ on a symmetric-log axis so
        that 0 is drawn. [mg/dL]
    """
    presets = list(curves)
    with plot_style():
        fig = Figure(figsize=(5.2 * len(presets), 4.0), layout="constrained")
        axes = np.atleast_1d(fig.subplots(1, len(presets), squeeze=False)[0])
        for ax, preset in zip(axes, presets, strict=True):
            no_skill = None
            for pinn, c in curves[preset].items():
                lam = np.asarray(c["lambda_phys"], float)
                sl = np.asarray([np.nan if v is None else v for v in c["slice_cv_rmse_mgdl"]])
                pr = np.asarray([np.nan if v is None else v for v in c["profile_cv_rmse_mgdl"]])
                col = model_color(pinn)
                ax.plot(lam, sl, color=col, marker=model_marker(pinn), ms=5,
                        label=model_label(pinn))
                ax.plot(lam, pr, color=col, ls="--", lw=1.0)
                k = int(np.argmin(np.abs(lam - float(c["tuned_lambda_phys"]))))
                ax.plot(lam[k], sl[k], "o", ms=11, mfc="none", mec=col, mew=1.6)
                no_skill = c.get("no_skill_rmse_mgdl") or no_skill
            if no_skill:
                ax.axhline(no_skill, color=GREY, ls=":", lw=1.0)
                ax.annotate(f"no skill {no_skill:.1f}", (1.0, no_skill), ha="right",
                            va="bottom", fontsize=7.5, color=GREY,
                            xycoords=("axes fraction", "data"))
            ax.set_xscale("symlog", linthresh=0.01)
            ax.set_xlim(-0.002, 1.5)
            ax.set_xticks([0.0, 0.01, 0.1, 1.0], ["0", "0.01", "0.1", "1"])
            ax.set_xlabel("physics weight λ [-]")
            ax.set_ylabel("tuning-CV RMSE [mg/dL]")
            ax.set_title(preset)
        axes[0].legend(fontsize=7.5, title="slice (solid), profile (dashed); ring: tuned",
                       title_fontsize=7.5)
    return fig
