"""The physics weight's validation-curve figure."""

from nirglucose.models.tuning import lambda_curve
from nirglucose.plots.physics_weight import figure_lambda_curves


def test_one_panel_per_preset_one_curve_pair_per_pinn():
    curves = {p: {m: lambda_curve(m, p) for m in ("rte-pinn", "original-pinn")}
              for p in ("paper", "wearable")}
    assert all(c is not None for d in curves.values() for c in d.values())
    fig = figure_lambda_curves(curves)
    assert [ax.get_title() for ax in fig.axes[:2]] == ["paper", "wearable"]
    ax = fig.axes[0]
    solid = [ln for ln in ax.lines if ln.get_linestyle() == "-" and len(ln.get_xdata()) == 4]
    assert len(solid) == 2
    assert list(solid[0].get_ydata()) == curves["paper"]["rte-pinn"]["slice_cv_rmse_mgdl"]
