"""Figures of recordings, simulations and videos.

Figures are :class:`matplotlib.figure.Figure` objects made without pyplot, so
importing this module selects no backend and drawing needs no display.
"""

from __future__ import annotations

import io
import multiprocessing
import signal
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np
import pandas as pd
import seaborn as sns
import xarray as xr
from matplotlib.axes import Axes
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure
from matplotlib.patches import Patch, Rectangle

from slipwave.errors import SlipwaveError
from slipwave.events.summary import PHASES, load_ratio
from slipwave.io import CHANNELS

PHASE_COLOURS = {"normal_loading": "#bbbbbb", "partial_slip": "#8fbc8f",
                 "gross_slip": "#e07b6a", "unclassified_slip": "#9fb4c7"}
KIND_MARKERS = {"gross_slip": ("v", "#b22222"), "partial_slip": ("v", "#2e8b57"),
                "unclassified": ("v", "#555555")}


def _phase_runs(phase: xr.DataArray) -> list[tuple[str, float, float]]:
    """(label, start, end) of each run of equal phases, stick left out."""
    codes = phase.values
    time = phase["time"].values
    change = np.flatnonzero(codes[1:] != codes[:-1]) + 1
    starts = np.concatenate([[0], change])
    ends = np.concatenate([change, [codes.size]]) - 1
    return [(PHASES[codes[a]], float(time[a]), float(time[b]))
            for a, b in zip(starts, ends, strict=True) if PHASES[codes[a]] != "stick"]


def _mark_events(axes: Iterable[Axes], t_axis: Axes | None, events: xr.Dataset, *,
                 alpha: float, suffix: str = "") -> set[str]:
    """Shade the phases on every axis and mark each slip's onset on T's; the phases shown."""
    runs = _phase_runs(events["phase"])
    for ax in axes:
        for label, start, end in runs:
            ax.axvspan(start, end, color=PHASE_COLOURS[label], alpha=alpha, lw=0)
    if t_axis is not None:
        kinds = events["kind"].values.astype(str)
        for kind, (marker, colour) in KIND_MARKERS.items():
            chosen = kinds == kind
            if chosen.any():
                t_axis.plot(events["t_start"].values[chosen], events["T_before"].values[chosen],
                            marker, color=colour, ms=4, label=kind.replace("_", " ") + suffix)
    return {label for label, _, _ in runs}


def plot_recording(recording: xr.Dataset, events: xr.Dataset | None = None) -> Figure:
    """The recorded channels and T/|N| against time, one panel each, time shared.

    Missing channels are left out. Axis labels carry the units. With
    ``events`` (from :func:`slipwave.events.events_dataset`) the phases are
    shaded on every panel and each slip's onset is marked on T.

    Parameters
    ----------
    recording
        From :func:`slipwave.io.read_acquisition`.
    events
        ``events.nc``, or ``None``.

    Returns
    -------
    matplotlib.figure.Figure
        One panel per channel and one for T/|N|.

    """
    panels = [c for c in CHANNELS if c in recording.data_vars]
    with_ratio = "N" in panels  # a force-only record has no T/|N|
    rows = len(panels) + with_ratio
    with sns.axes_style("whitegrid"):
        fig = Figure(figsize=(9.0, 1.6 * rows + 0.6), layout="constrained")
        axes = np.atleast_1d(fig.subplots(rows, 1, sharex=True))
    time = recording["time"].values
    colours = sns.color_palette("deep", len(panels) + 1)
    for ax, name, colour in zip(axes, panels, colours, strict=False):
        variable = recording[name]
        ax.plot(time, variable.values, lw=0.8, color=colour)
        ax.set_ylabel(f"{name} [{variable.attrs.get('units', '?')}]")
        ax.set_title(variable.attrs.get("long_name", name), fontsize=9, loc="left")
    if with_ratio:
        ratio = load_ratio(recording)
        axes[-1].plot(time, ratio.values, lw=0.8, color=colours[-1])
        axes[-1].set_ylabel("T/|N| [-]")
        axes[-1].set_title(ratio.attrs["long_name"], fontsize=9, loc="left")
    axes[-1].set_xlabel("time [s]")
    if events is not None:
        shown = _mark_events(axes, axes[panels.index("T")] if "T" in panels else None, events,
                             alpha=0.35)
        if "T" in panels:
            handles = [Patch(color=PHASE_COLOURS[k], alpha=0.35, label=k.replace("_", " "))
                       for k in PHASE_COLOURS if k in shown]
            axes[panels.index("T")].legend(
                handles=axes[panels.index("T")].get_legend_handles_labels()[0] + handles,
                fontsize=7, loc="upper left", ncol=2)
    fig.suptitle(str(recording.attrs.get("test_id", recording.attrs.get("source", ""))))
    return fig


def figure_png(fig: Figure, *, dpi: int = 110) -> bytes:
    """Render a figure to PNG bytes.

    Parameters
    ----------
    fig
        The figure.
    dpi
        Resolution, dots per inch.

    Returns
    -------
    bytes
        The PNG file's content.

    """
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=dpi)
    return buffer.getvalue()


_PENDING: tuple[Sequence[Figure], int] = ((), 110)
"""The figures :func:`figures_png` hands to its forked workers (they inherit it)."""


def _worker_start() -> None:
    # A forked worker inherits the command line's SIGTERM handler, which unwinds like
    # Ctrl-C; the pool stops its workers with SIGTERM, and a worker unwinding inside
    # the task queue's lock could leave it held, and the next worker and the report
    # waiting for ever. A worker simply dies on SIGTERM.
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


def _render_pending(index: int) -> bytes:
    figures, dpi = _PENDING
    return figure_png(figures[index], dpi=dpi)


def figures_png(figures: Sequence[Figure], *, workers: int = 1, dpi: int = 110) -> list[bytes]:
    r"""Render figures to PNG bytes, on several processes when asked.

    Drawing (layout, ticks, rasterising) is most of a report's time and each
    figure draws alone, so the figures are shared out over forked processes,
    which inherit them instead of receiving them pickled. Where processes
    cannot be forked (not POSIX), or with one worker, they are drawn in turn.

    Parameters
    ----------
    figures
        The figures, made (drawing happens here).
    workers
        Processes to draw on.
    dpi
        Resolution, dots per inch.

    Returns
    -------
    list of bytes
        Each figure's PNG, in the figures' order.

    Examples
    --------
    >>> fig = Figure(figsize=(2, 1))
    >>> _ = fig.add_subplot().plot([0, 1], [1, 0])
    >>> pngs = figures_png([fig, fig], workers=2)
    >>> all(png.startswith(b"\x89PNG") for png in pngs) and pngs[0] == pngs[1]
    True

    """
    workers = min(workers, len(figures))
    if workers <= 1 or "fork" not in multiprocessing.get_all_start_methods():
        return [figure_png(fig, dpi=dpi) for fig in figures]
    global _PENDING
    _PENDING = (figures, dpi)
    try:
        with multiprocessing.get_context("fork").Pool(workers, _worker_start) as pool:
            return pool.map(_render_pending, range(len(figures)), chunksize=1)
    finally:
        _PENDING = ((), dpi)


ZONE_COLOURS = {"open": "#f2f2f2", "stick": "#4c72b0", "slip": "#dd8452"}
CONDITION_COLOURS = {"open": "#f2f2f2", "stick": "#4c72b0", "slip (driven by T)": "#dd8452",
                     "slip (unloading, +x)": "#f3c9a6"}
"""Colours of the zone conditions of :mod:`slipwave.solver.zones`, slip split by direction."""


def plot_zones(simulation: xr.Dataset, *, vertical: str = "T") -> Figure:
    """Zone evolution as a space-time diagram: x across, load step (or T) upwards.

    Open, stick and slip zones are coloured per node and step, the picture to
    hold against a photoelastic kymograph. ``vertical`` is ``"T"`` (tangential
    load, N) or ``"step"``. Steps of the normal loading are drawn below T = 0
    when ``vertical="T"`` is not monotonic there, so the step axis is used then.

    Parameters
    ----------
    simulation
        From :func:`slipwave.solver.simulate`.
    vertical
        ``T``: the tangential load upwards; ``step``: the load step.

    Returns
    -------
    matplotlib.figure.Figure
        The space-time diagram with a legend of the zones.

    """
    state = simulation["state"].values
    x = simulation["x"].values
    edges_x = np.concatenate([[x[0]], 0.5 * (x[1:] + x[:-1]), [x[-1]]])
    values: np.ndarray | None
    if vertical == "T":
        T = simulation["T"].values
        tangential = simulation["phase"].values == "tangential"
        rows = np.flatnonzero(tangential)
        values = T[rows]
        label = "tangential load T [N]"
        if rows.size < 2 or np.any(np.diff(values) <= 0):
            rows, values, label = np.arange(state.shape[0]), None, "load step"
    elif vertical == "step":
        rows, values, label = np.arange(state.shape[0]), None, "load step"
    else:
        raise SlipwaveError(f"vertical must be 'T' or 'step', not {vertical!r}")
    if values is None:
        edges_y = np.arange(rows.size + 1) - 0.5
    else:
        middle = 0.5 * (values[1:] + values[:-1])
        edges_y = np.concatenate([[values[0] - (middle[0] - values[0])], middle,
                                  [values[-1] + (values[-1] - middle[-1])]])
    fig = Figure(figsize=(8.0, 5.0), layout="constrained")
    ax = fig.subplots()
    colours = ListedColormap(list(ZONE_COLOURS.values()))
    ax.pcolormesh(edges_x, edges_y, state[rows], cmap=colours, vmin=-0.5, vmax=2.5)
    ax.set_xlabel("x along the contact [mm]")
    ax.set_ylabel(label)
    ax.legend(handles=[Patch(color=c, label=k) for k, c in ZONE_COLOURS.items()],
              loc="upper left", bbox_to_anchor=(1.0, 1.0), frameon=False)
    attrs = simulation.attrs
    ax.set_title(f"H = {attrs.get('slab_height', '?')} mm, fs = {attrs.get('friction_fs', '?')}, "
                 f"fd = {attrs.get('friction_fd', '?')}", fontsize=10)
    return fig


def plot_kymograph(kymo: xr.Dataset, waves: pd.DataFrame | None = None, *,
                   window: tuple[float, float] | None = None) -> Figure:
    """The band's change along the contact against its time, tracked fronts on it.

    Each wave is drawn as its front's straight path (from ``x_start`` at
    ``t_start`` to ``x_end`` at ``t_end``) with its direction's colour; a
    change too fast to follow (``unresolved``) as a grey bar over the range it
    changed. ``window`` limits the time shown (s, camera time).

    Parameters
    ----------
    kymo
        From :func:`slipwave.video.kymograph`.
    waves
        From :func:`slipwave.video.track_waves`, drawn on it; ``None``: none.
    window
        (first, last) camera time shown, s; ``None``: all.

    Returns
    -------
    matplotlib.figure.Figure
        Position along the contact against camera time.

    """
    from slipwave.video.waves import change

    moved = change(kymo)
    if window is not None:
        moved = moved.sel(time=slice(*window))
    time, x = moved["time"].values, moved["x"].values
    fig = Figure(figsize=(9.0, 3.4), layout="constrained")
    ax = fig.subplots()
    ax.imshow(moved.values.T, aspect="auto", origin="lower", cmap="magma",
              extent=(time[0], time[-1], x[0], x[-1]), vmin=0.0,
              vmax=float(np.percentile(moved.values, 99.9)) or 1.0, interpolation="nearest")
    if waves is not None:
        for _, wave in waves.iterrows():
            if window is not None and not window[0] <= wave["t_start"] <= window[1]:
                continue
            if wave["direction"] == "unresolved":
                ax.plot([wave["t_start"]] * 2, [wave["x_min"], wave["x_max"]],
                        color=WAVE_COLOURS["unresolved"], lw=1.2)
            else:
                ax.plot([wave["t_start"], wave["t_end"]], [wave["x_start"], wave["x_end"]],
                        color=WAVE_COLOURS[wave["direction"]], lw=1.2)
        ax.legend(handles=[Patch(color=c, label=d.replace("_", " "))
                           for d, c in WAVE_COLOURS.items()], fontsize=7, loc="upper right")
    # the video's camera time, or a simulated film's test clock
    ax.set_xlabel(f"{kymo['time'].attrs.get('long_name', 'camera time')} [s]")
    ax.set_ylabel("x along the contact [mm]")
    ax.set_title("change of the band above the interface since the previous frame, and the "
                 "tracked fronts", fontsize=9, loc="left")
    return fig


_WAVES_SHOWN = 10  # the waves the fronts' figure shows: a run's hundreds fill it solid
WAVE_COLOURS = {"right_to_left": "#4fc3f7", "left_to_right": "#aed581",
                "unresolved": "#9e9e9e"}
"""A wave's colour by its direction, the video's and the simulation's alike."""


def plot_simulated_fronts(run: xr.Dataset, waves: pd.DataFrame) -> Figure:
    """A quasi-dynamic run's fronts: where the contact starts to slip, and its waves.

    Left, the first ten waves (a whole run's hundreds are a solid block): a tick where
    each node's slip rate passes the front speed, and each wave's path (from ``x_start``
    at ``t_start`` to ``x_end`` at ``t_end``) in its direction's colour. Right, the first
    wave in milliseconds: each node's arrival, the slope being the front's speed.

    Parameters
    ----------
    run
        From :func:`slipwave.simulate_waves.simulate_waves` (or
        :func:`slipwave.solver.quasi_dynamic.simulate_quasi_dynamic`).
    waves
        Its waves (:func:`slipwave.solver.fronts.front_waves`).

    Returns
    -------
    matplotlib.figure.Figure
        Position along the contact against time.
    """
    from slipwave.solver.fronts import slip_intervals

    intervals = slip_intervals(run)
    x = run["x"].values
    fig = Figure(figsize=(9.0, 3.4), layout="constrained")
    whole, first = fig.subplots(1, 2, width_ratios=(2.2, 1.0))
    whole.plot(intervals["start"], x[intervals["node"]], "|", color="#b71c1c", ms=2,
               alpha=0.5)
    for _, wave in waves.iterrows():
        whole.plot([wave["t_start"], wave["t_end"]], [wave["x_start"], wave["x_end"]],
                   color=WAVE_COLOURS[wave["direction"]], lw=1.2)
    shown = waves.iloc[:_WAVES_SHOWN]
    window = ((float(shown["t_start"].min()) - 0.5, float(shown["t_end"].max()) + 0.5)
              if len(shown) else (float(run["time"][0]), float(run["time"][-1])))
    whole.set(xlabel="time [s]", ylabel="x along the contact [mm]", xlim=window)
    whole.set_title(f"where the contact starts to slip, and the waves (the first "
                    f"{len(shown)} of {len(waves)})", fontsize=9, loc="left")
    if len(waves):
        wave = waves.iloc[0]
        inside = intervals[(intervals["start"] >= wave["t_start"] - 1e-9)
                           & (intervals["start"] <= wave["t_end"] + 1e-9)]
        arrivals = inside.groupby("node")["start"].min()
        first.plot(1e3 * (arrivals.to_numpy() - wave["t_start"]), x[arrivals.index.to_numpy()],
                   ".", color=WAVE_COLOURS[wave["direction"]], ms=3)
        first.set_title(f"the first wave: {wave['speed'] / 1e3:.2g} m/s", fontsize=9,
                        loc="left")
        first.set_xlabel(f"time after {wave['t_start']:.3f} s [ms]")
    else:
        first.text(0.5, 0.5, "no wave", ha="center", va="center", transform=first.transAxes)
    first.set_ylim(whole.get_ylim())
    whole.legend(handles=[Patch(color=c, label=d.replace("_", " "))
                          for d, c in WAVE_COLOURS.items() if d != "unresolved"],
                 fontsize=7, loc="upper right")
    return fig


def plot_frames(images: list[np.ndarray], times: list[float],
                labels: list[str] | None = None) -> Figure:
    """A row of frames with their times.

    Parameters
    ----------
    images
        The frames (grey, 8 or 16 bit).
    times
        Their camera times, s.
    labels
        What each frame shows, above its time; ``None``: the times alone.

    Returns
    -------
    matplotlib.figure.Figure
        The frames in a row, each titled with its time.

    """
    fig = Figure(figsize=(2.2 * len(images), 1.6 if labels is None else 1.9),
                 layout="constrained")
    axes = fig.subplots(1, len(images), squeeze=False)
    for k, (ax, image, time) in enumerate(zip(axes[0], images, times, strict=True)):
        ax.imshow(image, cmap="gray", vmin=0, vmax=np.iinfo(image.dtype).max)
        title = f"{time:.2f} s" if labels is None else f"{labels[k]}\n{time:.2f} s"
        ax.set_title(title, fontsize=8)
        ax.axis("off")
    return fig


def plot_zone_histories(cases: list[tuple[str, xr.Dataset]], *, columns: int = 4) -> Figure:
    """Zone space-time diagrams of several simulations, one panel each.

    Each node at each tangential step is open, sticking, slipping the way the flat
    drags it (towards -x relative to the flat: driven by T) or slipping outward at
    the right edge as T unloads it (+x); x across, T upwards, up to gross sliding.

    Parameters
    ----------
    cases
        (title, simulation) pairs.
    columns
        Panels per row.

    Returns
    -------
    matplotlib.figure.Figure
        The panels and one legend.

    """
    from slipwave.solver.zones import node_conditions

    if not cases:
        raise SlipwaveError("no simulation to draw")
    columns = min(columns, len(cases))
    rows = -(-len(cases) // columns)
    width, height = 2.1 * columns + 0.6, 2.3 * rows + 1.0
    fig = Figure(figsize=(width, height))
    # fixed margins (a constrained layout of many panels costs seconds)
    fig.subplots_adjust(left=0.6 / width, right=1 - 0.1 / width, bottom=0.55 / height,
                        top=1 - 0.6 / height, wspace=0.25, hspace=0.45)
    axes = np.atleast_1d(fig.subplots(rows, columns, squeeze=False)).ravel()
    colours = ListedColormap(list(CONDITION_COLOURS.values()))
    for ax, (title, ds) in zip(axes, cases, strict=False):
        tangential = np.flatnonzero(ds["phase"].values == "tangential")
        codes = node_conditions(ds["state"].values[tangential],
                                ds["slip_direction"].values[tangential])
        T = ds["T"].values[tangential]
        x = ds["x"].values
        half = 0.5 * float(x[1] - x[0])
        ax.imshow(codes, cmap=colours, vmin=-0.5, vmax=3.5, origin="lower", aspect="auto",
                  interpolation="nearest",
                  extent=(float(x[0]) - half, float(x[-1]) + half, -0.5, T.size - 0.5))
        ticks = np.linspace(0, T.size - 1, min(4, T.size)).round().astype(int)
        ax.set_yticks(ticks, [f"{T[k]:.0f}" for k in ticks])
        ax.set_title(title, fontsize=8)
        ax.tick_params(labelsize=7)
    for ax in axes[len(cases):]:
        ax.set_visible(False)
    fig.supxlabel("x along the contact [mm] (flat moving towards +x)", fontsize=9, y=0.05 / height)
    fig.supylabel("tangential load T [N]", fontsize=9, x=0.05 / width)
    fig.legend(handles=[Patch(color=c, label=k, ec="#999999") for k, c in
                        CONDITION_COLOURS.items()],
               loc="upper center", ncols=4, frameon=False, fontsize=8)
    return fig


def plot_map(whole: xr.Dataset, tests: pd.DataFrame | None = None, *,
             label: str = "campaign tests (T/N at gross slips)") -> Figure:
    """The behaviour map (the paper's figure 2): f upwards, H/L across.

    Each case is coloured by its behaviour (legend in words below the map), the
    regions named ZD and ZG are labelled on the map, and the cases whose first
    opening is at the right edge (the paper's L) are outlined by a dashed line; the
    cases of the map's band (``mesh_band``: where its succession still moves with the
    mesh) are hatched.
    With ``tests`` (:func:`slipwave.map.place_tests`), each test is a point at its
    H/L and measured T/N at gross slips, with its confidence interval.

    Parameters
    ----------
    whole
        From :func:`slipwave.map.assemble_map`.
    tests
        The campaign's tests, or ``None``.
    label
        The tests' legend entry (what their f is).

    Returns
    -------
    matplotlib.figure.Figure
        The map and its legend.

    """
    import textwrap

    hl = whole["height_ratio"].values
    f = whole["friction"].values
    grid = whole["behaviour"].values
    ids = whole["behaviour_id"].values
    names = [str(n) for n in whole["behaviour_name"].values]
    # One hue per family, shades within it: ZD blues, ZG oranges, the others greens.
    families = {"ZD": "Blues", "ZG": "Oranges", "": "Greens"}
    members = {family: [n for n in names if _family(n) == family] for family in families}
    shades = {family: sns.color_palette(families[family], max(3, len(group)) + 2)[::-1]
              for family, group in members.items()}
    colours = ListedColormap([shades[_family(n)][1 + members[_family(n)].index(n)]
                              for n in names])

    def edges(values: np.ndarray) -> np.ndarray:
        if values.size == 1:
            return np.array([values[0] - 0.05, values[0] + 0.05])
        middle = 0.5 * (values[1:] + values[:-1])
        return np.concatenate([[values[0] - (middle[0] - values[0])], middle,
                               [values[-1] + (values[-1] - middle[-1])]])

    legend_lines = [textwrap.fill(f"{name}: {sequence}", 110, subsequent_indent="      ")
                    for name, sequence in zip(names, whole["behaviours"].values, strict=True)]
    legend_rows = sum(line.count("\n") + 1 for line in legend_lines)
    legend_height = 0.16 * legend_rows + 0.6
    height = 6.2 + legend_height
    fig = Figure(figsize=(8.0, height))
    # fixed places: the map above, its legend in words below
    ax = fig.add_axes((0.09, (legend_height + 0.75) / height, 0.88, 5.0 / height))
    legend_ax = fig.add_axes((0.02, 0.1 / height, 0.96, legend_height / height))
    ax.pcolormesh(edges(hl), edges(f), grid.T, cmap=colours, vmin=ids[0] - 0.5,
                  vmax=ids[-1] + 0.5)
    # The paper's L: first opening at the right edge (dashed outline of those cases).
    if np.unique(whole["L"].values).size > 1:
        ax.contour(hl, f, whole["L"].values.T.astype(float), levels=[0.5], colors="black",
                   linestyles="dashed", linewidths=1.0)
    handles: list[Any] = []
    if "mesh_band" in whole:
        _hatch_band(ax, whole["mesh_band"].values, edges(hl), edges(f))
        handles.append(Patch(fill=False, hatch="////", edgecolor="0.25", lw=0,
                             label=f"still moves with the mesh "
                             f"({whole.attrs['band_elements']} -> "
                             f"{whole.attrs['contact_elements']} elements)"))
    for family in ("ZD", "ZG"):
        mask = np.isin(grid, ids[[n.startswith(family) for n in names]])
        if mask.any():
            i, j = np.nonzero(mask)
            k = int(np.argmin(np.hypot(i - i.mean(), (j - j.mean()) / 10)))
            ax.text(hl[i[k]], f[j[k]], family, ha="center", va="center", fontsize=12,
                    fontweight="bold", color="black",
                    bbox={"boxstyle": "round", "fc": "white", "alpha": 0.7, "lw": 0})
    if tests is not None and len(tests):
        handles.append(ax.errorbar(
            tests["height_ratio"], tests["ratio"],
            yerr=[tests["ratio"] - tests["ci_low"], tests["ci_high"] - tests["ratio"]],
            fmt="o", color="black", mfc="white", ms=6, capsize=3, label=label))
        for _, test in tests.iterrows():
            ax.annotate(str(test["test_id"]), (test["height_ratio"], test["ratio"]),
                        xytext=(6, 4), textcoords="offset points", fontsize=8)
    if handles:
        ax.legend(handles=handles, loc="upper right", fontsize=8)
    ax.set_xlabel("slab height over contact length H/L")
    ax.set_ylabel("friction coefficient f")
    control = ("N held" if whole.attrs.get("normal_control") == "force"
               else "normal displacement held")
    ax.set_title(f"Interface behaviour, {grid.size} cases at {whole.attrs['contact_elements']} "
                 f"elements ({control}; dashed: first opening at the right edge, L)",
                 fontsize=10)
    legend_ax.set_axis_off()
    y = 1.0
    step = 1.0 / max(1, legend_rows)
    for k, line in enumerate(legend_lines):
        legend_ax.add_patch(Rectangle((0.0, y - step * 0.85), 0.02, step * 0.75,
                                      transform=legend_ax.transAxes, color=colours(k)))
        legend_ax.text(0.03, y, line, transform=legend_ax.transAxes, fontsize=6.5, va="top",
                       family="monospace")
        y -= step * (line.count("\n") + 1)
    return fig



def _hatch_band(ax: Axes, band: np.ndarray, hl_edges: np.ndarray, f_edges: np.ndarray) -> None:
    """Hatch the cases of the map's band, one rectangle per run along f at each H/L."""
    for i, column in enumerate(band.astype(bool)):
        padded = np.concatenate([[False], column, [False]])
        starts = np.flatnonzero(~padded[:-1] & padded[1:])
        stops = np.flatnonzero(padded[:-1] & ~padded[1:])
        for start, stop in zip(starts, stops, strict=True):
            ax.add_patch(Rectangle((hl_edges[i], f_edges[start]), hl_edges[i + 1] - hl_edges[i],
                                   f_edges[stop] - f_edges[start], fill=False, hatch="////",
                                   edgecolor="0.25", lw=0))


def _family(name: str) -> str:
    return name[:2] if name.startswith(("ZD", "ZG")) else ""


def plot_fits(table: pd.DataFrame) -> Figure:
    """The campaign's fitted coefficients against H/L, with their 95 % intervals.

    Parameters
    ----------
    table
        From :func:`slipwave.fits.fits_table`.

    Returns
    -------
    matplotlib.figure.Figure
        fs and fd of each test's chosen law against H/L, labelled by test.

    """
    figure = Figure(figsize=(6.4, 4.0), layout="constrained")
    axes = figure.subplots()
    for name, colour, label in (("fs", "#b2182b", "static fs"), ("fd", "#2166ac", "dynamic fd")):
        low = table[name] - table[f"{name}_low"]
        high = table[f"{name}_high"] - table[name]
        axes.errorbar(table["height_ratio"], table[name], yerr=[low, high], fmt="o",
                      color=colour, capsize=3, label=label)
    for _, row in table.iterrows():
        axes.annotate(f"{row['test_id']} ({row['law']})", (row["height_ratio"], row["fs"]),
                      textcoords="offset points", xytext=(5, 5), fontsize=8)
    axes.set_xlabel("H/L")
    axes.set_ylabel("fitted coefficient (1)")
    axes.set_title("Fitted friction (chosen law; 95 % intervals)")
    axes.legend()
    axes.grid(alpha=0.3)
    return figure


MEASURED_STYLE = {"lw": 0.8}
SIMULATED_STYLE = {"lw": 1.0, "color": "#222222", "ls": "--"}
"""How measured (coloured, solid) and simulated (black, dashed) curves are told apart in
every comparison figure."""


def _along_x(recording: xr.Dataset, events: xr.Dataset | None) -> xr.Dataset:
    """DG along +x (the left sensor turned when it reads its edge's outward motion)."""
    if events is not None and str(events.attrs.get("edge_convention")) == "outward" and (
            "DG" in recording):
        recording = recording.assign(DG=-recording["DG"])
        recording["DG"].attrs["long_name"] = "left edge displacement, along +x"
    return recording


def plot_pairing(recording: xr.Dataset, simulated: xr.Dataset, events: xr.Dataset | None = None,
                 simulated_events: pd.DataFrame | None = None) -> Figure:
    """Measured and simulated T, N, DG, DD and T/|N| on shared time axes.

    Measured in colour, simulated dashed black; the measured phases shaded (partial
    slips green, gross slips red, normal loading grey) and every slip's onset marked on
    T, measured (filled) and simulated (hollow). DG is drawn along +x.

    Parameters
    ----------
    recording
        The measured recording.
    simulated
        The simulated recording (:func:`slipwave.simulate.replay_test`).
    events
        The measured ``events.nc``, or ``None``.
    simulated_events
        The simulated recording's events, or ``None``.

    Returns
    -------
    matplotlib.figure.Figure
        One panel per channel present in both, and T/|N|.

    """
    recording = _along_x(recording, events)
    panels = [c for c in ("T", "N", "DG", "DD") if c in recording and c in simulated]
    rows = len(panels) + ("N" in panels)
    with sns.axes_style("whitegrid"):
        fig = Figure(figsize=(9.0, 1.55 * rows + 0.8), layout="constrained")
        axes = np.atleast_1d(fig.subplots(rows, 1, sharex=True))
    colours = dict(zip(panels, sns.color_palette("deep", 5), strict=False))
    series = [(name, recording[name], simulated[name]) for name in panels]
    if "N" in panels:
        series.append(("T/|N|", load_ratio(recording), load_ratio(simulated)))
        colours["T/|N|"] = sns.color_palette("deep", 5)[4]
    for ax, (name, measured, model) in zip(axes, series, strict=True):
        ax.plot(measured["time"], measured.values, color=colours[name], label="measured",
                **MEASURED_STYLE)
        ax.plot(model["time"], model.values, label="simulated", **SIMULATED_STYLE)
        unit = measured.attrs.get("units", "1") if name != "T/|N|" else "-"
        ax.set_ylabel(f"{name} [{unit}]")
    if events is not None:
        _mark_events(axes, axes[0] if "T" in panels else None, events, alpha=0.3,
                     suffix=" (measured)")
    if simulated_events is not None and len(simulated_events) and "T" in panels:
        for kind, (marker, colour) in KIND_MARKERS.items():
            chosen = simulated_events[simulated_events["kind"] == kind]
            if len(chosen):
                axes[0].plot(chosen["t_start"], chosen["T_before"], marker, mfc="none",
                             color=colour, ms=6, label=f"{kind.replace('_', ' ')} (simulated)")
    axes[0].legend(fontsize=7, loc="lower left", bbox_to_anchor=(0.0, 1.02), ncol=6,
                   frameon=False)
    axes[-1].set_xlabel("time [s]")
    return fig


def plot_gross_zooms(recording: xr.Dataset, simulated: xr.Dataset, events: xr.Dataset,
                     simulated_events: pd.DataFrame | None, *, count: int = 3,
                     before: float = 3.0, after: float = 3.0) -> Figure | None:
    """The first gross slips up close: T, DG and DD around each onset, measured and simulated.

    Each column is one of the first ``count`` measured gross slips; the simulated
    gross slip of the same rank is drawn on the same axes, shifted to the measured
    onset (its own time difference is in the title). Time runs from the onset.

    Parameters
    ----------
    recording, simulated, events, simulated_events
        As in :func:`plot_pairing`.
    count
        Gross slips shown.
    before, after
        Seconds shown before and after each onset.

    Returns
    -------
    matplotlib.figure.Figure or None
        ``None`` without a measured gross slip.

    """
    recording = _along_x(recording, events)
    kinds = events["kind"].values.astype(str)
    onsets = events["t_start"].values[kinds == "gross_slip"][:count]
    if not onsets.size:
        return None
    model_onsets = np.array([])
    if simulated_events is not None and len(simulated_events):
        model_onsets = simulated_events.loc[simulated_events["kind"] == "gross_slip",
                                            "t_start"].to_numpy()
    panels = [c for c in ("T", "DG", "DD") if c in recording]
    with sns.axes_style("whitegrid"):
        fig = Figure(figsize=(9.0, 1.5 * len(panels) + 0.9), layout="constrained")
        axes = fig.subplots(len(panels), onsets.size, sharex=True, squeeze=False)
    colours = dict(zip(("T", "N", "DG", "DD"), sns.color_palette("deep", 4), strict=True))
    for column, onset in enumerate(onsets):
        shift = model_onsets[column] - onset if column < model_onsets.size else np.nan
        for row, name in enumerate(panels):
            ax = axes[row, column]
            window = recording[name].sel(time=slice(onset - before, onset + after))
            ax.plot(window["time"] - onset, window.values, color=colours[name],
                    label="measured", **MEASURED_STYLE)
            if np.isfinite(shift) and name in simulated:
                model = simulated[name].sel(time=slice(onset + shift - before,
                                                       onset + shift + after))
                # the same level before the slip: sensor offsets and drift are not modelled
                level = float(window.sel(time=slice(None, onset)).mean()) - float(
                    model.sel(time=slice(None, onset + shift)).mean())
                ax.plot(model["time"] - onset - shift, model.values + level,
                        label="simulated", **SIMULATED_STYLE)
            ax.axvline(0.0, color=KIND_MARKERS["gross_slip"][1], lw=0.6)
            if column == 0:
                ax.set_ylabel(f"{name} [{recording[name].attrs.get('units', '?')}]")
            if row == 0:
                title = f"gross slip {column + 1}, {onset:.1f} s"
                if np.isfinite(shift):
                    title += f"\n(simulated {shift:+.1f} s)"
                ax.set_title(title, fontsize=8)
        axes[-1, column].set_xlabel("time from the onset [s]")
    axes[0, 0].legend(fontsize=7, loc="lower left")
    fig.suptitle("First gross slips (DG, DD along +x; simulated levelled to the measured "
                 "before the slip)", fontsize=9)
    return fig


def plot_space_time(contact: xr.Dataset | None, kymo: xr.Dataset | None = None,
                    card_time: tuple[float, float] = (0.0, 1.0),
                    window: tuple[float, float] | None = None) -> Figure:
    """The video's kymograph, the simulated zones and the simulated kymograph, one time axis.

    Parameters
    ----------
    contact
        The simulated contact history (``state``, ``intensity``), or ``None``.
    kymo
        The video's kymograph, or ``None``.
    card_time
        (offset, rate) turning the camera's time into the card's (``clock.json``).
    window
        (first, last) card time shown, s; ``None``: all.

    Returns
    -------
    matplotlib.figure.Figure
        Up to three panels: x along the contact upwards, card time across.

    """
    panels = []
    if kymo is not None:
        panels.append("video")
    if contact is not None:
        panels.append("zones")
        if "intensity" in contact:
            panels.append("simulated")
    if not panels:
        raise SlipwaveError("no kymograph and no simulation to draw")
    fig = Figure(figsize=(9.0, 1.9 * len(panels) + 0.7), layout="constrained")
    axes = np.atleast_1d(fig.subplots(len(panels), 1, sharex=True))
    for ax, panel in zip(axes, panels, strict=True):
        if panel == "video":
            assert kymo is not None
            time = card_time[0] + card_time[1] * kymo["time"].values
            values = kymo["intensity"].values
            x = kymo["x"].values
            ax.set_title("video: intensity of the band above the interface", fontsize=9,
                         loc="left")
            ax.imshow(values.T, aspect="auto", origin="lower", cmap="gray",
                      extent=(time[0], time[-1], x[0], x[-1]), interpolation="nearest")
        elif panel == "zones":
            assert contact is not None
            time, x = contact["time"].values, contact["x"].values
            colours = ListedColormap(list(ZONE_COLOURS.values()))
            ax.pcolormesh(np.concatenate([[0.0], time]), _edges(x),
                          contact["state"].values[:, :].T, cmap=colours, vmin=-0.5, vmax=2.5)
            ax.set_title("simulation: zone state of the contact", fontsize=9, loc="left")
            ax.legend(handles=[Patch(color=c, label=k, ec="#999999")
                               for k, c in ZONE_COLOURS.items()], fontsize=7,
                      loc="upper right", ncols=3)
        else:
            assert contact is not None
            time, x = contact["time"].values, contact["x_image"].values
            ax.pcolormesh(np.concatenate([[0.0], time]), _edges(x),
                          contact["intensity"].values.T, cmap="gray", vmin=0, vmax=255)
            ax.set_title("simulation: intensity of the same band (camera model)", fontsize=9,
                         loc="left")
        ax.set_ylabel("x [mm]")
    if window is not None:
        axes[-1].set_xlim(*window)
    axes[-1].set_xlabel("time (card) [s]")
    return fig


def _edges(centres: np.ndarray) -> np.ndarray:
    middle = 0.5 * (centres[1:] + centres[:-1])
    return np.concatenate([[2 * centres[0] - middle[0]], middle,
                           [2 * centres[-1] - middle[-1]]])


def plot_gross_ratios(events: pd.DataFrame, simulated_events: pd.DataFrame | None) -> Figure:
    """T/|N| before and after each gross slip, measured and simulated, by rank.

    Parameters
    ----------
    events
        The measured events table.
    simulated_events
        The simulated recording's events, or ``None``.

    Returns
    -------
    matplotlib.figure.Figure
        T/|N| against the gross slip's rank.

    """
    with sns.axes_style("whitegrid"):
        fig = Figure(figsize=(6.4, 3.0), layout="constrained")
        ax = fig.subplots()
    colour = KIND_MARKERS["gross_slip"][1]
    for table, filled, label in ((events, True, "measured"),
                                 (simulated_events, False, "simulated")):
        if table is None or not len(table):
            continue
        gross = table[table["kind"] == "gross_slip"]
        rank = np.arange(1, len(gross) + 1)
        face = colour if filled else "none"
        ax.plot(rank, gross["ratio_before"], "o", color=colour, mfc=face,
                label=f"before (static), {label}")
        ax.plot(rank, gross["ratio_after"], "s", color="#2166ac", mfc=face if not filled
                else "#2166ac", label=f"after (dynamic), {label}")
    ax.set_xlabel("gross slip (rank)")
    ax.set_ylabel("T/|N| [-]")
    ax.legend(fontsize=7, ncols=2)
    return fig


def plot_campaign(summary: pd.DataFrame, fits: pd.DataFrame) -> Figure:
    """Measured T/|N| and fitted coefficients against H/L, one point per test.

    Left, T/|N| at gross slips: before (static, mean with its 95 % interval) and after
    (dynamic). Right, the chosen law's fs and fd with their 95 % intervals.

    Parameters
    ----------
    summary
        ``results/summary.csv``.
    fits
        ``results/fits.csv`` (:func:`slipwave.fits.fits_table`).

    Returns
    -------
    matplotlib.figure.Figure
        Two panels sharing H/L.

    """
    table = fits.merge(summary, on="test_id", how="left")
    with sns.axes_style("whitegrid"):
        fig = Figure(figsize=(9.0, 3.6), layout="constrained")
        measured, fitted = fig.subplots(1, 2, sharex=True)
    static, dynamic = KIND_MARKERS["gross_slip"][1], "#2166ac"
    measured.errorbar(table["height_ratio"], table["static_ratio_mean"],
                      yerr=[table["static_ratio_mean"] - table["static_ratio_ci_low"],
                            table["static_ratio_ci_high"] - table["static_ratio_mean"]],
                      fmt="o", color=static, capsize=3, label="before (static)")
    measured.plot(table["height_ratio"], table["dynamic_ratio_mean"], "s", color=dynamic,
                  label="after (dynamic)")
    measured.set_title("measured T/|N| at gross slips", fontsize=9, loc="left")
    measured.set_ylabel("T/|N| [-]")
    for name, colour, label in (("fs", static, "fs"), ("fd", dynamic, "fd")):
        fitted.errorbar(table["height_ratio"], table[name],
                        yerr=[table[name] - table[f"{name}_low"],
                              table[f"{name}_high"] - table[name]],
                        fmt="o" if name == "fs" else "s", color=colour, capsize=3, label=label)
    for _, row in table.iterrows():
        fitted.annotate(f"{row['test_id']} ({row['law']})", (row["height_ratio"], row["fs"]),
                        textcoords="offset points", xytext=(4, 4), fontsize=7)
        measured.annotate(str(row["test_id"]), (row["height_ratio"], row["static_ratio_mean"]),
                          textcoords="offset points", xytext=(4, 4), fontsize=7)
    fitted.set_title("fitted coefficients (chosen law, 95 % intervals)", fontsize=9, loc="left")
    fitted.set_ylabel("coefficient [-]")
    for ax in (measured, fitted):
        ax.set_xlabel("H/L [-]")
        ax.legend(fontsize=7)
    return fig
