"""The hybrids' stacking weights (issue 29): a hybrid is no worse than its parts where
the residual (or the backbone) holds no signal, and keeps the GP where it does."""

from __future__ import annotations

import json

import numpy as np
import pytest

import nirglucose as ng
from nirglucose.exceptions import DataError
from nirglucose.models import load_model
from nirglucose.models._base import predict_input
from nirglucose.models.hybrid import EBLGP, _stacking_weights


def _rmse(pred, y) -> float:
    return float(np.sqrt(np.mean((np.asarray(pred) - np.asarray(y)) ** 2)))


def _held_out(ds, n_test_subjects: int):
    """A subject-grouped split: the last ``n_test_subjects`` subjects are held out."""
    subjects = ds.frame["subject_id"].to_numpy()
    test = np.isin(subjects, np.unique(subjects)[-n_test_subjects:])
    return ds.rows(np.flatnonzero(~test)), ds.rows(np.flatnonzero(test))


@pytest.fixture(scope="module")
def paper():
    return _held_out(ng.simulate("paper", 80, 3, seed=1), 20)


@pytest.fixture(scope="module")
def noise():
    """The paper device with glucose drawn independently of every reading: neither the
    backbone nor the residual has anything to learn."""
    ds = ng.simulate("paper", 40, 3, seed=1)
    frame = ds.frame.copy()
    frame["glucose_mgdl"] = np.random.default_rng(5).uniform(70.0, 250.0, len(frame))
    return _held_out(ng.Dataset(frame, config=ds.config), 10)


def test_stacking_weights_worked_examples():
    """Hand-computed weights of :func:`_stacking_weights`."""
    rng = np.random.default_rng(0)
    b, r_hat = rng.normal(size=50), rng.normal(size=50)
    # the backbone's residual is a quarter of the GP's prediction: s = 0.25 exactly
    a, s = _stacking_weights(b + 0.25 * r_hat, b, r_hat)
    assert a == 1.0 and s == pytest.approx(0.25, abs=1e-12)
    # by hand: <z - b, r> / <r, r> = (1*2 + 2*2) / (2*2 + 2*2) = 0.75
    a, s = _stacking_weights(np.array([1.0, 2.0]), np.zeros(2), np.array([2.0, 2.0]))
    assert (a, s) == (1.0, pytest.approx(0.75))
    # an anti-correlated GP gets 0, a GP three times too small is capped at 1
    assert _stacking_weights(b - r_hat, b, r_hat) == (1.0, 0.0)
    assert _stacking_weights(b + 3.0 * r_hat, b, r_hat) == (1.0, 1.0)
    # a backbone pointing the wrong way: the training mean (z = 0 rows cost nothing)
    assert _stacking_weights(-b, b, np.zeros(50)) == (0.0, 0.0)


@pytest.mark.parametrize("cv", [3, 0])
def test_noise_residual_is_shrunk_away(noise, cv):
    """No signal anywhere: the GP's weight is near 0 and the hybrid is no worse than its
    backbone (nor than the training mean) on held-out subjects."""
    train, test = noise
    y = test.frame["glucose_mgdl"].to_numpy()
    m = EBLGP(cv=cv, backbone_params={"alphas": [10.0]}, random_state=0).fit(train)
    assert m.shrinkage_ < 0.2, m.shrinkage_
    hybrid, backbone = _rmse(m.predict(test), y), _rmse(m.backbone_.predict(test), y)
    no_skill = _rmse(np.full(len(y), train.frame["glucose_mgdl"].mean()), y)
    assert hybrid <= backbone + 0.5, (hybrid, backbone)
    assert hybrid <= no_skill + 0.5, (hybrid, no_skill)


def test_signal_residual_is_kept_and_beats_the_backbone(paper):
    train, test = paper
    y = test.frame["glucose_mgdl"].to_numpy()
    # EBL's backbone as tuned on `paper` (tuned_params.json): the GP learns most of it
    m = EBLGP(backbone_params={"alphas": [1000.0]}, random_state=0).fit(train)
    assert m.shrinkage_ > 0.8 and m.backbone_weight_ == 1.0, (m.shrinkage_, m.backbone_weight_)
    hybrid, backbone = _rmse(m.predict(test), y), _rmse(m.backbone_.predict(test), y)
    assert hybrid < 0.5 * backbone, (hybrid, backbone)


def test_too_few_subjects_keep_the_plain_hybrid(paper):
    """Fewer subjects than folds: no cross-fit, both weights 1 (backbone + GP)."""
    train, test = paper
    two = train.rows(np.flatnonzero(np.isin(train.frame["subject_id"],
                                            np.unique(train.frame["subject_id"])[:2])))
    m = EBLGP(random_state=0).fit(two)
    assert (m.backbone_weight_, m.shrinkage_) == (1.0, 1.0)
    base = m.backbone_.predict(test)
    U = np.column_stack([m.schema_.stacked(predict_input(m, test)), base])
    np.testing.assert_allclose(m.predict(test), base + m.residual_.predict(U), rtol=1e-12)


def test_weights_round_trip_and_forged_weights_are_refused(paper, tmp_path):
    train, test = paper
    m = EBLGP(random_state=0).fit(train)
    path = m.save(tmp_path / "h.json")
    back = load_model(path)
    assert (back.y_mean_, back.backbone_weight_, back.shrinkage_) == (
        m.y_mean_, m.backbone_weight_, m.shrinkage_)
    np.testing.assert_array_equal(back.predict(test), m.predict(test))
    doc = json.loads(path.read_text())
    for key, forged in (("shrinkage_", 2.0), ("backbone_weight_", -0.5),
                        ("shrinkage_", "NaN"), ("shrinkage_", None)):
        bad = json.loads(json.dumps(doc))
        bad["state"][key] = forged
        text = json.dumps(bad).replace('"NaN"', "NaN")
        (tmp_path / "bad.json").write_text(text)
        with pytest.raises(DataError) as err:
            load_model(tmp_path / "bad.json")
        assert "\n" not in str(err.value) and key in str(err.value), str(err.value)
