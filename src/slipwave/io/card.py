"""Acquisition CSVs written as a card would write them (canonical or vendor flavour)."""

from __future__ import annotations

from os import PathLike
from pathlib import Path
from typing import Literal

import numpy as np
import pandas as pd
import xarray as xr

from slipwave.errors import SlipwaveError
from slipwave.io.atomic import atomic_output
from slipwave.io.channels import CHANNEL_ATTRS, CHANNELS, RESERVED_ATTRS

_VENDOR_HEADERS = {
    "time": "Temps (s)",
    "T": "Effort tangentiel (N)",
    "N": "Effort normal (N)",
    "DG": "Déplacement gauche (mm)",
    "DD": "Déplacement droit (mm)",
    "DT": "Déplacement plan (mm)",
}


def write_acquisition(
    ds: xr.Dataset,
    path: str | PathLike[str],
    *,
    flavour: Literal["canonical", "vendor"] = "canonical",
    float_format: str = "%.6g",
) -> Path:
    """Write a recording as an acquisition CSV that :func:`read_acquisition` reads.

    Parameters
    ----------
    ds
        Dimension ``time`` (s) and any of the channels ``T, N, DG, DD, DT``.
        Its simple global attributes become ``# key: value`` metadata lines.
    path
        Destination, written whole or not at all.
    flavour
        ``canonical``: comma separated, UTF-8, ``name [unit]`` headers, LF.
        ``vendor``: what a French acquisition card writes: ``;`` separator,
        decimal comma, Latin-1 headers ``Déplacement gauche (mm)``, CRLF and
        a trailing separator on every line.
    float_format
        printf format of the values.

    Returns
    -------
    Path
        The CSV written.

    """
    channels = [c for c in CHANNELS if c in ds.data_vars]
    frame = pd.DataFrame({"time": ds["time"].values, **{c: ds[c].values for c in channels}})
    skip = RESERVED_ATTRS | {"comment"}
    metadata = [
        f"# {key}: {value}"
        for key, value in ds.attrs.items()
        if key not in skip and isinstance(value, str | int | float | np.integer | np.floating)
        and "\n" not in str(value)
    ]
    if flavour == "canonical":
        frame.columns = ["time [s]", *(f"{c} [{CHANNEL_ATTRS[c]['units']}]" for c in channels)]
        body = frame.to_csv(index=False, float_format=float_format, lineterminator="\n")
        text, encoding = "\n".join([*metadata, body]), "utf-8"
    elif flavour == "vendor":
        frame.columns = [_VENDOR_HEADERS[c] for c in frame.columns]
        frame[""] = ""  # the trailing separator vendor cards write
        body = frame.to_csv(
            index=False, sep=";", decimal=",", float_format=float_format, lineterminator="\r\n"
        )
        text, encoding = "\r\n".join([*metadata, body]), "latin-1"
    else:
        raise SlipwaveError(f"unknown CSV flavour {flavour!r}: canonical or vendor")
    with atomic_output(path) as temporary:
        temporary.write_bytes(text.encode(encoding))
    return Path(path)
