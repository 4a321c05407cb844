"""Former home of :mod:`nirglucose.config.keys` (the config keys' units, ranges and
suggestions); kept so that ``from nirglucose.config_keys import ...`` still works."""

from __future__ import annotations

from .config.keys import *  # noqa: F403
from .config.keys import __all__  # noqa: F401
