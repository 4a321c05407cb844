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
    train = ng.simulate("wearable", 40, 3, seed=0)
    return {"ebl": EnhancedBeerLambert().fit(train), "pls": PLSBaseline().fit(train)}


@pytest.fixture(scope="module")
def samples():
    """10,000 simulated snapshots (measured columns), as float32 like a device has."""
    ds = ng.simulate("wearable", 3334, 3, seed=9)
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
    ds = ng.simulate("wearable", 6, 2, seed=0)
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
    with pytest.raises(DataError, match="out_dir must be a directory path, got int"):
        export_c(fitted["ebl"], 5)
    # the path of a model file exports what the model itself exports
    saved = fitted["ebl"].save(tmp_path / "ebl.json")
    h2, c2 = export_c(str(saved), tmp_path / "fw2")
    assert (h2.read_text(), c2.read_text()) == (h.read_text(), c.read_text())


def _driver(schema) -> str:
    """A driver reading rows of the device's raw columns (float32) and printing glucose."""
    k, m, w = schema.n_channels, len(schema.physiology), len(schema.raw_columns)
    args = ["row"]
    if schema.reference:
        args.append(f"row + {k}")
    if m:
        args.append(f"row + {w - m}")
    return f"""
#include <stdio.h>
#include "nirglucose_model.h"
int main(int argc, char **argv)
{{
    float row[{w}];
    FILE *f;
    if (argc != 2 || !(f = fopen(argv[1], "rb"))) return 1;
    while (fread(row, sizeof(float), {w}, f) == {w})
        printf("%.9g\\n", (double)nirglucose_predict({", ".join(args)}));
    fclose(f);
    return 0;
}}
"""


@pytest.mark.skipif(GCC is None, reason="gcc is not installed")
@pytest.mark.parametrize("name", ["ebl", "pls"])
@pytest.mark.parametrize(
    ("n_leds", "bits", "keep"),
    [
        (1, 10, "none"),
        (1, 12, "all"),
        (3, 14, "all"),
        (3, 12, "some"),
        (4, 16, "all"),
        (4, 12, "paper"),
    ],
)
def test_any_device_compiles_and_matches_python(name, n_leds, bits, keep, tmp_path):
    """gcc parity at N = 1, 3 and 4 LEDs, with and without references and physiology;
    "paper": the paper device's PPG columns, whose blood volume is EBL's perfusion."""
    from device_data import device_overrides

    wl = (850.0, 940.0, 1050.0, 1150.0) if n_leds == 4 else None
    if wl is None:
        from device_data import LED_SETS

        wl = LED_SETS[n_leds]
    preset = "paper" if keep == "paper" else "wearable"
    train = ng.simulate(preset, 30, 3, seed=1, overrides=device_overrides(wl, bits))
    test = ng.simulate(preset, 200, 3, seed=2, overrides=device_overrides(wl, bits))
    f = train.frame
    if keep == "none":  # a bare one-LED device: no reference codes, no physiology
        cols = [c for c in f if c.startswith("adc_") and not c.startswith("adc_ref")]
    elif keep == "some":
        cols = [c for c in f if c.startswith("adc_")] + ["age_yr", "skin_temp_c", "pressure_mbar"]
    else:
        cols = list(f.columns)
    model = (EnhancedBeerLambert if name == "ebl" else PLSBaseline)(adc_bits=bits)
    model.fit(f[[*cols, "glucose_mgdl", "subject_id"]] if keep in ("none", "some") else train)
    s = model.schema_
    assert ("blood_volume_pct" in s.physiology) == (keep == "paper")
    assert s.n_channels == n_leds and s.adc_bits == bits
    out = tmp_path / "fw"
    export_c(model, out)
    header = (out / "nirglucose_model.h").read_text()
    assert f"#define NIRGLUCOSE_N_CHANNELS {n_leds}\n" in header
    assert f"#define NIRGLUCOSE_ADC_BITS {bits}\n" in header
    (tmp_path / "driver.c").write_text(_driver(s))
    subprocess.run(
        [GCC, *CFLAGS, "-c", str(out / "nirglucose_model.c"), "-o", str(tmp_path / "m.o")],
        check=True,
        capture_output=True,
    )
    exe = tmp_path / "driver"
    subprocess.run(
        [GCC, "-std=c99", "-O2", "-I", str(out), str(tmp_path / "driver.c"),
         str(tmp_path / "m.o"), "-o", str(exe), "-lm"],
        check=True,
        capture_output=True,
    )  # fmt: skip
    X = test.frame[list(s.raw_columns)].to_numpy(np.float32)
    data = tmp_path / "x.f32"
    X.tofile(data)
    res = subprocess.run([str(exe), str(data)], check=True, capture_output=True, text=True)
    c_pred = np.array(res.stdout.split(), dtype=float)
    py_pred = model.predict(X.astype(np.float64))
    assert c_pred.shape == (len(X),)
    np.testing.assert_allclose(c_pred, py_pred, rtol=0, atol=0.01)


def test_plain_array_models_do_not_export(tmp_path):
    rng = np.random.default_rng(0)
    m = PLSBaseline().fit(rng.normal(size=(30, 3)), rng.normal(size=30))
    with pytest.raises(DataError, match="plain array"):
        export_c(m, tmp_path / "fw")
