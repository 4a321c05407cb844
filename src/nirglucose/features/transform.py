"""The feature transforms: a device's measurements -> its absorbances and physiology
(:class:`MeasurementTransformer`) or its Enhanced Beer–Lambert features.

:func:`enhanced_beer_lambert` (a DataFrame in, a DataFrame out) and the scikit-learn
transformer :class:`EnhancedBeerLambertFeatures`; both take the vectorised study path
(:func:`~nirglucose.features.study.ebl_feature_matrix`) at the study's device and the
any-device path (:func:`~nirglucose.features.device.compute_features`) elsewhere.

References
----------
.. [1] R. Gani, "Physics-Informed Neural Networks vs. Physics Models for Non-Invasive
   Glucose Monitoring: A Comparative Study Under Noise-Stressed Synthetic Conditions",
   University College London.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from sklearn.base import BaseEstimator, TransformerMixin

from ..dataset import Dataset
from ..dataset.schema import DeviceSchema
from ..fitted import as_raw_input, fit_schema, require_fitted
from .device import compute_features, feature_table
from .study import ebl_feature_matrix

__all__ = ["enhanced_beer_lambert", "EnhancedBeerLambertFeatures", "MeasurementTransformer"]


def enhanced_beer_lambert(
    frame: pd.DataFrame | Dataset, adc_bits: int | None = None
) -> pd.DataFrame:
    """The Enhanced Beer–Lambert features of a device's measurements.

    Parameters
    ----------
    frame : pandas.DataFrame or Dataset
        Measurements with ``adc_<nm>`` columns (any LEDs), optional ``adc_ref_<nm>``
        and any known physiological columns; other columns (``true_*``) are ignored.
    adc_bits : int, optional
        Declared ADC resolution (else the file's, or 12). [bit]

    Returns
    -------
    pandas.DataFrame
        (n, p) features of :func:`feature_table` (56 at the study's device), the
        input's index.

    Raises
    ------
    DataError
        Missing columns, non-numeric cells, NaN, ADC codes out of range, implausible
        physiology (the message names the column and rows).

    Examples
    --------
    >>> import nirglucose as ng
    >>> ds = ng.simulate("wearable", n_subjects=2, per_subject=2, seed=0)
    >>> enhanced_beer_lambert(ds).shape
    (4, 56)
    """
    schema = DeviceSchema.infer(frame, adc_bits)
    if isinstance(frame, Dataset):
        frame = frame.frame
    Xa = schema.raw(frame)
    table = feature_table(schema)
    if schema.is_study:
        values = ebl_feature_matrix(Xa)
    else:
        m = schema.split(Xa)
        values = compute_features(table, schema, m.absorbance, m.physiology)
    return pd.DataFrame(
        values,
        columns=[f.name for f in table],
        index=frame.index,
    )


class EnhancedBeerLambertFeatures(TransformerMixin, BaseEstimator):
    """scikit-learn transformer: a device's measured columns -> its EBL features.

    ``fit`` records the device (:class:`~nirglucose.dataset.schema.DeviceSchema`: from the
    column names of a frame, or plain for an array) and the feature table
    (:func:`feature_table`; 56 features at the study's device), so it can sit in a
    :class:`~sklearn.pipeline.Pipeline` before a scaler and a regressor.

    Parameters
    ----------
    adc_bits : int, optional
        Declared ADC resolution (else the data's, or 12). [bit]

    Examples
    --------
    >>> import nirglucose as ng
    >>> ds = ng.simulate("wearable", n_subjects=2, per_subject=2, seed=0)
    >>> t = EnhancedBeerLambertFeatures().fit(ds.frame)
    >>> t.transform(ds.frame).shape, t.get_feature_names_out()[4]
    ((4, 56), 'dA_1150_940')
    """

    def __init__(self, adc_bits: int | None = None):
        self.adc_bits = adc_bits

    def fit(self, X, y=None):
        """Record the device's schema and feature table; returns self."""
        self.schema_ = fit_schema(self, X, self.adc_bits)
        self.table_ = feature_table(self.schema_)
        if isinstance(X, pd.DataFrame | Dataset):
            self.schema_.raw(X)
        return self

    def transform(self, X) -> np.ndarray:
        """The (n, p) feature matrix."""
        require_fitted(self, "schema_")
        Xa = self.schema_.raw(as_raw_input(self, X, self.schema_))
        if self.schema_.is_study:
            return ebl_feature_matrix(Xa)
        m = self.schema_.split(Xa)
        return compute_features(self.table_, self.schema_, m.absorbance, m.physiology)

    def get_feature_names_out(self, input_features=None) -> np.ndarray:
        """The feature names."""
        require_fitted(self, "schema_")
        return np.asarray([f.name for f in self.table_], dtype=object)

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.requires_fit = True
        if tags.transformer_tags is not None:
            tags.transformer_tags.preserves_dtype = ["float64"]  # always float64 out
        return tags


class MeasurementTransformer(TransformerMixin, BaseEstimator):
    """scikit-learn transformer: a device's columns -> [absorbances | physiology].

    ``fit`` records the device (:class:`~nirglucose.dataset.schema.DeviceSchema`, from
    the column names, or plain for an array); ``transform`` returns the (n, k + m)
    float64 array of the k absorbances and the m physiological columns.

    Parameters
    ----------
    adc_bits : int, optional
        Declared ADC resolution (else from the data's scenario/metadata, or 12). [bit]

    Examples
    --------
    >>> import nirglucose as ng
    >>> ds = ng.simulate("wearable", n_subjects=2, per_subject=2, seed=0)
    >>> t = MeasurementTransformer().fit(ds)
    >>> t.transform(ds).shape, t.get_feature_names_out()[0]
    ((4, 16), 'A_850')
    """

    def __init__(self, adc_bits: int | None = None):
        self.adc_bits = adc_bits

    def fit(self, X, y=None):
        """Record the device's schema; returns self."""
        self.schema_ = fit_schema(self, X, self.adc_bits)
        if isinstance(X, pd.DataFrame | Dataset):
            self.schema_.raw(X)  # validate the device's columns now
        return self

    def transform(self, X) -> np.ndarray:
        """(n, k + m) absorbances then physiology."""
        require_fitted(self, "schema_")
        return self.schema_.stacked(self.schema_.raw(as_raw_input(self, X, self.schema_)))

    def get_feature_names_out(self, input_features=None) -> np.ndarray:
        """``A_<nm>`` for each LED, then the physiological column names."""
        return np.asarray(self.schema_.stacked_names, dtype=object)
