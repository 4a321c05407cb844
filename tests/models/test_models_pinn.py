"""The four PINNs: architectures, physics terms, registry, round trips."""

from __future__ import annotations

import numpy as np
import pytest
import torch

import nirglucose as ng
from nirglucose.config import resolve_config
from nirglucose.exceptions import ConfigError
from nirglucose.models import (
    RTEPINN,
    OptimizedPINN,
    OriginalPINN,
    SelectiveRTEPINN,
    available_models,
    load_model,
    make_model,
)
from nirglucose.models._torch_base import TorchRegressor
from nirglucose.models.networks import OriginalPINNNet, RTEPINNNet
from nirglucose.models.physics_losses import (
    beer_lambert_loss,
    glucose_absorptivity_per_cm_per_mgdl,
)
from nirglucose.models.pinn import nominal_optics

PINNS = {
    "original-pinn": OriginalPINN,
    "optimized-pinn": OptimizedPINN,
    "rte-pinn": RTEPINN,
    "selective-rte-pinn": SelectiveRTEPINN,
}
FAST = {"max_epochs": 3, "batch_size": 16, "random_state": 0}


pytestmark = pytest.mark.usefixtures("torch_one_thread")  # tests/conftest.py


@pytest.fixture(scope="module")
def small():
    return ng.simulate("wearable", n_subjects=12, per_subject=3, seed=1)


@pytest.fixture(scope="module")
def fitted(small):
    return {name: make_model(name, **FAST).fit(small) for name in PINNS}


def _lin(n_in: int, n_out: int) -> int:
    return n_in * n_out + n_out


# ----------------------------------------------------------------- architectures


def test_original_pinn_parameter_count_by_hand():
    nir = (4 * 32 + 32) + (32 * 64 + 64) + (64 * 32 + 32)
    pmf = (12 * 16 + 16) + (16 * 32 + 32) + (32 * 16 + 16)
    head = (48 * 128 + 128) + (128 * 64 + 64) + (64 * 1 + 1)
    assert nir + pmf + head == 20_225
    assert OriginalPINN().n_parameters == nir + pmf + head
    net = OriginalPINNNet()
    assert [m.in_features for m in net.modules() if isinstance(m, torch.nn.Linear)] == [
        4,
        32,
        64,
        12,
        16,
        32,
        48,
        128,
        64,
    ]


def test_rte_parameter_counts_by_hand():
    def count(k):
        return (
            _lin(4, 128)
            + _lin(128, 128)
            + _lin(12, 64)
            + _lin(64, 64)
            + _lin(192, 256)
            + _lin(256, 256)
            + _lin(256, 128)
            + _lin(128, 64)
            + _lin(64, 2 * k)
            + _lin(128 + 2 * k, 64)
            + _lin(64, 1)
        )

    assert RTEPINN().n_parameters == count(4) == 187_849
    assert SelectiveRTEPINN().n_parameters == count(2) == 187_333


def test_optimized_pinn_uses_multihead_attention():
    m = OptimizedPINN(d_model=32, n_heads=8)
    net = m.build_module()
    attn = [x for x in net.modules() if isinstance(x, torch.nn.MultiheadAttention)]
    assert len(attn) == 1 and attn[0].num_heads == 8
    assert OptimizedPINN().n_parameters == 76_225
    assert m.n_parameters < OptimizedPINN().n_parameters


def test_rte_heads_start_at_nominal_optics():
    mua0, musp0 = [0.3, 0.4, 0.5, 1.0], [15.0, 13.0, 11.0, 10.0]
    net = RTEPINNNet(mua0, musp0)
    with torch.no_grad():
        _, mua, musp = net(torch.zeros(2, 4), torch.zeros(2, 12))
    assert torch.all(mua > 0) and torch.all(musp > 0)
    np.testing.assert_allclose(mua.mean(0).numpy(), mua0, rtol=0.3)
    np.testing.assert_allclose(musp.mean(0).numpy(), musp0, rtol=0.3)


def test_nominal_optics_are_plausible_skin_values():
    mua, musp = nominal_optics(resolve_config("paper"))
    assert mua.shape == musp.shape == (4,)
    assert np.all((mua > 0.05) & (mua < 3.0))  # NIR skin, 1/cm
    assert np.all((musp > 3.0) & (musp < 40.0))
    assert np.all(np.diff(musp) < 0)  # power law falls with wavelength


def test_rte_pinn_nominal_optics_follow_the_reference_tissue():
    # the RTE PINN's nominal skin is the scenario's optics.reference_tissue, not the default
    base = resolve_config("paper")
    moved = resolve_config("paper", {"optics.reference_tissue.blood_fraction": 0.06,
                                     "optics.reference_tissue.skin_thickness_mm": 3.0})
    wl = base.leds.wavelengths_nm
    p0 = RTEPINN()._physics_from(base, "test", None, wl)
    p1 = RTEPINN()._physics_from(moved, "test", None, wl)
    assert np.all(np.array(p1["nominal_mua_per_cm"]) > np.array(p0["nominal_mua_per_cm"]))
    assert not np.allclose(p1["nominal_musp_per_cm"], p0["nominal_musp_per_cm"])


# ----------------------------------------------------------------- registry and API


def test_registered_by_name():
    names = available_models()
    for name, cls in PINNS.items():
        assert name in names
        assert type(make_model(name)) is cls


@pytest.mark.parametrize("name", list(PINNS))
def test_fit_predict_save_load(fitted, small, name, tmp_path):
    m = fitted[name]
    pred = m.predict(small)
    assert pred.shape == (len(small),) and np.all(np.isfinite(pred))
    path = m.save(tmp_path / f"{name}.json")
    again = load_model(path)
    assert type(again) is type(m)
    np.testing.assert_array_equal(again.predict(small), pred)
    assert again.physics_ == m.physics_


@pytest.mark.parametrize("name", list(PINNS))
def test_history_has_physics_terms(fitted, name):
    rec = fitted[name].history_[0]
    assert {"train_mse", "train_physics", "val_mse", "val_physics"} <= set(rec)
    if "rte" in name:
        assert {"train_reflectance", "train_scattering_prior"} <= set(rec)
    assert rec["train_physics"] > 0


# ----------------------------------------------------------------- physics terms


def test_beer_lambert_constants_are_published_never_the_datasets(fitted, small):
    """The study PINNs are deployable: their glucose constants are the published table's
    at gain 1 (what real skin gives), never the training Dataset's amplified gain."""
    phys = fitted["original-pinn"].physics_
    cfg = small.config
    assert cfg.glucose.signal_gain > 1.0  # an amplified preset
    expected = glucose_absorptivity_per_cm_per_mgdl(
        (850, 940, 1050, 1150), phys["glucose_peak_per_cm_per_mm"], 1.0
    )
    np.testing.assert_allclose(phys["absorptivity_per_cm_per_mgdl"], expected)
    assert phys["signal_gain"] == 1.0 and phys["pathlength_cm"] == 1.0
    assert "published tables" in phys["constants_from"]
    # the same constants from a plain frame of the same device (no scenario to read)
    m = OriginalPINN(max_epochs=1).fit(small.frame)
    np.testing.assert_allclose(m.physics_["absorptivity_per_cm_per_mgdl"], expected)
    m2 = OriginalPINN(max_epochs=1, signal_gain=2.0).fit(small.frame)
    assert m2.physics_["signal_gain"] == 2.0


def test_get_loss_is_parent_mse_plus_weighted_physics(fitted, small):
    m = fitted["original-pinn"]
    t = m._tensors(m._transform(m._measurements(small)[0]))
    y = torch.as_tensor(m._scale_y(small.frame.glucose_mgdl.to_numpy()), dtype=torch.float32)
    batch = {**t, "y": y}
    with torch.no_grad():
        out = m.module_(batch["nir"], batch["pmf"])
        total, terms = m.get_loss(out, y, batch)
        c_hat = out * m.scaler_["y_scale"] + m.scaler_["y_mean"]
        eps = torch.tensor(m.physics_["absorptivity_per_cm_per_mgdl"], dtype=torch.float32)
        phys = beer_lambert_loss(batch["absorbance"], c_hat, eps)
    assert float(terms["mse"]) == pytest.approx(float(torch.mean((out - y) ** 2)), rel=1e-6)
    assert float(terms["physics"]) == pytest.approx(float(phys), rel=1e-5)
    assert float(total) == pytest.approx(float(terms["mse"]) + 0.01 * float(phys), rel=1e-6)


def test_relative_form_stores_training_means(small):
    m = OriginalPINN(physics_form="relative", **FAST).fit(small)
    assert m.physics_["form"] == "relative"
    assert m.physics_["glucose_ref_mgdl"] > 60
    assert all(0 < a < 1 for a in m.physics_["absorbance_ref"])
    rel = m.history_[0]["train_physics"]
    ab = OriginalPINN(**FAST).fit(small).history_[0]["train_physics"]
    assert rel < ab  # the tissue background is gone


def test_rte_optics_are_positive_and_selective_covers_two_leds(fitted, small):
    mua, musp = fitted["rte-pinn"].predict_optics(small)
    assert mua.shape == musp.shape == (len(small), 4)
    assert np.all(mua > 0) and np.all(musp > 0)
    assert np.all(mua < 10) and np.all((musp > 1) & (musp < 100))
    mua2, musp2 = fitted["selective-rte-pinn"].predict_optics(small)
    assert mua2.shape == (len(small), 2)
    assert fitted["selective-rte-pinn"].physics_["wavelengths_nm"] == [1050.0, 1150.0]


def test_rte_offset_makes_nominal_skin_reproduce_mean_absorbance(fitted):
    from nirglucose.models.physics_losses import diffusion_absorbance

    p = fitted["rte-pinn"].physics_
    a = diffusion_absorbance(
        torch.tensor([p["nominal_mua_per_cm"]], dtype=torch.float64),
        torch.tensor([p["nominal_musp_per_cm"]], dtype=torch.float64),
        torch.tensor(p["absorbance_offset"], dtype=torch.float64),
        rho_cm=p["rho_cm"],
        detector_area_cm2=p["detector_area_cm2"],
        n_tissue=p["n_tissue"],
    )
    mean_a = fitted["rte-pinn"].scaler_["nir_mean"]
    np.testing.assert_allclose(a.numpy()[0], mean_a, rtol=1e-9)


def test_rte_regulariser_is_learned(small):
    m = RTEPINN(max_epochs=15, lambda_phys=1.0, patience=None, random_state=0).fit(small)
    first, last = m.history_[0]["train_reflectance"], m.history_[-1]["train_reflectance"]
    assert last < first


@pytest.mark.parametrize(
    "cls, params",
    [
        (OriginalPINN, {"lambda_phys": -1.0}),
        (OriginalPINN, {"physics_form": "log"}),
        (OriginalPINN, {"signal_gain": 0.0}),
        (OptimizedPINN, {"n_heads": 5}),
        (OptimizedPINN, {"dropout": 1.0}),
        (RTEPINN, {"stability_weight": -0.1}),
    ],
)
def test_bad_physics_params_raise(small, cls, params):
    with pytest.raises(ConfigError):
        cls(**params).fit(small)


def test_lambda_phys_changes_the_fit(small):
    a = OriginalPINN(**FAST).fit(small).predict(small)
    b = OriginalPINN(lambda_phys=100.0, **FAST).fit(small).predict(small)
    assert not np.allclose(a, b)


def _plain(cls):
    """``cls`` with the base class's loss: the plain network, no physics term at all."""
    return type(f"Plain{cls.__name__}", (cls,), {"get_loss": TorchRegressor.get_loss})


@pytest.mark.parametrize("name", sorted(PINNS))
def test_lambda_zero_is_exactly_the_plain_network(small, name):
    # The benchmark's physics ablation pairs the tuned lambda_phys against 0: at 0 the
    # network must be the plain one bit for bit (same init, same data path, same steps).
    cls = PINNS[name]
    kw = {"max_epochs": 4, "dropout": 0.1, "random_state": 3, "lambda_phys": 0.0}
    ablated = cls(**kw).fit(small)
    plain = _plain(cls)(**kw).fit(small)
    wa, wb = ablated.module_.state_dict(), plain.module_.state_dict()
    assert wa.keys() == wb.keys()
    assert all(torch.equal(wa[k], wb[k]) for k in wa)
    np.testing.assert_array_equal(ablated.predict(small), plain.predict(small))
    # The physics term is still computed and logged at 0, and a weight > 0 changes the fit.
    assert np.isfinite(ablated.history_[-1]["train_physics"])
    weighted = cls(**{**kw, "lambda_phys": 1.0}).fit(small)
    assert not np.array_equal(weighted.predict(small), ablated.predict(small))
