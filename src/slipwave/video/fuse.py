"""Load events and video waves paired on the card's clock."""

from __future__ import annotations

import numpy as np
import pandas as pd

from slipwave.defaults import PAIRING_TOLERANCE_S
from slipwave.video.clock import ClockFit
from slipwave.video.waves import WAVE_COLUMNS


def fuse(events: pd.DataFrame, waves: pd.DataFrame, clock: ClockFit, *,
         tolerance: float = PAIRING_TOLERANCE_S) -> pd.DataFrame:
    """Each load event with its wave; waves without an event and events without one kept.

    Waves are put on the card's clock, then each event takes the nearest wave
    starting within ``tolerance`` (s) of its onset (each wave once). Columns
    ``wave_*`` describe the wave; ``video_kind`` is its kind from the swept
    extent (none for an ``unresolved`` wave) and ``kind_agrees`` compares it
    with the event's; ``source`` says
    ``both``, ``load`` (no wave seen) or ``video`` (a wave without a T drop).

    Parameters
    ----------
    events
        From :func:`~slipwave.events.detect_events`.
    waves
        From :func:`~slipwave.video.track_waves`.
    clock
        From :func:`~slipwave.video.align_clocks`.
    tolerance
        Largest gap between a wave's start and an event's onset, s.

    Returns
    -------
    pandas.DataFrame
        One row per event or lone wave, in time order.

    """
    starts = clock.acquisition_time(waves["t_start"].to_numpy(dtype=float))
    taken = np.zeros(len(waves), dtype=bool)
    chosen = np.full(len(events), -1)
    onsets = events["t_start"].to_numpy(dtype=float)
    for k in np.argsort(onsets):
        gap = np.abs(starts - onsets[k])
        gap[taken] = np.inf
        if gap.size and gap.min() <= tolerance:
            chosen[k] = int(np.argmin(gap))
            taken[chosen[k]] = True
    described = waves[list(WAVE_COLUMNS)].assign(
        t_start=starts, t_end=clock.acquisition_time(waves["t_end"].to_numpy(dtype=float)))
    columns = {f"wave_{c}": c for c in WAVE_COLUMNS}
    fused = events.reset_index(drop=True).copy()
    for name, column in columns.items():
        values = described[column].to_numpy()
        fused[name] = [values[i] if i >= 0 else None for i in chosen]
    fused["source"] = np.where(chosen >= 0, "both", "load")
    alone = described[~taken].rename(columns={c: name for name, c in columns.items()})
    alone = alone.assign(kind="none", t_start=alone["wave_t_start"], source="video")
    fused = pd.concat([fused, alone], ignore_index=True).sort_values("t_start",
                                                                      ignore_index=True)
    video_kind = fused["wave_kind"].map({"gross": "gross_slip", "partial": "partial_slip"})
    fused["video_kind"] = video_kind
    # no verdict where the video has no kind (no wave, or one too fast to follow)
    fused["kind_agrees"] = (fused["kind"] == video_kind).where(
        (fused["source"] == "both") & video_kind.notna())
    return fused
