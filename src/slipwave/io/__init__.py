"""Files in and out: acquisition CSVs, CF netCDF, outputs written whole or not at all.

- :mod:`slipwave.io.ingest`: :func:`read_acquisition`, the ingest stage.
- :mod:`slipwave.io.card`: :func:`write_acquisition`, CSVs as a card writes them.
- :mod:`slipwave.io.netcdf`: :func:`write_dataset`, :func:`read_dataset`.
- :mod:`slipwave.io.tables`: :func:`write_table`, :func:`read_table`, slipwave's CSV tables.
- :mod:`slipwave.io.atomic`: :func:`atomic_output`.
- :mod:`slipwave.io.channels`: the channels and their CF attributes.
"""

from slipwave.io.atomic import atomic_output
from slipwave.io.card import write_acquisition
from slipwave.io.channels import CHANNEL_ATTRS, CHANNELS, REQUIRED_CHANNELS
from slipwave.io.ingest import read_acquisition
from slipwave.io.netcdf import read_dataset, write_dataset
from slipwave.io.tables import read_table, write_table

__all__ = [
    "CHANNELS", "CHANNEL_ATTRS", "REQUIRED_CHANNELS", "atomic_output", "read_acquisition",
    "read_dataset", "read_table", "write_acquisition", "write_dataset",
    "write_table",
]
