"""Spring-slider records saved by MATLAB: a time column and the spring's force over the normal load.

The Colas et al. (2019) records (paper on paper, ``k{K}Nm_v{V}.mat``) hold ``t``
(s) and ``Fnorm`` = F / (m g), the spring's force over the slider's weight: the
spring-slider's friction ratio. :func:`read_slider_record` reads such a file
into the dataset the spring-slider's stages take, checking what it reads.
"""

from __future__ import annotations

from os import PathLike
from pathlib import Path

import numpy as np
import scipy.io
import xarray as xr

from slipwave import __version__
from slipwave.defaults import CONVENTIONS
from slipwave.errors import AcquisitionError

TIME_VARIABLE = "t"
"""The MAT variable holding the sample times, s."""

RATIO_VARIABLE = "Fnorm"
"""The MAT variable holding the spring's force over the normal load."""


def _column(path: Path, contents: dict[str, object], name: str) -> np.ndarray:
    """A MAT variable as a float vector, or an error naming it."""
    if name not in contents:
        found = sorted(key for key in contents if not key.startswith("__"))
        raise AcquisitionError(path, f"no variable {name!r} (the file has {found})",
                               column=name)
    values = np.asarray(contents[name])
    if values.ndim != 2 or min(values.shape) != 1 or not np.issubdtype(values.dtype, np.number):
        raise AcquisitionError(
            path, f"{name!r} must be a numeric vector, got shape {values.shape} of "
            f"{values.dtype}", column=name)
    return values.ravel().astype(float)


def read_slider_record(path: str | PathLike[str]) -> xr.Dataset:
    """Read a spring-slider record from a MAT file.

    Parameters
    ----------
    path
        The MAT (version 5) file, with the vectors ``t`` and ``Fnorm``.

    Returns
    -------
    xarray.Dataset
        ``friction_ratio`` over ``time`` (s, counted from the record's first sample), with
        the file's first time, its sampling rate and its name as attributes.

    Raises
    ------
    AcquisitionError
        When the file cannot be read, a variable is missing or not a vector, the two
        differ in length, a value is not finite (its sample is named), or the times do
        not increase at a constant step.
    """
    path = Path(path)
    try:
        contents = scipy.io.loadmat(path)
    # scipy reads MAT versions 4 to 7.2; a 7.3 file (HDF5) makes it raise
    # NotImplementedError, a file that is no MAT file MatReadError or ValueError
    except (OSError, ValueError, TypeError, NotImplementedError,
            scipy.io.matlab.MatReadError) as error:
        raise AcquisitionError(path, f"not a readable MAT file ({error})") from error
    time = _column(path, contents, TIME_VARIABLE)
    ratio = _column(path, contents, RATIO_VARIABLE)
    if time.size != ratio.size:
        raise AcquisitionError(
            path, f"{TIME_VARIABLE!r} has {time.size} samples and {RATIO_VARIABLE!r} "
            f"{ratio.size}")
    if time.size < 2:
        raise AcquisitionError(path, f"{time.size} sample(s): a record needs two at least")
    for name, values in ((TIME_VARIABLE, time), (RATIO_VARIABLE, ratio)):
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            raise AcquisitionError(path, f"sample {bad[0] + 1} (1-based) is {values[bad[0]]}",
                                   column=name)
    steps = np.diff(time)
    step = float(np.median(steps))
    uneven = np.flatnonzero(np.abs(steps - step) > 1e-3 * step)
    if step <= 0 or uneven.size:
        first = int(uneven[0]) if uneven.size else 0
        raise AcquisitionError(
            path, f"the times must increase at a constant step ({step:.6g} s); between "
            f"samples {first + 1} and {first + 2} (1-based) they go {time[first]:.9g} -> "
            f"{time[first + 1]:.9g}", column=TIME_VARIABLE)
    ds = xr.Dataset(
        {"friction_ratio": ("time", ratio, {
            "units": "1", "long_name": "the spring's force over the normal load"})},
        coords={"time": ("time", time - time[0], {
            "units": "s", "long_name": "time from the record's first sample", "axis": "T"})},
    )
    ds.attrs = {
        "Conventions": CONVENTIONS,
        "title": f"spring-slider record {path.stem}",
        "source": f"slipwave {__version__} read_slider_record, from {path.name}",
        "first_time_s": float(time[0]),
        "sample_rate_hz": 1.0 / step,
    }
    return ds
