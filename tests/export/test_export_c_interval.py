"""The exported C returns the split-conformal interval: text and gcc parity."""

from __future__ import annotations

import shutil
import subprocess

import numpy as np
import pytest

import nirglucose as ng
from nirglucose.calibration.conformal import interval, split_conformal
from nirglucose.dataset import measured_columns
from nirglucose.export import export_c, generate_c
from nirglucose.export.c_codegen import interval_prototype
from nirglucose.models import EnhancedBeerLambert, PLSBaseline, load_model

GCC = shutil.which("gcc")
DRIVER = r"""
#include <stdio.h>
#include "nirglucose_model.h"
int main(int argc, char **argv)
{
    float row[20], lo, hi, g;
    FILE *f;
    if (argc != 2 || !(f = fopen(argv[1], "rb"))) return 1;
    while (fread(row, sizeof(float), 20, f) == 20) {
        g = nirglucose_predict_interval(row, row + 4, row + 8, &lo, &hi);
        printf("%.9g %.9g %.9g\n", (double)lo, (double)g, (double)hi);
    }
    fclose(f);
    return 0;
}
"""


@pytest.fixture(scope="module")
def calibrated():
    train = ng.simulate("wearable", 60, 3, seed=0)
    return {
        "ebl": split_conformal(EnhancedBeerLambert(), train, seed=0),
        "pls": split_conformal(PLSBaseline(), train, seed=0),
    }


def test_interval_only_with_a_calibration(calibrated):
    plain = EnhancedBeerLambert().fit(ng.simulate("wearable", 20, 3, seed=0))
    assert "nirglucose_predict_interval" not in generate_c(plain)["nirglucose_model.c"]
    texts = generate_c(calibrated["ebl"])
    proto = interval_prototype(calibrated["ebl"].schema_)
    assert proto + ";" in texts["nirglucose_model.h"]
    assert "#define NIRGLUCOSE_INTERVAL_LEVEL_PCT 90" in texts["nirglucose_model.h"]
    assert proto in texts["nirglucose_model.c"]


def test_saved_calibration_survives_reload_and_export(calibrated, tmp_path):
    path = calibrated["pls"].save(tmp_path / "pls.json")
    again = load_model(path)
    assert again.conformal_ == calibrated["pls"].conformal_
    assert generate_c(again) == generate_c(calibrated["pls"])


@pytest.mark.skipif(GCC is None, reason="gcc is not installed")
@pytest.mark.parametrize("name", ["ebl", "pls"])
def test_compiled_interval_matches_python(calibrated, name, tmp_path):
    model = calibrated[name]
    out = tmp_path / "fw"
    export_c(model, out)
    (tmp_path / "driver.c").write_text(DRIVER)
    exe = tmp_path / "driver"
    subprocess.run(
        [
            GCC,
            "-std=c99",
            "-Wall",
            "-Wextra",
            "-Werror",
            "-O2",
            "-I",
            str(out),
            str(tmp_path / "driver.c"),
            str(out / "nirglucose_model.c"),
            "-o",
            str(exe),
            "-lm",
        ],
        check=True,
        capture_output=True,
    )
    x = ng.simulate("wearable", 700, 3, seed=9).frame[measured_columns()].to_numpy(np.float32)
    x.tofile(tmp_path / "x.f32")
    res = subprocess.run(
        [str(exe), str(tmp_path / "x.f32")], check=True, capture_output=True, text=True
    )
    c = np.array(res.stdout.split(), dtype=float).reshape(-1, 3)
    py = model.predict(x.astype(np.float64))
    lo, hi = interval(model, py, 0.9)
    assert c.shape == (len(x), 3)
    np.testing.assert_allclose(c[:, 1], py, rtol=0, atol=0.01)
    np.testing.assert_allclose(c[:, 0], np.maximum(lo, 0.0), rtol=0, atol=0.01)
    np.testing.assert_allclose(c[:, 2], hi, rtol=0, atol=0.01)
    assert np.all(c[:, 2] - c[:, 1] > 1.0)  # a real width, not a degenerate interval
