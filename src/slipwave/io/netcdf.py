"""Datasets stored as compressed CF netCDF4, written whole or not at all."""

from __future__ import annotations

from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from slipwave.errors import SlipwaveError
from slipwave.identity import check_product
from slipwave.io.atomic import atomic_output


def _netcdf_attr(value: Any) -> Any:
    if isinstance(value, bool | np.bool_):
        return int(value)
    if isinstance(value, str | int | float | np.integer | np.floating):
        return value
    if isinstance(value, list | tuple | np.ndarray) and all(
        isinstance(v, int | float | np.integer | np.floating) for v in value
    ):
        return np.asarray(value)
    return str(value)


def write_dataset(ds: xr.Dataset, path: str | PathLike[str]) -> Path:
    """Save a Dataset as compressed netCDF4, whole or not at all.

    Attributes netCDF cannot hold (booleans, None, mappings) are stored as
    integers or text.

    Returns
    -------
    Path
        The written file.

    Parameters
    ----------
    ds
        The Dataset.
    path
        The netCDF file.

    """
    out = ds.copy()
    out.attrs = {k: _netcdf_attr(v) for k, v in ds.attrs.items() if v is not None}
    for name in out.variables:
        out[name].attrs = {
            k: _netcdf_attr(v) for k, v in ds[name].attrs.items() if v is not None
        }
    encoding: dict[str, dict[str, Any]] = {}
    for name, variable in out.variables.items():
        if variable.dtype.kind in "USO":
            # text as its own width: an encoding inherited from a narrower piece (a
            # concatenation keeps the first piece's) would cut the longer strings
            variable.encoding = {k: v for k, v in variable.encoding.items() if k != "dtype"}
        if variable.dtype.kind in "fiu":
            encoding[str(name)] = {"zlib": True, "complevel": 4, "shuffle": True}
            if name in out.coords:
                encoding[str(name)]["_FillValue"] = None
    target = Path(path)
    try:
        with atomic_output(target) as temporary:
            out.to_netcdf(temporary, engine="netcdf4", format="NETCDF4", encoding=encoding)
    except OSError as err:
        raise SlipwaveError(f"{target}: cannot be written: {err}") from err
    return target


def read_dataset(path: str | PathLike[str], product: str | None = None) -> xr.Dataset:
    """Load a Dataset written by :func:`write_dataset` fully into memory.

    Parameters
    ----------
    path
        The netCDF file.
    product
        The kind of product it must be (:data:`slipwave.identity.PRODUCTS`);
        ``None``: any.

    Returns
    -------
    xarray.Dataset
        Its content, loaded.

    Raises
    ------
    SlipwaveError
        If the file cannot be read as netCDF.

    """
    try:
        dataset = xr.load_dataset(path, engine="netcdf4", decode_timedelta=False)
    except (OSError, ValueError) as err:
        raise SlipwaveError(f"{path}: cannot be read as netCDF: {err}") from err
    if product is not None:
        check_product(dataset.attrs, product, path)
    return dataset

