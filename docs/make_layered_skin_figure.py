"""Figure: detected reflectance and per-layer path of three-layer skin, 700-1300 nm.

Fitzpatrick I (melanosome fraction 0.015) and VI (0.135), otherwise nominal skin (dermal
blood 2 %, SO2 0.7, water 65 %, subcutis fat 80 %, glucose 100 mg/dL, skin 1.8 mm,
epidermis 80 um), the probe of the default config (3 mm, 6.6 mm^2 photodiode), from the
rte-lut model's table (Monte Carlo of the RTE, nirglucose.optics.lut; built on first use,
about 2 hours of CPU, then cached), with the three-layer diffusion model
(nirglucose.optics.layers) dotted for comparison. Also prints, per LED, the share of the
path in the dermis and the glucose sensitivity d ln R / dC at literature magnitudes.

Usage: python docs/make_layered_skin_figure.py [out.png]
(default docs/figures/layered_skin.png)
"""

from __future__ import annotations

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from nirglucose.constants import DEFAULT_LED_WAVELENGTHS_NM, MGDL_PER_MMOLL_GLUCOSE  # noqa: E402
from nirglucose.optics import lut as skin_lut  # noqa: E402
from nirglucose.optics.layers import (  # noqa: E402
    LAYER_NAMES,
    skin_layer_optics,
    three_layer_reflectance,
)

RHO_CM, AREA_CM2, T_EPI_CM, T_SKIN_CM = 0.3, 0.066, 0.008, 0.18
SKINS = {"Fitzpatrick I": 0.015, "Fitzpatrick VI": 0.135}
GLUCOSE_MM = 100.0 / MGDL_PER_MMOLL_GLUCOSE


def solve(wavelength_nm: np.ndarray, melanin: float, glucose_mm: float = GLUCOSE_MM,
          model: str = "rte-lut"):
    o = skin_layer_optics(wavelength_nm, melanin_fraction=melanin, glucose_mm=glucose_mm)
    args = dict(
        mua_epidermis_per_cm=o["mua_epidermis"][0], mua_dermis_per_cm=o["mua_dermis"][0],
        musp_dermis_per_cm=o["musp_dermis"][0], mua_subcutis_per_cm=o["mua_subcutis"][0],
        musp_subcutis_per_cm=o["musp_subcutis"][0], skin_thickness_cm=T_SKIN_CM,
    )
    if model == "rte-lut":
        r, paths = skin_lut.interpolate_lut(skin_lut.get_lut(RHO_CM, T_EPI_CM), pathlengths=True,
                                            **args)
    else:
        r, paths = three_layer_reflectance(RHO_CM, epidermis_thickness_cm=T_EPI_CM, **args)
    return r * AREA_CM2, paths


def led_table() -> list[str]:
    leds = np.asarray(DEFAULT_LED_WAVELENGTHS_NM)
    rows = ["| LED nm | skin | detected fraction | path epidermis / dermis / subcutis (mm) "
            "| dermis share | d ln R / dC (1e-4 per mM) |", "|---|---|---|---|---|---|"]
    for name, mel in SKINS.items():
        frac, paths = solve(leds, mel)
        frac_hi, _ = solve(leds, mel, GLUCOSE_MM + 1.0)
        sens = (np.log(frac_hi) - np.log(frac)) * 1e4
        for i, wl in enumerate(leds):
            p = paths[i] * 10.0
            rows.append(
                f"| {wl:g} | {name.split()[1]} | {frac[i]:.2e} | {p[0]:.2f} / {p[1]:.1f} / "
                f"{p[2]:.1f} | {p[1] / p.sum():.0%} | {sens[i]:+.1f} |"
            )
    return rows


def main(out: Path) -> None:
    wl = np.arange(700.0, 1301.0, 5.0)
    fig, axes = plt.subplots(1, 3, figsize=(13.5, 4.2), constrained_layout=True)
    styles = {"Fitzpatrick I": "-", "Fitzpatrick VI": "--"}
    colours = dict(zip(LAYER_NAMES, ("#8c564b", "#d62728", "#1f77b4"), strict=True))
    for name, mel in SKINS.items():
        frac, paths = solve(wl, mel)
        axes[0].semilogy(wl, frac, styles[name], color="k", label=f"{name} (RTE, Monte Carlo)")
        frac_d, _ = solve(wl, mel, model="diffusion")
        axes[0].semilogy(wl, frac_d, ":", color="0.45", lw=1.0,
                         label="diffusion model" if mel == SKINS["Fitzpatrick VI"] else None)
        for j, layer in enumerate(LAYER_NAMES):
            axes[1].semilogy(wl, paths[:, j] * 10.0, styles[name], color=colours[layer],
                             label=f"{layer}, {name.split()[1]}")
        axes[2].plot(wl, paths[:, 1] / paths.sum(axis=1), styles[name], color="k", label=name)
    for ax in axes:
        for led in DEFAULT_LED_WAVELENGTHS_NM:
            ax.axvline(led, color="0.8", lw=0.8, zorder=0)
        ax.set_xlabel("wavelength (nm)")
        ax.set_xlim(700, 1300)
    axes[0].set_ylabel("detected fraction  R(3 mm) x 6.6 mm$^2$")
    axes[0].set_title("Detected reflectance")
    axes[1].set_ylabel("mean path of detected light (mm)")
    axes[1].set_title("Path per layer")
    axes[2].set_ylabel("share of the path in the dermis")
    axes[2].set_title("Where interstitial glucose is")
    axes[2].set_ylim(0, 1)
    axes[0].legend(frameon=False, fontsize=8)
    axes[1].legend(frameon=False, fontsize=7, ncol=2)
    axes[2].legend(frameon=False)
    fig.suptitle("Three-layer skin (epidermis 80 um, skin 1.8 mm, fat below), source-detector "
                 "3 mm; grey lines: the four LEDs", fontsize=10)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=130)
    print("\n".join(led_table()))


if __name__ == "__main__":
    default = Path(__file__).resolve().parent / "figures" / "layered_skin.png"
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else default)
