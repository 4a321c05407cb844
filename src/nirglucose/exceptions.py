"""Exception hierarchy of nirglucose.

Every error the package raises on purpose derives from :class:`NirGlucoseError` and
also from the builtin type a caller would expect, so ``except ValueError`` keeps
working (the xarray / scikit-learn habit).
"""

from __future__ import annotations

__all__ = ["NirGlucoseError", "ConfigError", "DataError", "NotFittedError"]


class NirGlucoseError(Exception):
    """Base class of every error raised on purpose by nirglucose."""


class ConfigError(NirGlucoseError, ValueError):
    """An invalid configuration value, preset name or override key."""


class DataError(NirGlucoseError, ValueError):
    """A malformed dataset: missing columns, NaN, non-numeric or out-of-range values."""


class NotFittedError(NirGlucoseError, AttributeError):
    """An estimator was used before ``fit``."""
