"""Signals derived from a recording, shared by detection, plots and reports."""

from __future__ import annotations

import xarray as xr


def load_ratio(recording: xr.Dataset, *, min_fraction: float = 0.05) -> xr.DataArray:
    """T/|N|, the apparent friction ratio, along the recording.

    Parameters
    ----------
    recording
        A Dataset from :func:`slipwave.io.read_acquisition`.
    min_fraction
        Where |N| is below this fraction of its maximum (the start of normal
        loading) the ratio is meaningless and set to NaN.

    Examples
    --------
    The first sample, at |N| = 1 N < 5 % of 85 N, is masked:

    >>> import xarray as xr
    >>> ds = xr.Dataset({"T": ("time", [0.0, 40.0, 85.0]), "N": ("time", [-1.0, -80.0, -85.0])})
    >>> load_ratio(ds).values.round(2).tolist()
    [nan, 0.5, 1.0]

    """
    compressive = abs(recording["N"])
    floor = min_fraction * float(compressive.max(skipna=True))
    ratio = (recording["T"] / compressive).where(compressive > floor)
    ratio.attrs = {"units": "1", "long_name": "T/|N|, tangential over compressive normal load"}
    return ratio.rename("T_over_N")
