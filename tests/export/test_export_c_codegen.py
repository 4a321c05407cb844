"""C99 export of the linear models: text, compilation, C-Python parity."""

from __future__ import annotations

import re
import shutil
import subprocess

import numpy as np
import pytest

import nirglucose as ng
from nirglucose.dataset import PMF_COLUMNS, measured_columns
from nirglucose.exceptions import ConfigError, DataError
from nirglucose.export import PROTOTYPE, c_float, export_c, generate_c
from nirglucose.models import EnhancedBeerLambert, Oracle, PLSBaseline

GCC = shutil.which("gcc")
CFLAGS = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-O2"]
DRIVER = r"""
#include <stdio.h>
#include "nirglucose_model.h"
int main(int argc, char **argv)
{
    float row[20];
    FILE *f;
    if (argc != 2 || !(f = fopen(argv[1], "rb"))) return 1;
    while (fread(row, sizeof(float), 20, f) == 20)
        printf("%.9g\n", (double)nirglucose_predict(row, row + 4, row + 8));
    fclose(f);
    return 0;
}
"""


@pytest.fixture(scope="module")
def fitted():
    train = ng.simulate("paper", 40, 3, seed=0)
    return {"ebl": EnhancedBeerLambert().fit(train), "pls": PLSBaseline().fit(train)}


@pytest.fixture(scope="module")
def samples():
    """10,000 simulated snapshots (measured columns), as float32 like a device has."""
    ds = ng.simulate("paper", 3334, 3, seed=9)
    return ds.frame[measured_columns()].to_numpy(np.float32)[:10_000]


def test_header_declares_the_interface(fitted):
    h = generate_c(fitted["ebl"])["nirglucose_model.h"]
    assert (
        "float nirglucose_predict(const float adc[4], const float adc_ref[4], "
        "const float pmf[NIRGLUCOSE_N_PMF]);" in h
    )
    assert PROTOTYPE + ";" in h
    assert "#define NIRGLUCOSE_N_PMF 12\n" in h
    cols = ", ".join(f'"{c}"' for c in PMF_COLUMNS)
    assert f"#define NIRGLUCOSE_PMF_COLUMNS {cols}\n" in h
    assert cols.startswith('"age_yr", "bmi_kgm2"')


@pytest.mark.parametrize("name", ["ebl", "pls"])
def test_source_is_freestanding(fitted, name):
    c = generate_c(fitted[name])["nirglucose_model.c"]
    assert re.findall(r"#include\s*[<\"]([^>\"]+)", c) == ["math.h", "nirglucose_model.h"]
    for word in ("malloc", "calloc", "free(", "printf", "double"):
        assert word not in c
    # Coefficients printed with 9 significant digits as float literals.
    coef = np.asarray(fitted[name].coef_, dtype=np.float32)
    assert f"{c_float(coef[0])}" in c


def test_c_float_literals_round_trip_float32():
    rng = np.random.default_rng(0)
    for x in np.r_[rng.normal(size=200) * 10.0 ** rng.integers(-12, 12, 200), 0.0, 1.0, -3.0]:
        text = c_float(x)
        assert text.endswith("f") and re.fullmatch(r"-?[\d.]+(e[+-]\d+)?f", text), text
        assert np.float32(float(text[:-1])) == np.float32(x)
    with pytest.raises(DataError, match="non-finite"):
        c_float(np.nan)


@pytest.mark.skipif(GCC is None, reason="gcc is not installed")
@pytest.mark.parametrize("name", ["ebl", "pls"])
def test_compiled_c_matches_python(fitted, samples, name, tmp_path):
    model = fitted[name]
    out = tmp_path / "firmware"
    export_c(model, out)
    (tmp_path / "driver.c").write_text(DRIVER)
    exe = tmp_path / "driver"
    # The model itself under the strict flags; the test driver is ordinary C.
    subprocess.run(
        [GCC, *CFLAGS, "-c", str(out / "nirglucose_model.c"), "-o", str(tmp_path / "model.o")],
        check=True,
        capture_output=True,
    )
    subprocess.run(
        [
            GCC,
            "-std=c99",
            "-O2",
            "-I",
            str(out),
            str(tmp_path / "driver.c"),
            str(tmp_path / "model.o"),
            "-o",
            str(exe),
            "-lm",
        ],
        check=True,
        capture_output=True,
    )
    data = tmp_path / "x.f32"
    samples.tofile(data)
    res = subprocess.run([str(exe), str(data)], check=True, capture_output=True, text=True)
    c_pred = np.array(res.stdout.split(), dtype=float)
    py_pred = model.predict(samples.astype(np.float64))
    assert c_pred.shape == (10_000,)
    np.testing.assert_allclose(c_pred, py_pred, rtol=0, atol=0.01)


def test_only_fitted_linear_models_export(fitted, tmp_path):
    ds = ng.simulate("paper", 6, 2, seed=0)
    with pytest.raises(ConfigError, match="only the linear models"):
        export_c(Oracle().fit(ds), tmp_path / "fw")
    with pytest.raises(DataError, match="not fitted"):
        export_c(EnhancedBeerLambert(), tmp_path / "fw")
    with pytest.raises(DataError, match="does not exist"):
        export_c(fitted["ebl"], tmp_path / "no" / "such" / "fw")
    (tmp_path / "file").write_text("x")
    with pytest.raises(DataError, match="not a directory"):
        export_c(fitted["ebl"], tmp_path / "file")
    h, c = export_c(fitted["ebl"], tmp_path / "fw")
    assert h.read_text().startswith("/* nirglucose_model.h")
    assert sorted(p.name for p in (tmp_path / "fw").iterdir()) == [
        "nirglucose_model.c",
        "nirglucose_model.h",
    ]
