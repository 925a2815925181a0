"""A simple saw-tooth model of the bench's signals, for fixtures and demos.

This is not the virtual bench (no mechanics, no video): the tangential load
is a spring loaded by the flat's travel and relaxed by prescribed slips. It
reproduces the shape of the paper's figure 5 (normal loading, stick ramp,
gross slips with growing drops and DG/DD jumps, then partial slips) cheaply,
with the event times known.
"""

from __future__ import annotations

from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import Literal

import numpy as np
import pandas as pd
import xarray as xr

from slipwave.defaults import CONTACT_LENGTH_MM, CONVENTIONS, SLAB_HEIGHT_MM, SLAB_WIDTH_MM
from slipwave.io.card import write_acquisition
from slipwave.io.channels import CHANNEL_ATTRS


@dataclass(frozen=True)
class SawtoothBench:
    """Parameters of the saw-tooth model (mm, N, s).

    Attributes
    ----------
    normal_load
        Compressive normal load after step 1, recorded as ``-normal_load``.
    ratio
        T/|N| at which the interface slips.
    stiffness
        Tangential stiffness of slab and machine, N/mm of flat travel.
    gross_drops
        T drops of the first gross slips, growing as on the bench.
    partial_drop
        T drop of a partial slip; after the listed gross slips, partial and
        gross slips (of the last listed drop) alternate.

    """

    test_id: str = "demo"
    length: float = CONTACT_LENGTH_MM
    height: float = SLAB_HEIGHT_MM
    width: float = SLAB_WIDTH_MM
    speed: float = 0.048
    normal_load: float = 85.0
    ratio: float = 1.0
    stiffness: float = 20.0
    duration: float = 280.0
    loading_time: float = 20.0
    sample_rate: float = 100.0
    gross_drops: tuple[float, ...] = (5.0, 8.0, 11.0, 14.0)
    partial_drop: float = 2.5
    noise_load: float = 0.05
    noise_displacement: float = 0.002


def sawtooth_events(bench: SawtoothBench) -> pd.DataFrame:
    """Times, kinds and drops of the slips of a saw-tooth test.

    Returns
    -------
    pandas.DataFrame
        ``t_start`` (s), ``kind`` (``gross_slip`` or ``partial_slip``),
        ``drop`` (N).

    Parameters
    ----------
    bench
        The test's parameters.

    """
    rate = bench.stiffness * bench.speed  # N/s while the interface sticks
    threshold = bench.ratio * bench.normal_load
    t, load, rows = bench.loading_time, 0.0, []
    k = 0
    while True:
        if k < len(bench.gross_drops):
            kind, drop = "gross_slip", bench.gross_drops[k]
        else:
            partial = (k - len(bench.gross_drops)) % 2 == 0
            kind = "partial_slip" if partial else "gross_slip"
            drop = bench.partial_drop if partial else bench.gross_drops[-1]
        t += (threshold - load) / rate
        if t >= bench.duration - 1.0:
            break
        rows.append((t, kind, drop))
        load = threshold - drop
        k += 1
    return pd.DataFrame(rows, columns=["t_start", "kind", "drop"])


def sawtooth_recording(bench: SawtoothBench, *, seed: int = 0) -> xr.Dataset:
    """Signals of a saw-tooth test, as :func:`slipwave.io.read_acquisition` returns them.

    Parameters
    ----------
    bench
        The test's parameters.
    seed
        Noise seed.

    Returns
    -------
    xarray.Dataset
        time, T, N, DG, DD, DT with CF attributes.

    Examples
    --------
    >>> ds = sawtooth_recording(SawtoothBench(duration=120.0))
    >>> float(abs(ds["N"]).max()) > 80, ds.sizes["time"]
    (True, 12000)

    """
    rng = np.random.default_rng(seed)
    time = np.arange(0.0, bench.duration, 1.0 / bench.sample_rate)
    loading = np.clip(time / bench.loading_time, 0.0, 1.0)
    normal = bench.normal_load * loading**2 * (3 - 2 * loading)  # smooth approach
    travel = np.clip(time - bench.loading_time, 0.0, None) * bench.speed

    events = sawtooth_events(bench)
    # Each slip relaxes the spring over ~40 ms (a few samples), as a wave does.
    slip = np.zeros_like(time)
    left_jump = np.zeros_like(time)
    right_jump = np.zeros_like(time)
    for start, kind, drop in zip(
        events["t_start"].to_numpy(), events["kind"], events["drop"].to_numpy(), strict=True
    ):
        step = 1.0 - np.exp(-np.clip(time - start, 0.0, None) / 0.04)
        amount = drop / bench.stiffness
        slip += amount * step
        right_jump += amount * step
        if kind == "gross_slip":
            left_jump += amount * step
    tangential = bench.stiffness * (travel - slip)

    # Barrel: the faces bulge out with N; shear tilts both the same way.
    bulge = 0.06 * normal
    shear = 0.02 * tangential
    dg = -bulge + shear + left_jump
    dd = bulge + shear + right_jump
    dt = travel

    def noisy(values: np.ndarray, sigma: float) -> np.ndarray:
        return values + rng.normal(0.0, sigma, values.shape)

    signals = {
        "T": noisy(tangential, bench.noise_load),
        "N": noisy(-normal, bench.noise_load),  # the card records compression as negative
        "DG": noisy(dg, bench.noise_displacement),
        "DD": noisy(dd, bench.noise_displacement),
        "DT": noisy(dt, bench.noise_displacement),
    }
    attrs = {
        "test_id": bench.test_id,
        "sample_rate_hz": bench.sample_rate,
        "length_mm": bench.length,
        "height_mm": bench.height,
        "width_mm": bench.width,
        "speed_mm_s": bench.speed,
        "normal_load_n": bench.normal_load,
        "generator": f"slipwave.bench.sawtooth saw-tooth model, ratio {bench.ratio}, seed {seed}",
        "Conventions": CONVENTIONS,
    }
    return xr.Dataset(
        {name: ("time", values, CHANNEL_ATTRS[name]) for name, values in signals.items()},
        coords={"time": ("time", time, CHANNEL_ATTRS["time"])},
        attrs=attrs,
    )


SAWTOOTH_CAMPAIGN: tuple[tuple[SawtoothBench, Literal["canonical", "vendor"]], ...] = (
    (SawtoothBench(test_id="saw_hl050", height=40.0, ratio=1.0), "canonical"),
    (SawtoothBench(test_id="saw_hl025", height=20.0, ratio=0.9, stiffness=26.0,
                   gross_drops=(4.0, 6.0, 8.0), partial_drop=2.0), "canonical"),
    (SawtoothBench(test_id="saw_hl075", height=60.0, ratio=1.1, stiffness=16.0,
                   gross_drops=(6.0, 10.0, 14.0, 18.0), partial_drop=3.0), "vendor"),
)
"""Three saw-tooth tests (H/L 0.5, 0.25, 0.75) and the CSV flavour each is written in."""


def write_sawtooth_campaign(folder: str | PathLike[str], *, seed: int = 0) -> list[Path]:
    """Write the tests of :data:`SAWTOOTH_CAMPAIGN` as acquisition CSVs.

    Parameters
    ----------
    folder
        Where ``<test_id>.csv`` files go.
    seed
        Noise seed of the first test; test k uses ``seed + k``.

    Returns
    -------
    list of Path
        The CSVs written.

    """
    paths = []
    for k, (bench, flavour) in enumerate(SAWTOOTH_CAMPAIGN):
        path = Path(folder) / f"{bench.test_id}.csv"
        write_acquisition(sawtooth_recording(bench, seed=seed + k), path, flavour=flavour)
        paths.append(path)
    return paths
