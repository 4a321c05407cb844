"""Input whitening shared by the networks and the boosted trees (no torch here).

Glucose sits in low-variance directions of the correlated absorbances and physiology;
gradient descent learns those directions last and axis-aligned tree splits cannot follow
them. Decorrelating the standardised inputs (ZCA) exposes them to both.

References
----------
.. [1] A. Kessy, A. Lewin and K. Strimmer, "Optimal whitening and decorrelation",
   Am. Stat. 72, 309-314 (2018). :doi:`10.1080/00031305.2016.1277159`
"""

from __future__ import annotations

import numpy as np

__all__ = ["scale_of", "zca_whitening", "WHITENING_FLOOR"]


def scale_of(x: np.ndarray) -> np.ndarray:
    """Column standard deviations, 1 where a column is constant (no division by 0). [-]"""
    s = np.std(x, axis=0)
    return np.where(s > 1e-12 * np.maximum(np.abs(np.mean(x, axis=0)), 1.0), s, 1.0)


#: Eigenvalue floor of the whitening, relative to the largest eigenvalue of the inputs'
#: correlation matrix: a numerical guard (float32 has ~7 significant digits), so that
#: an exactly constant or collinear column maps to 0 instead of dividing by 0.
WHITENING_FLOOR = 1e-6


def zca_whitening(z: np.ndarray) -> np.ndarray:
    """ZCA whitening matrix of standardised inputs, ``W = C^{-1/2}``.

    ZCA after Kessy, Lewin and Strimmer (2018) [1]_.

    ``z @ W`` has (up to the eigenvalue floor) the identity as covariance and stays as
    close as possible to ``z`` (no rotation): each column keeps its meaning.

    Parameters
    ----------
    z : numpy.ndarray
        (n, d) standardised training inputs. [-]

    Returns
    -------
    numpy.ndarray
        (d, d) symmetric matrix. [-]
    """
    cov = np.atleast_2d(np.cov(z, rowvar=False))
    w, v = np.linalg.eigh(cov)
    w_max = max(float(w.max()), 1e-300)
    inv_sqrt = np.where(w > WHITENING_FLOOR * w_max, 1.0 / np.sqrt(np.maximum(w, 1e-300)), 0.0)
    return (v * inv_sqrt) @ v.T
