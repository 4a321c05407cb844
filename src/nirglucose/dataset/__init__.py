"""The data boundary: the Dataset container and everything that reads or checks a file.

One package, one module per concept:

* :mod:`~nirglucose.dataset.container`: :class:`Dataset` (a frame and the scenario that
  produced it), Parquet/CSV IO with atomic writes, partitioned datasets;
* :mod:`~nirglucose.dataset.meta`: the package's metadata stored in a Parquet file;
* :mod:`~nirglucose.dataset.columns`: the column registry (names, units, ranges);
* :mod:`~nirglucose.dataset.files`: reading a user's file (delimiters, names, units,
  glucose in mg/dL or mmol/L, meter flags);
* :mod:`~nirglucose.dataset.adc`: the one ADC-resolution policy;
* :mod:`~nirglucose.dataset.schema`: any device's columns -> named absorbances and
  physiology (:class:`~nirglucose.dataset.schema.DeviceSchema`);
* :mod:`~nirglucose.dataset.small_data`: how many subjects each claim needs.

It imports nothing of the simulator, the models or the evaluation (they import it). The
names below are the container's and the column registry's, importable from here as
before the package was split (``from nirglucose.dataset import Dataset``).

Examples
--------
>>> from nirglucose.dataset import Dataset, measured_columns
>>> measured_columns()[:2]
['adc_850', 'adc_940']
"""

from __future__ import annotations

from ..constants import PHYSIOLOGICAL_RANGES
from .columns import (
    COLUMN_UNITS,
    DEFAULT_ADC_BITS,
    GLUCOSE_REPORTING_RANGE_MGDL,
    KNOWN_PHYSIOLOGY,
    PMF_COLUMNS,
    PPG_COLUMNS,
    WEAR_COLUMNS,
    adc_columns,
    measured_columns,
    ref_columns,
)
from .container import (
    MANIFEST,
    META_KEY,
    PART_PATTERN,
    SUFFIXES,
    Dataset,
    PartitionedDataset,
    atomic_write,
    load_dataset,
    open_partitioned,
    scan_dataset,
)
from .small_data import MIN_FIT_ROWS, MIN_FIT_SUBJECTS

__all__ = [
    "Dataset",
    "PartitionedDataset",
    "load_dataset",
    "open_partitioned",
    "scan_dataset",
    "PMF_COLUMNS",
    "PPG_COLUMNS",
    "MANIFEST",
    "META_KEY",
    "PART_PATTERN",
    "COLUMN_UNITS",
    "WEAR_COLUMNS",
    "adc_columns",
    "ref_columns",
    "measured_columns",
    "atomic_write",
    "SUFFIXES",
    "KNOWN_PHYSIOLOGY",
    "PHYSIOLOGICAL_RANGES",
    "GLUCOSE_REPORTING_RANGE_MGDL",
    "DEFAULT_ADC_BITS",
    "MIN_FIT_ROWS",
    "MIN_FIT_SUBJECTS",
]
