"""Drop-one-LED refits: the LED that carries the glucose is the one that costs most to lose."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import nirglucose as ng
from nirglucose.evaluation import Protocol
from nirglucose.evaluation.benchmark.drop_one import (
    DEFAULT_DROP_ONE_MODELS,
    DROP_ONE_COLUMNS,
    resolve_drop_one_models,
    without_led,
)
from nirglucose.evaluation.benchmark.run import run_benchmark
from nirglucose.evaluation.splits import make_splits
from nirglucose.exceptions import ConfigError, DataError
from nirglucose.models import make_model

WAVELENGTHS = (850.0, 940.0, 1050.0, 1150.0)
THREE_BY_TWO = Protocol(n_splits=3, repeats=2, seed=0, resamples=200)
FAST = {"oracle_reference": False,
        "timing": {"n_single": 3, "min_single": 1, "warmup": 1, "batch_rows": 50,
                   "batch_repeats": 1}}


def _one_led_carries_glucose(n_subjects: int = 24, per_subject: int = 4) -> pd.DataFrame:
    """Four channels sharing each subject's skin (correlated), glucose at 1050 nm only.

    Absorbance A_k = 0.5 + 0.1 s + e (s: the subject's skin, e: 0.003 noise); the
    1050 nm channel adds 0.05 per 100 mg/dL. Codes are 3000 exp(-A) on a 12-bit ADC with
    a reference of 3000. With every LED a linear model reads glucose from 1050 nm and
    the skin from the others; without 1050 nm nothing in the data knows glucose.
    """
    rng = np.random.default_rng(7)
    n = n_subjects * per_subject
    sid = np.repeat(np.arange(n_subjects), per_subject)
    skin = rng.normal(0.0, 1.0, n_subjects)[sid]
    glucose = rng.uniform(70.0, 300.0, n)
    frame = {"subject_id": sid, "measurement_id": np.arange(n), "glucose_mgdl": glucose}
    for w in WAVELENGTHS:
        a = 0.5 + 0.1 * skin + rng.normal(0.0, 0.003, n)
        if w == 1050.0:
            a = a + 0.05 * (glucose - 180.0) / 100.0
        frame[f"adc_{w:g}"] = np.round(3000.0 * np.exp(-a))
        frame[f"adc_ref_{w:g}"] = np.full(n, 3000.0)
    return pd.DataFrame(frame)


@pytest.fixture(scope="module")
def informative(tmp_path_factory):
    out = tmp_path_factory.mktemp("drop") / "r"
    ds = ng.Dataset(_one_led_carries_glucose(), metadata={"adc_bits": 12})
    seen = []
    res = run_benchmark(ds, ["ebl", "pls"], protocol=THREE_BY_TWO, out=out,
                        drop_one_models="all", on_task=lambda s, c: seen.append((s, c)),
                        **FAST)
    return ds, out, res, seen


def test_the_informative_led_costs_significantly_more(informative):
    _, _, res, _ = informative
    t = res.drop_one
    for model in ("ebl", "pls"):
        part = t[t["model"] == model].set_index("dropped_wavelength_nm")
        key = part.loc[1050.0]
        others = part.drop(index=1050.0)
        # dropping 1050 nm loses the glucose: its CI lies above 0 ...
        assert key["ci_low"] > 0 and key["significant"], model
        # ... and above every other LED's CI: significantly more costly than any other
        assert key["ci_low"] > others["ci_high"].max(), model
        # without it the model is no better than a few mg/dL below the spread of glucose
        assert key["rmse_without_mgdl"] > 0.6 * np.std(res.dataset.frame["glucose_mgdl"])


def test_table_columns_and_values_are_the_paired_rmses(informative):
    ds, out, res, _ = informative
    t = res.drop_one
    assert list(t.columns) == list(DROP_ONE_COLUMNS)
    assert list(pd.read_csv(out / "drop_one.csv").columns) == list(DROP_ONE_COLUMNS)
    assert len(t) == 2 * 4 and (t["n_test_subjects"] == 24).all() and (t["n_repeats"] == 1).all()
    np.testing.assert_allclose(t["delta_rmse_mgdl"], t["rmse_without_mgdl"] - t["rmse_all_mgdl"])
    assert ((t["ci_low"] <= t["delta_rmse_mgdl"]) & (t["delta_rmse_mgdl"] <= t["ci_high"])).all()
    # "with every LED" is the model's own first repeat in predictions.parquet
    p = res.predictions[(res.predictions["model"] == "pls") & (res.predictions["repeat"] == 0)]
    rmse0 = float(np.sqrt(np.mean((p["scored_mgdl"] - p["reference_mgdl"]) ** 2)))
    assert np.allclose(t.loc[t["model"] == "pls", "rmse_all_mgdl"], rmse0)
    # "without" is an independent refit of PLS (deterministic) on the 3-LED data, same folds
    splits = [s for s in make_splits(ds.frame["subject_id"].to_numpy(), "grouped-cv",
                                     n_splits=3, repeats=2, seed=0) if s.repeat == 0]
    small = without_led(ds, 940.0)
    sq = []
    for s in splits:
        m = make_model("pls").fit(small.rows(s.train))
        pred = np.maximum(m.predict(small.rows(s.test)), 0.0)
        sq.append((pred - ds.frame["glucose_mgdl"].to_numpy()[s.test]) ** 2)
    want = float(np.sqrt(np.mean(np.concatenate(sq))))
    got = t[(t["model"] == "pls") & (t["dropped_wavelength_nm"] == 940.0)]["rmse_without_mgdl"]
    assert np.isclose(float(got.iloc[0]), want, rtol=1e-9)


def test_refits_are_tasks_of_the_first_repeat_with_the_models_seeds(informative):
    _, out, res, seen = informative
    drops = [s for s, _ in seen if "drop_nm" in s]
    assert len(drops) == 2 * 3 * 4  # models x folds of the first repeat x LEDs
    assert {s["repeat"] for s in drops} == {0}
    own = {(s["model"], s["fold"]): s for s, _ in seen if "drop_nm" not in s and s["repeat"] == 0}
    for s in drops:
        base = own[(s["model"], s["fold"])]
        assert {k: v for k, v in s.items() if k not in ("drop_nm", "timed")} == {
            k: v for k, v in base.items() if k != "timed"}
    assert len(list((out / ".tasks").glob("*-no1050-*.json"))) == 2 * 3
    assert res.meta["drop_one_models"] == ["ebl", "pls"]


def test_resumes_from_cache_and_is_the_same_for_any_jobs(informative, tmp_path):
    ds, out, res, _ = informative
    again = run_benchmark(ds, ["ebl", "pls"], protocol=THREE_BY_TWO, out=out,
                          drop_one_models="all", **FAST)
    assert again.meta["tasks_computed"] == 0
    pd.testing.assert_frame_equal(again.drop_one, res.drop_one)
    two = run_benchmark(ds, ["ebl", "pls"], protocol=THREE_BY_TWO, out=tmp_path / "j2",
                        drop_one_models="all", jobs=2, **FAST)
    assert two.meta["tasks_computed"] == two.meta["tasks_total"]
    pd.testing.assert_frame_equal(two.drop_one, res.drop_one)


def test_without_led_is_a_three_led_device_the_oracle_reads():
    ds = ng.simulate("paper", n_subjects=10, per_subject=2, seed=1)
    small = without_led(ds, 1150)
    assert small.config.leds.wavelengths_nm == (850.0, 940.0, 1050.0)
    assert not {"adc_1150", "adc_ref_1150"} & set(small.frame.columns)
    assert len(small.frame.columns) == len(ds.frame.columns) - 2
    pred = make_model("oracle").fit(small).predict(small)
    assert pred.shape == (20,) and np.isfinite(pred).all()
    with pytest.raises(DataError, match="no LED at 1300 nm"):
        without_led(ds, 1300)
    one = ds.frame.drop(columns=[c for c in ds.frame.columns
                                 if c.startswith("adc_") and not c.endswith("850")])
    with pytest.raises(DataError, match="one LED"):
        without_led(ng.Dataset(one, metadata={"adc_bits": 12}), 850)


def test_resolving_the_models():
    names = ["ebl", "mean", "gp", "original-pinn", "original-pinn/no-physics", "oracle"]
    assert resolve_drop_one_models(None, names) == [m for m in names
                                                    if m in DEFAULT_DROP_ONE_MODELS]
    assert resolve_drop_one_models("none", names) == resolve_drop_one_models([], names) == []
    assert "original-pinn/no-physics" not in resolve_drop_one_models("all", names)
    assert resolve_drop_one_models("gp, ebl", names) == ["ebl", "gp"]
    with pytest.raises(ConfigError, match=r"\['sdnn'\] are not benchmarked"):
        resolve_drop_one_models("sdnn", names)


def test_cli_bad_drop_one_is_one_line(tmp_path, capsys):
    from nirglucose.cli import main

    argv = ["benchmark", "--models", "pls", "--subjects", "10", "--per-subject", "2",
            "--folds", "2", "--repeats", "1", "--resamples", "50", "--no-references",
            "--no-ablation", "--drop-one", "sdnn", "--out", str(tmp_path / "r")]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "sdnn" in err[0] and "Traceback" not in err[0]


def test_paper_split_refits_its_one_split_on_its_test_subjects():
    ds = ng.Dataset(_one_led_carries_glucose(n_subjects=20, per_subject=3),
                    metadata={"adc_bits": 12})
    res = run_benchmark(ds, ["pls"], protocol=Protocol("paper-split", resamples=200),
                        drop_one_models="pls", **FAST)
    t = res.drop_one
    assert t["dropped_wavelength_nm"].tolist() == list(WAVELENGTHS)
    assert (t["n_test_subjects"] == res.predictions["subject_id"].nunique()).all()
    assert res.meta["tasks_total"] == 1 + 4
