"""plots.designs: best RMSE against LEDs, one colour per detector."""

from __future__ import annotations

import pandas as pd

from nirglucose.plots.designs import plot_design_curve


def _designs():
    rows = []
    for det, k, bound, oracle_bound, rmse in (("BPW34", 1, 50.0, 13.0, 14.0),
                                              ("BPW34", 2, 40.0, 12.0, 13.0),
                                              ("FGA01", 1, 45.0, 30.0, 31.0)):
        rows.append({"detector": det, "n_leds": k, "rank": 1, "wavelengths_nm": "900",
                     "bound_rmse_mgdl": bound, "oracle_bound_rmse_mgdl": oracle_bound,
                     "model": "oracle", "rmse_mgdl": rmse, "rmse_ci_low": rmse - 1,
                     "rmse_ci_high": rmse + 1})
    return pd.DataFrame(rows)


def test_design_curve_draws_one_colour_per_detector():
    ax = plot_design_curve(_designs())
    labels = {t.get_text() for t in ax.get_legend().get_texts()}
    assert labels == {f"{d}: {what}" for d in ("BPW34", "FGA01")
                      for what in ("device bound", "oracle-conditioned bound",
                                   "Oracle (true nuisances) RMSE")}
    lines = {ln.get_label(): ln for ln in ax.get_lines()}
    assert lines["BPW34: device bound"].get_ydata().tolist() == [50.0, 40.0]
    assert lines["FGA01: oracle-conditioned bound"].get_ydata().tolist() == [30.0]
    assert lines["BPW34: device bound"].get_color() != lines["FGA01: device bound"].get_color()
    assert [t for t in ax.get_xticks()] == [1, 2]
