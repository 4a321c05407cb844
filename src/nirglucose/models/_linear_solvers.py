"""Fast inner cross-validation of the linear models: one pass of sufficient statistics.

Ridge (EBL) and PLS1 (the PLS baseline) choose their penalty or component count by
subject-grouped inner CV. Rather than refitting per fold and candidate, the sums over
each fold's rows (Gram matrix, cross-products, means) are accumulated once; every
fold's standardised problem and every candidate's coefficients come from them.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from threadpoolctl import threadpool_limits

__all__ = ["StandardizedFit", "fit_standardized_cv", "pls1_coefs", "ridge_coefs"]


class StandardizedFit(NamedTuple):
    """Sufficient statistics of a standardised least-squares problem (all rows)."""

    R: np.ndarray  # X^T X of the standardised inputs, (p, p)
    xy: np.ndarray  # X^T (y - ybar), (p,)
    mean: np.ndarray  # input means, (p,)
    scale: np.ndarray  # input SDs (1 where constant), (p,)
    ybar: float
    mse: np.ndarray | None  # inner-CV MSE per hyperparameter value, or None


def _standardize_stats(G, zy, zsum, ysum, n):
    """From sums over n rows (z z^T, z y, z, y), the problem on rows standardised by
    their own mean and SD: returns ``(R, xy, mu, sd, ybar)``."""
    mu = zsum / n
    ybar = ysum / n
    cov = G - n * np.outer(mu, mu)
    sd = np.sqrt(np.clip(np.diag(cov) / n, 0.0, None))
    sd[sd <= 1e-12] = 1.0
    R = cov / np.outer(sd, sd)
    return (R + R.T) / 2.0, (zy - mu * ysum) / sd, mu, sd, ybar


def fit_standardized_cv(inputs, n, y, folds, solve) -> StandardizedFit:
    """Standardise, cross-validate a family of linear solutions, return the statistics.

    Parameters
    ----------
    inputs : callable
        ``inputs(rows)`` -> (p, len(rows)) inputs of those rows (one row per input).
    n : int
        Number of rows.
    y : numpy.ndarray
        Target, (n,).
    folds : numpy.ndarray or None
        Inner fold of each row, or None for no CV.
    solve : callable
        ``solve(R, xy)`` -> (p, h) standardised coefficients, one column per
        hyperparameter value.

    Each fold is standardised exactly by its own training rows, computed from sums over
    all rows minus sums over the fold (rows are sorted by fold, so a fold is one
    contiguous block): one pass over the data in all.
    """
    order = np.argsort(folds, kind="stable") if folds is not None else np.arange(n)
    with threadpool_limits(limits=1, user_api="blas"):  # tiny dense algebra
        Z = inputs(order)
        y = np.asarray(y, dtype=float)[order]
        # Global standardisation first, for conditioning of the sums.
        m0 = Z.mean(axis=1)
        Z = Z - m0[:, None]
        s0 = np.sqrt(np.einsum("ij,ij->i", Z, Z) / n)
        s0[s0 <= 1e-12 * np.maximum(np.abs(m0), 1.0)] = 1.0
        Z /= s0[:, None]
        G, zy, zs, ys = Z @ Z.T, Z @ y, Z.sum(axis=1), y.sum()
        mse = None
        if folds is not None:
            bounds = np.searchsorted(folds[order], np.arange(int(folds.max()) + 2))
            sse = 0.0
            for a, b in zip(bounds[:-1], bounds[1:], strict=True):
                Zv, yv = Z[:, a:b], y[a:b]
                R, xy, mu, sd, ybar = _standardize_stats(
                    G - Zv @ Zv.T, zy - Zv @ yv, zs - Zv.sum(axis=1), ys - yv.sum(), n - (b - a)
                )
                coef = solve(R, xy)
                pred = coef.T @ ((Zv - mu[:, None]) / sd[:, None]) + ybar
                sse = sse + ((pred - yv) ** 2).sum(axis=1)
            mse = sse / n
        R, xy, mu, sd, ybar = _standardize_stats(G, zy, zs, ys, n)
    return StandardizedFit(R, xy, m0 + s0 * mu, s0 * sd, float(ybar), mse)


def ridge_coefs(R, xy, alphas) -> np.ndarray:
    """Ridge coefficients for every alpha from one eigen-decomposition, (p, n_alpha).

    coef = V diag(1 / (lambda + alpha)) V^T X^T y with X^T X = V diag(lambda) V^T
    (Hoerl & Kennard 1970).
    """
    lam, V = np.linalg.eigh(R)
    lam = np.clip(lam, 0.0, None)
    return V @ ((V.T @ xy)[:, None] / (lam[:, None] + np.asarray(alphas)[None, :]))


def pls1_coefs(R, xy, n_components: int) -> np.ndarray:
    """PLS1 coefficients for 1..n_components latent variables, (p, n_components).

    The kernel algorithm of Dayal & MacGregor (1997) on X^T X and X^T y: the same
    components as NIPALS / SIMPLS (de Jong 1993) for a single response. When the
    cross-covariance is exhausted (a perfect fit), further columns repeat the last.
    """
    p = len(xy)
    B = np.zeros((p, n_components))
    Rs = np.zeros((p, n_components))
    Ps = np.zeros((p, n_components))
    s = xy.astype(float).copy()
    s_norm0 = np.linalg.norm(s)
    b = np.zeros(p)
    for a in range(n_components):
        norm = np.linalg.norm(s)
        if norm <= 1e-12 * max(s_norm0, 1e-300):
            B[:, a:] = b[:, None]
            break
        w = s / norm
        r = w - Rs[:, :a] @ (Ps[:, :a].T @ w)
        Rr = R @ r
        tt = r @ Rr
        if tt <= 0:
            B[:, a:] = b[:, None]
            break
        pa = Rr / tt
        q = (s @ r) / tt
        s = s - pa * (q * tt)
        Rs[:, a], Ps[:, a] = r, pa
        b = b + r * q
        B[:, a] = b
    return B
