"""Figures of recordings, drawn with matplotlib on the non-interactive backend."""

from __future__ import annotations

import io

import matplotlib

matplotlib.use("Agg")  # the workflow runs without a display

import matplotlib.pyplot as plt
import seaborn as sns
import xarray as xr
from matplotlib.figure import Figure

from slipwave.io import CHANNELS
from slipwave.signals import load_ratio


def plot_recording(recording: xr.Dataset) -> Figure:
    """The recorded channels and T/|N| against time, one panel each, time shared.

    Missing channels are left out. Axis labels carry the units.
    """
    panels = [c for c in CHANNELS if c in recording.data_vars]
    with sns.axes_style("whitegrid"):
        fig, axes = plt.subplots(
            len(panels) + 1, 1, sharex=True, figsize=(9.0, 1.6 * (len(panels) + 1) + 0.6),
            layout="constrained",
        )
    time = recording["time"].values
    colours = sns.color_palette("deep", len(panels) + 1)
    for ax, name, colour in zip(axes, panels, colours, strict=False):
        variable = recording[name]
        ax.plot(time, variable.values, lw=0.8, color=colour)
        ax.set_ylabel(f"{name} [{variable.attrs.get('units', '?')}]")
        ax.set_title(variable.attrs.get("long_name", name), fontsize=9, loc="left")
    ratio = load_ratio(recording)
    axes[-1].plot(time, ratio.values, lw=0.8, color=colours[-1])
    axes[-1].set_ylabel("T/|N| [-]")
    axes[-1].set_title(ratio.attrs["long_name"], fontsize=9, loc="left")
    axes[-1].set_xlabel("time [s]")
    fig.suptitle(str(recording.attrs.get("test_id", recording.attrs.get("source", ""))))
    return fig


def figure_png(fig: Figure, *, dpi: int = 110) -> bytes:
    """Render a figure to PNG bytes and close it."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=dpi)
    plt.close(fig)
    return buffer.getvalue()
